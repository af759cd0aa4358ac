"""Error of the FFT effective permittivity against resolution, for the three Green operators.

Two exact references: Hashin's coated sphere (core −50 + 20i, shell 2.25, core fraction 0.3,
embedded in its Hashin value 5.679356409 + 0.251835364i) and the 2-D checkerboard (1 and
−2 + 0.5i: sqrt(ε1 ε2)). Also the linear (Richardson) extrapolation over the two finest grids.

Run: ``python examples/homogenize_convergence.py [output_dir]``.
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from nmmm.homogenize import fft_permittivity, richardson  # noqa: E402
from nmmm.homogenize import geometries as G  # noqa: E402

OPS = ("continuous", "willot2014", "willot2015")


def main(out_dir="out/homogenize"):
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    ec, es, phi = -50 + 20j, 2.25, 0.3
    beta = (ec - es) / (ec + 2 * es)
    hashin = es * (1 + 2 * phi * beta) / (1 - phi * beta)
    sizes3 = (16, 24, 32, 40)
    cb = np.sqrt(1 * (-2 + 0.5j))
    sizes2 = (16, 32, 64, 128)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for op in OPS:
        vals = [fft_permittivity(G.coated_sphere(n, 0.4, phi), {0: ec, 1: es, 2: hashin}, green=op,
                                 directions=[0], dtype="complex64").tensor[0, 0] for n in sizes3]
        err = np.abs(np.array(vals) / hashin - 1)
        ext = richardson(vals[-2:], [1 / sizes3[-2], 1 / sizes3[-1]])
        axes[0].loglog(sizes3, err, "o-", label=f"{op} (extrapolated: {abs(ext / hashin - 1):.2%})")
        print(f"coated sphere {op:11s} rel. errors {np.round(err, 4).tolist()}  extrapolated {abs(ext / hashin - 1):.4f}")
        vals = [fft_permittivity(G.checkerboard(n), {0: 1.0, 1: -2 + 0.5j}, green=op, directions=[0]).tensor[0, 0]
                for n in sizes2]
        err = np.abs(np.array(vals) - cb) / abs(cb)
        axes[1].loglog(sizes2, err, "o-", label=op)
        print(f"checkerboard  {op:11s} rel. errors {np.round(err, 5).tolist()}")
    for ax, title in zip(axes, ("Hashin coated sphere (metal core)", "2-D checkerboard, 1 | −2+0.5i")):
        ax.set(xlabel="voxels per cell edge", ylabel="relative error", title=title)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "homogenize_convergence.png", dpi=120)
    print("wrote", out / "homogenize_convergence.png")


if __name__ == "__main__":
    main(*sys.argv[1:])
