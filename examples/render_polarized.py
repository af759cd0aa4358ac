"""Polarized plate renders (issue 19 item 7): the hematite recipe's solid paint and the grey metallic
recipe's paint (statistical flakes) in the grey viewing booth, seen at Brewster's angle of the coat
(56.3 deg from the normal), as Stokes images: the unpolarized view, the views through a horizontal (0 deg)
and a vertical (90 deg) linear polarizer, and the degree of linear polarization; writes
render_polarized.png and the spectral Stokes EXR (S0..S3) of each.

    python examples/render_polarized.py [OUTDIR]
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from nmmm.appearance.render import PaintedPlate, PinholeCamera, ViewingBooth  # noqa: E402
from nmmm.appearance.render.plate.stokes import render_plate_stokes  # noqa: E402
from nmmm.recipes.render_cli import plate_from_recipe_file  # noqa: E402

out = Path(sys.argv[1] if len(sys.argv) > 1 else "polarized_out")
out.mkdir(parents=True, exist_ok=True)
recipes = Path(__file__).resolve().parents[1] / "src" / "nmmm" / "recipes" / "examples"
w = np.arange(400.0, 701.0, 20.0)
e = np.radians(90.0 - np.degrees(np.arctan(1.5)))  # camera elevation: the plate centre at Brewster's angle
cam = PinholeCamera((0.0, -400.0 * np.cos(e), 400.0 * np.sin(e)), (0, 0, 0), (0, 0, 1), 36, (180, 120))
fig, axes = plt.subplots(2, 4, figsize=(15, 5.4))
for row, name in enumerate(("hematite_paint.toml", "grey_metallic.toml")):
    plate, _ = plate_from_recipe_file(recipes / name)
    plate = PaintedPlate(plate.brdf, size_mm=plate.size_mm)  # the statistical BRDF (no glints)
    scene = ViewingBooth(source="45").scene(plate, w)
    st = render_plate_stokes(plate, cam, scene["lights"], scene["environment"], wavelength_nm=w)
    st.write_exr(out / f"{name.split('.')[0]}_stokes.exr")
    dolp = st.degree_of_polarization()
    on = st.on_plate
    views = ((st.s0, "unpolarized"), (st.through_polarizer(0.0), "polarizer 0° (horizontal)"),
             (st.through_polarizer(90.0), "polarizer 90° (vertical)"))
    # one exposure per row (all three views alike; a polarizer view is exposed for the white tile seen through
    # the filter, StokesImage.through_polarizer): 1 (white tile = display white) unless the plate's
    # 99th-percentile radiance exceeds white (the metallic's flake highlight in the booth: a white blob at 1)
    top = np.percentile(st.s0.radiance[on].mean(axis=1), 99)
    expo = float(min(1.0, 0.9 * np.mean(st.white_radiance) / max(top, 1e-9)))
    for col, (img, title) in enumerate(views):
        rgb, stats = img.to_display("sRGB", expo, "knee")
        axes[row, col].imshow(rgb)
        axes[row, col].set_title(f"{plate.brdf.name}: {title}\nplate {stats['plate_mean_cd_m2']:.1f} cd/m² (exposure {expo:.2f})", fontsize=8)
        axes[row, col].axis("off")
    im = axes[row, 3].imshow(np.where(on, dolp, np.nan), vmin=0, vmax=1, cmap="magma")
    axes[row, 3].set_title(f"degree of linear polarization (plate mean {dolp[on].mean():.2f})", fontsize=8)
    axes[row, 3].axis("off")
    fig.colorbar(im, ax=axes[row, 3])
    print(f"{name}: plate DoLP mean {dolp[on].mean():.3f}, max {dolp[on].max():.3f}; "
          f"polarizer 90/0 luminance ratio {st.through_polarizer(90).to_xyz()[on][:, 1].mean() / st.through_polarizer(0).to_xyz()[on][:, 1].mean():.3f}")
fig.suptitle("Viewing booth (D65 source at 45°, grey walls 0.2); camera 400 mm away, plate centre seen at Brewster's "
             "angle 56.3° of n = 1.5", fontsize=9)
fig.tight_layout()
fig.savefig(out / "render_polarized.png", dpi=100)
print(f"wrote {out / 'render_polarized.png'}")
