"""Aluminium flakes lying flat in a resin: an anisotropic effective medium.

A small periodic flake deposit (nmmm.microstructure.flake_deposit, scaled down so that it fits
a 64 × 64 × 32 grid) is homogenized with Rakić's aluminium and a constant resin (n = 1.5).
The result is a uniaxial Material: ``ordinary`` (in the plane of the flakes, metal-like) and
``extraordinary`` (across them, dielectric-like) — what the layers and appearance packages use.

Run: ``python examples/homogenize_flakes.py [output_dir]``.
"""

import sys
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from nmmm.homogenize import homogenize  # noqa: E402
from nmmm.materials import get  # noqa: E402
from nmmm.materials.models import Constant  # noqa: E402
from nmmm.microstructure import flake_deposit  # noqa: E402


def main(out_dir="out/homogenize"):
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    dep = flake_deposit(box_nm=(6400.0, 6400.0, 1600.0), diameter_nm=("lognormal", 2500.0, 600.0),
                        thickness_nm=100.0, fraction=0.10, tilt_std_deg=5.0, exclusion_nm=50.0, seed=3)
    ms = dep.rasterize(shape=(64, 64, 32))
    print(ms, "flake fraction", round(ms.volume_fraction(1), 3))
    w = np.arange(400.0, 701.0, 50.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the flakes are not small against λ: quasi-static limit
        mat = homogenize(ms, {0: Constant(nk=1.5), 1: get("main/Al/Rakic")}, wavelength_nm=w,
                         dtype="complex64", tol=1e-5)
    o, e = mat.ordinary.eps(w), mat.extraordinary.eps(w)
    print("projections per loading:", np.asarray(mat.result.iterations).tolist())
    for wl, a, b in zip(w, o, e):
        print(f"{wl:5.0f} nm  in-plane eps {a:.3f}   normal eps {b:.3f}")
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    ax[0].imshow(ms.labels[:, 32, :].T, origin="lower", cmap="gray_r", aspect="auto")
    ax[0].set(title="flakes: x-z section", xlabel="x (voxel)", ylabel="z (voxel)")
    ax[1].plot(w, o.real, "o-", label="Re ε ordinary (in plane)")
    ax[1].plot(w, o.imag, "o--", label="Im ε ordinary")
    ax[1].plot(w, e.real, "s-", label="Re ε extraordinary (normal)")
    ax[1].plot(w, e.imag, "s--", label="Im ε extraordinary")
    ax[1].set(xlabel="wavelength (nm)", title="effective permittivity of the flake layer")
    ax[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "homogenize_flakes.png", dpi=120)
    print("wrote", out / "homogenize_flakes.png")


if __name__ == "__main__":
    main(*sys.argv[1:])
