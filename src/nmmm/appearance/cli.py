"""``nmmm appearance`` — BRDFs, multi-angle colour, sparkle.

Commands
--------
- ``nmmm appearance multiangle`` — CIELAB at the ASTM E2539 (or E2194) aspecular angles
  and the flop index of a built-in paint (``--paint grey-metallic|metallic|interference|solid``).
- ``nmmm appearance table`` — export a paint's BRDF over (θ_h, θ_d, λ) to .nc or .csv.
- ``nmmm appearance sparkle IMAGE --pixel-size-um 10`` — sparkle and graininess of a
  photograph or render (PNG/JPEG/TIFF; ``--encoding srgb`` for photographs).
- ``nmmm appearance demo OUTDIR`` — the worked examples (figures, CSV, BRDF table; in
  :mod:`nmmm.demo.cli`, attached to this group by :mod:`nmmm.cli`).
"""

from __future__ import annotations

import json

import click
import numpy as np

PAINTS = ("grey-metallic", "metallic", "interference", "solid")


def _paint(name: str, tio2_nm: float, tilt_deg: float, optical_depth: float, base: float, roughness: float):
    from nmmm.appearance import brdf

    if name == "grey-metallic":
        return brdf.grey_metallic_paint()
    if name == "metallic":
        return brdf.metallic_paint(optical_depth=optical_depth, tilt=tilt_deg, body_reflectance=base,
                                   roughness=roughness)
    if name == "interference":
        return brdf.interference_paint(tio2_nm, optical_depth=optical_depth, tilt=tilt_deg, body_reflectance=base,
                                       roughness=roughness)
    return brdf.opaque_paint(base, roughness=roughness, name="solid grey paint")


def _paint_options(f):
    opts = [
        click.option("--paint", type=click.Choice(PAINTS), default="grey-metallic", show_default=True),
        click.option("--tio2-nm", type=float, default=120.0, show_default=True, help="TiO2 thickness (interference)."),
        click.option("--tilt-deg", type=float, default=8.0, show_default=True, help="Gaussian flake tilt sigma."),
        click.option("--optical-depth", type=float, default=1.5, show_default=True, help="Flake area per area (tau)."),
        click.option("--base", type=float, default=0.1, show_default=True, help="Internal base reflectance."),
        click.option("--roughness", type=float, default=0.0, show_default=True, help="Clear-coat GGX alpha."),
    ]
    for o in reversed(opts):
        f = o(f)
    return f


@click.group(name="appearance")
def appearance():
    """BRDFs of solid, metallic and interference paints; multi-angle colour; sparkle."""


@appearance.command()
@_paint_options
@click.option("--standard", type=click.Choice(["E2539", "E2194"]), default="E2539", show_default=True)
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
def multiangle(paint, tio2_nm, tilt_deg, optical_depth, base, roughness, standard, as_json):
    """CIELAB (D65/10°) at 45° illumination and the flop index (Alman 1987)."""
    from nmmm.appearance.multiangle import ASTM_E2194_ALL_ASPECULAR_DEG, ASTM_E2539_ASPECULAR_DEG, multiangle_lab

    b = _paint(paint, tio2_nm, tilt_deg, optical_depth, base, roughness)
    angles = ASTM_E2539_ASPECULAR_DEG if standard == "E2539" else ASTM_E2194_ALL_ASPECULAR_DEG
    c = multiangle_lab(b, np.arange(380.0, 781.0, 5.0), angles)
    fi = c.flop_index()
    if as_json:
        click.echo(json.dumps({"paint": b.name, "flop_index": fi, "angles": c.table()}, indent=1))
        return
    click.echo(f"{b.name} — ASTM {standard}, 45° illumination, D65/10°")
    click.echo(f"{'aspec':>6} {'L*':>7} {'a*':>7} {'b*':>7} {'C*':>7} {'h':>6}")
    for r in c.table():
        click.echo(f"{r['aspecular_deg']:6.0f} {r['L']:7.2f} {r['a']:7.2f} {r['b']:7.2f} {r['C']:7.2f} {r['h_deg']:6.1f}")
    click.echo(f"flop index (Alman 1987): {fi:.2f}")


@appearance.command()
@_paint_options
@click.option("--out", "out_path", type=click.Path(dir_okay=False), required=True, help="Output .nc or .csv.")
@click.option("--n-theta-h", type=int, default=90, show_default=True)
@click.option("--n-theta-d", type=int, default=90, show_default=True)
@click.option("--n-phi-d", type=int, default=36, show_default=True)
@click.option("--step-nm", type=float, default=10.0, show_default=True)
def table(paint, tio2_nm, tilt_deg, optical_depth, base, roughness, out_path, n_theta_h, n_theta_d, n_phi_d, step_nm):
    """Export the BRDF over (theta_h, theta_d, wavelength), averaged over phi_d."""
    from nmmm.appearance.brdf import write_brdf_table
    from nmmm.spectra import wavelength_grid

    b = _paint(paint, tio2_nm, tilt_deg, optical_depth, base, roughness)
    p = write_brdf_table(out_path, b, wavelength_grid(380.0, 780.0, step_nm), n_theta_h=n_theta_h,
                         n_theta_d=n_theta_d, n_phi_d=n_phi_d)
    click.echo(f"wrote {p}")


@appearance.command()
@click.argument("image", type=click.Path(exists=True, dir_okay=False))
@click.option("--pixel-size-um", type=float, required=True, help="Pixel size on the plate (µm).")
@click.option("--encoding", type=click.Choice(["srgb", "linear"]), default="srgb", show_default=True)
@click.option("--threshold", type=float, default=1.0, show_default=True, help="Sparkle contrast threshold.")
def sparkle(image, pixel_size_um, encoding, threshold):
    """Sparkle and graininess of a photograph or render of a plate."""
    from nmmm.appearance.sparkle import sparkle_graininess
    from nmmm.errors import DataFileError

    try:
        if image.lower().endswith((".tif", ".tiff")):
            import tifffile

            arr = tifffile.imread(image)
        elif image.lower().endswith(".npy"):
            arr = np.load(image)
        else:
            from PIL import Image

            arr = np.asarray(Image.open(image).convert("RGB"))
    except Exception as exc:  # PIL, tifffile and numpy each raise their own kinds
        raise DataFileError(f"cannot read the image {image!r} ({exc}); give a PNG, JPEG, TIFF or .npy array") from exc
    m = sparkle_graininess(arr, pixel_size_um, encoding=encoding, threshold_contrast=threshold)
    click.echo(json.dumps(m.as_dict(), indent=1))
