"""``nmmm micro`` — generate random microstructures and analyse SEM images.

- ``nmmm micro generate model.toml -o cell.tif`` — the TOML file names the ``model`` (a key
  of :data:`MODELS`), the grid (``shape`` in voxels, ``voxel_nm``) and the model's keyword
  arguments, e.g.::

      model = "hardcore_pseudocubes"
      shape = [128, 128, 128]
      voxel_nm = 5.0
      seed = 1
      diagonal_nm = 250.0
      fraction = 0.07

  For ``flake_deposit`` give ``box_nm`` and ``voxel_nm`` (anisotropic allowed) instead of
  ``shape``.
- ``nmmm micro analyze image.png --pixel-nm 10`` — prints the estimated parameters and
  writes a figure with the detected particles and their exclusion zones;
  ``--model aggregates`` adds the cluster-model fit, ``--model flakes`` the flake model
  from a cross-section (substrate horizontal).
- ``nmmm micro info cell.tif`` — shape, voxel size, fractions and parameters of a file.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import click

from nmmm.errors import DataFileError, InvalidInputError

MODELS = {
    "boolean_spheres": "nmmm.microstructure.boolean:boolean_spheres",
    "boolean_cubes": "nmmm.microstructure.boolean:boolean_cubes",
    "boolean_discs": "nmmm.microstructure.boolean:boolean_discs",
    "hardcore_spheres": "nmmm.microstructure.hardcore:hardcore_spheres",
    "hardcore_pseudocubes": "nmmm.microstructure.hardcore:hardcore_pseudocubes",
    "aggregates": "nmmm.microstructure.aggregation:aggregates",
    "flake_deposit": "nmmm.microstructure.flakes:flake_deposit",
}


def _load(target):
    import importlib

    mod, attr = target.split(":")
    return getattr(importlib.import_module(mod), attr)


def generate_from_config(cfg: dict, progress: bool = False):
    """Build a :class:`Microstructure` from a model description (a TOML table as a dict)."""
    cfg = dict(cfg)
    name = cfg.pop("model", None)
    if name not in MODELS:
        raise InvalidInputError(f"model must be one of {sorted(MODELS)}, got {name!r}")
    fn = _load(MODELS[name])
    if name == "flake_deposit":
        voxel = cfg.pop("voxel_nm", None)
        if voxel is None:
            raise InvalidInputError("flake_deposit needs voxel_nm (e.g. [1000, 1000, 100]) to rasterise the cell")
        deposit = fn(**cfg)
        return deposit.rasterize(voxel_nm=voxel)
    for key in ("shape", "voxel_nm"):
        if key not in cfg:
            raise InvalidInputError(f"model {name!r} needs '{key}' (grid in voxels and voxel size in nm)")
    if name.startswith("hardcore"):
        cfg.setdefault("progress", progress)
    try:
        return fn(**cfg)
    except TypeError as exc:
        raise InvalidInputError(f"bad parameters for {name}: {exc}") from None


@click.group(name="micro")
def micro():
    """Random microstructures (Boolean, hard-core, aggregates, flakes) and SEM image analysis."""


@micro.command("generate")
@click.argument("config", type=click.Path(dir_okay=False))
@click.option("-o", "--output", default="cell.tif", show_default=True, help="Output file (.tif or .npz).")
def generate(config, output):
    """Generate a microstructure described by a TOML file and save it."""
    from nmmm.microstructure.io import save_microstructure

    p = Path(config)
    if not p.is_file():
        raise DataFileError(f"model file not found: {p}")
    try:
        cfg = tomllib.loads(p.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise DataFileError(f"{p}: not a valid TOML file ({exc})") from None
    if "model" in cfg and isinstance(cfg["model"], dict):  # [model] table form
        cfg = dict(cfg["model"])
    m = generate_from_config(cfg, progress=True)
    save_microstructure(m, output)
    click.echo(repr(m))
    click.echo(f"written {output}")


@micro.command("analyze")
@click.argument("image", type=click.Path(dir_okay=False))
@click.option("--pixel-nm", default=1.0, show_default=True, type=float, help="Pixel size in nm.")
@click.option("--threshold", default="otsu", show_default=True, help="'otsu' or a grey level in [0, 1].")
@click.option("--invert", is_flag=True, help="Particles are darker than the matrix.")
@click.option("--smooth-px", default=1.0, show_default=True, type=float, help="Gaussian smoothing before thresholding.")
@click.option("--figure", default=None, help="Figure path (default: <image>_analysis.png).")
@click.option("--model", type=click.Choice(["aggregates", "flakes"]), default=None,
              help="Also fit the aggregate (cluster) model, or the flake model to a cross-section "
                   "with the substrate horizontal.")
@click.option("--json", "as_json", is_flag=True, help="Print the estimates as JSON.")
def analyze(image, pixel_nm, threshold, invert, smooth_px, figure, model, as_json):
    """Estimate fraction, sizes, exclusion zones and model parameters from an SEM-like image."""
    from nmmm.microstructure.analysis import analyze_image, read_image

    img = read_image(image)
    thr = threshold
    if threshold.lower() != "otsu":
        try:
            thr = float(threshold)
        except ValueError:
            raise InvalidInputError(f"--threshold must be 'otsu' or a number, got {threshold!r}") from None
    res = analyze_image(img, pixel_nm, thr, invert, smooth_px, model=model)
    s = res.summary()
    fig = figure or str(Path(image).with_name(Path(image).stem + "_analysis.png"))
    res.plot(fig, title=f"{Path(image).name}: area fraction {res.fraction:.3f}")
    if as_json:
        click.echo(json.dumps(s, indent=2, default=float))
    else:
        for k, v in s.items():
            click.echo(f"{k:32s} {v:.6g}" if isinstance(v, float) else f"{k:32s} {v}")
    click.echo(f"figure: {fig}")


@micro.command("info")
@click.argument("path", type=click.Path(dir_okay=False))
def info(path):
    """Describe a saved microstructure."""
    from nmmm.microstructure.io import load_microstructure

    m = load_microstructure(path)
    click.echo(repr(m))
    click.echo(json.dumps(m.params, indent=2, default=str))
