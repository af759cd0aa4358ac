"""nmmm's plate renderer beside Mitsuba 3 (issue 19 item 5): the shipped hematite and grey
metallic recipes (statistical flakes, no glints) on a 15 cm x 10 cm plate under a point lamp and a
uniform D65 sky, rendered by both; a figure of the two images side by side with the deviation of
each of 3 x 3 regions, and the table of region means.

    python examples/mitsuba_crosscheck.py [OUTDIR]

Needs Mitsuba 3 (pip install 'nmmm[mitsuba]') and a libLLVM >= 17 (apt-get install libllvm19);
without them it says so in one line and exits 0 (nothing to compare).
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from nmmm.appearance.render import PointLight, UniformEnvironment  # noqa: E402
from nmmm.appearance.render.mitsuba_paint import MitsubaUnavailableError, require_mitsuba  # noqa: E402

try:
    require_mitsuba("llvm_ad_spectral")
except MitsubaUnavailableError as exc:
    print(f"mitsuba_crosscheck: nothing to compare: {exc}")
    sys.exit(0)

from nmmm.appearance.render.mitsuba_crosscheck import crosscheck_plate  # noqa: E402
from nmmm.recipes.render_cli import plate_from_recipe_file  # noqa: E402

out = Path(sys.argv[1] if len(sys.argv) > 1 else "crosscheck_out")
out.mkdir(parents=True, exist_ok=True)
recipes = Path(__file__).resolve().parents[1] / "src" / "nmmm" / "recipes" / "examples"
w = np.arange(400.0, 701.0, 20.0)
lamp = PointLight((0.0, 150.0, 300.0), "D65", 1.0)
sky = UniformEnvironment("D65", 0.1)
fig, axes = plt.subplots(2, 3, figsize=(13, 5.6))
for row, name in enumerate(("hematite_paint.toml", "grey_metallic.toml")):
    plate, _ = plate_from_recipe_file(recipes / name)
    cc = crosscheck_plate(plate.brdf, [lamp], sky, position_mm=(0.0, -250.0, 300.0), fov_deg=35,
                          resolution=(180, 120), spp=256, wavelength_nm=w, grid=(3, 3))
    print(f"{name}: {cc!r}\n{cc.table()}")
    # the same exposure for both renders: the plate's 99th-percentile radiance at 0.9 of display white (the
    # metallic's flake highlight is ~6x the white diffuser's radiance: exposure 1 showed a white blob)
    top = np.percentile(cc.nmmm.radiance[cc.nmmm.on_plate].mean(axis=1), 99)
    expo = float(min(0.9 * cc.nmmm.white_radiance.mean() / max(top, 1e-9), 4.0))
    for col, (img, title) in enumerate(((cc.nmmm, "nmmm render_plate"), (cc.mitsuba, "Mitsuba 3 path + nmmm_paint"))):
        axes[row, col].imshow(img.to_srgb(expo))
        axes[row, col].set_title(f"{plate.brdf.name}: {title}", fontsize=9)
        axes[row, col].axis("off")
    im = axes[row, 2].imshow(100 * cc.deviation, cmap="RdBu_r", vmin=-2, vmax=2)
    for (i, j), v in np.ndenumerate(cc.deviation):
        axes[row, 2].text(j, i, f"{100 * v:+.2f} %\n±{100 * cc.standard_error[i, j]:.2f}", ha="center",
                          va="center", fontsize=8)
    axes[row, 2].set_title("Mitsuba / nmmm − 1 per region (± s.e.)", fontsize=9)
    axes[row, 2].set_xticks([])
    axes[row, 2].set_yticks([])
    fig.colorbar(im, ax=axes[row, 2], label="%")
fig.suptitle("Point lamp (0, 150, 300) mm + uniform D65 sky; camera (0, −250, 300) mm; 180×120 px, 256 spp "
             "(ldsampler), 16 bands 400–700 nm", fontsize=9)
fig.tight_layout()
fig.savefig(out / "mitsuba_crosscheck.png", dpi=110)
print(f"wrote {out / 'mitsuba_crosscheck.png'}")
