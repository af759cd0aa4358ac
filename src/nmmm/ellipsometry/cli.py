"""``nmmm ellipsometry`` — fit ellipsometric data from the command line.

Commands
--------
- ``nmmm ellipsometry fit data.csv --model model.toml`` — weighted fit of the model's free
  parameters; prints values ± uncertainties and the correlation matrix, writes a plot of data
  against model (``--output-dir``), optionally the fitted constants of layers as Material CSVs
  (``--save-material epoxy``) and a point-by-point inversion (``--point-by-point epoxy``).
  ``nmmm ellipsometry fit a.csv b.csv --model model.toml --shared A,B,C`` fits several data
  files jointly (:func:`nmmm.ellipsometry.joint.fit_joint`).
- ``nmmm ellipsometry pseudo data.csv`` — pseudo-dielectric function of a bulk sample, as a
  Material CSV.
- ``nmmm ellipsometry simulate --model model.toml -o data.csv`` — synthetic data of a model.
- ``nmmm ellipsometry uniaxial parallel.csv perpendicular.csv`` — ordinary, extraordinary and
  mean constants of a uniaxial crystal.

Data files: plain CSV or J. A. Woollam ASCII (see :mod:`nmmm.ellipsometry.data`).
"""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

__all__ = ["ellipsometry"]


def _floats(text: str, what: str):
    """'300:1000:5' (start:stop:step, inclusive) or '55,65,75'."""
    try:
        if ":" in text:
            a, b, c = (float(x) for x in text.split(":"))
            n = int(round((b - a) / c)) + 1
            return np.linspace(a, a + (n - 1) * c, n)
        return np.array([float(x) for x in text.split(",") if x.strip()])
    except ValueError:
        raise click.BadParameter(f"{what}: give 'start:stop:step' or comma-separated numbers, got {text!r}") from None


@click.group(name="ellipsometry")
def ellipsometry():
    """Spectroscopic ellipsometry: Psi/Delta data -> optical constants (Delta = 180 deg at normal
    incidence on a dielectric; 0 < Delta < 180 deg for a bulk absorber)."""


@ellipsometry.command("fit")
@click.argument("data_files", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option("--model", "model_files", required=True, multiple=True, type=click.Path(dir_okay=False),
              help="TOML model file: one for all data files, or one per data file (repeat --model).")
@click.option("--shared", default=None,
              help="Joint fit of several data files: comma-separated parameters common to all "
                   "(e.g. A,B,C); the others are fitted per file as name[i].")
@click.option("--format", "fmt", type=click.Choice(["csv", "woollam"]), default=None,
              help="Data format (default: from the suffix: .csv -> csv, else woollam).")
@click.option("--output-dir", "-o", type=click.Path(file_okay=False), default=".", show_default=True,
              help="Where plots and files go.")
@click.option("--save-material", multiple=True, help="Layer whose fitted n, k to write as a Material CSV (repeatable; "
              "in a joint fit, from the first data file's model).")
@click.option("--point-by-point", "pbp_layer", default=None, help="Also invert this layer's n, k wavelength by wavelength "
              "(one data file only).")
@click.option("--no-plot", is_flag=True, help="Do not write the plot.")
@click.option("--strict", is_flag=True, help="Refuse a data file with NaN rows, truncated lines, repeated or unsorted "
              "points, and exit 2 when the fit's reduced MSE is above 10 (instead of warning).")
@click.option("--no-prescan", is_flag=True, help="Start the local fit from the model's values instead of a global "
              "scan of each varied layer thickness (which finds the interference order first).")
def fit_cmd(data_files, model_files, shared, fmt, output_dir, save_material, pbp_layer, no_plot, strict, no_prescan):
    """Fit MODEL's free parameters to DATA_FILES (all angles at once); several data files with
    --shared are fitted jointly (e.g. films of one resin with different thicknesses).

    Each data file is scanned first (its summary is printed); each varied layer thickness is
    scanned over its range before the local fit (--no-prescan to skip); a reduced MSE above 10
    is warned about (--strict: an error, exit 2)."""
    import warnings

    from nmmm.ellipsometry.data import read_data, write_material_csv
    from nmmm.ellipsometry.fit_start import MSE_WARN_THRESHOLD, check_fit_quality, thickness_prescan
    from nmmm.ellipsometry.model import read_model
    from nmmm.errors import ConvergenceError

    joint = len(data_files) > 1 or shared is not None
    if len(data_files) > 1 and shared is None:
        raise click.UsageError("several data files are fitted jointly: say which parameters they share with "
                               "--shared (e.g. --shared A,B,C), or fit them one at a time")
    if len(model_files) not in (1, len(data_files)):
        raise click.UsageError(f"give one --model for all data files or one per data file; got {len(model_files)} "
                               f"models for {len(data_files)} data files")
    if joint and pbp_layer:
        raise click.UsageError("--point-by-point needs a single data file")
    datas = []
    for f in data_files:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # the scan summary below says it once
            datas.append(read_data(f, format=fmt, strict=strict))
    models = [read_model(m) for m in model_files]
    if len(models) == 1:
        models = models * len(datas)
    for d in datas:
        click.echo(f"data: {d!r}")
        scan = d.metadata.get("scan")
        if scan is not None:
            click.echo(("  " if scan.clean else "  warning: ") + scan.summary(), err=not scan.clean)
    if not no_prescan and not joint:
        models[0], lines = thickness_prescan(models[0], datas[0])
        for line in lines:
            click.echo(line)
    click.echo(f"model: {', '.join(dict.fromkeys(m.name for m in models))}")
    if joint:
        from nmmm.ellipsometry.joint import fit_joint

        result = fit_joint(list(zip(datas, models)), shared=shared)
        click.echo(f"joint fit of {len(datas)} data sets, shared: {shared}")
        useds, psis, deltas = result.extra["data"], result.extra["psi_deg"], result.extra["delta_deg"]
        fitted = result.extra["models"][0]
        for i, (f, c2) in enumerate(zip(data_files, result.extra["chi2_per_dataset"])):
            click.echo(f"  [{i}] {f}: chi2 = {c2:.6g}")
    else:
        result = models[0].fit(datas[0])
        useds, psis, deltas = [result.extra["data"]], [result.extra["psi_deg"]], [result.extra["delta_deg"]]
        fitted = result.extra["model"]
    click.echo(result.summary())
    click.echo("\ncorrelation matrix:")
    click.echo(result.correlation_table())
    bad_fit = check_fit_quality(result, MSE_WARN_THRESHOLD)
    if bad_fit:
        if strict:
            raise ConvergenceError(bad_fit + " (--strict)")
        click.echo(f"warning: {bad_fit}; --strict makes this an error", err=True)
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    if not no_plot:
        from nmmm.ellipsometry.plotting import plot_fit

        for f, used, psi, delta, model in zip(data_files, useds, psis, deltas, models):
            p = plot_fit(used, psi, delta, out / f"{Path(f).stem}_fit.png",
                         title=f"{model.name}: MSE {result.mse:.3g}" + (" (joint)" if joint else ""))
            click.echo(f"\nplot: {p}")
    for layer in save_material:
        mat = fitted.material(layer)
        w = np.unique(np.concatenate([d.wavelength_nm for d in datas]))
        what = ", ".join(Path(f).name for f in data_files)
        path = write_material_csv(out / f"{layer}_nk.csv", w, mat.nk(w), name=f"{layer} (fitted {models[0].name})",
                                  reference=f"ellipsometry {'joint ' if joint else ''}fit of {what}, MSE {result.mse:.3g}")
        click.echo(f"material: {path}")
    if pbp_layer:
        from nmmm.ellipsometry.point_by_point_inversion import kk_check, point_by_point

        pbp = point_by_point(result.extra["data"], fitted, pbp_layer)
        path = pbp.write_csv(out / f"{pbp_layer}_point_by_point.csv")
        click.echo(f"point-by-point: {path}")
        click.echo(str(kk_check(pbp)))


@ellipsometry.command("pseudo")
@click.argument("data_file", type=click.Path(dir_okay=False))
@click.option("--angle", type=float, default=None, help="Angle of incidence to use (deg) when the data hold several.")
@click.option("--format", "fmt", type=click.Choice(["csv", "woollam"]), default=None)
@click.option("--output", "-o", type=click.Path(dir_okay=False), default="pseudo_dielectric.csv", show_default=True)
def pseudo_cmd(data_file, angle, fmt, output):
    """Pseudo-dielectric function <eps> of a bulk sample, written as a Material CSV (n, k)."""
    from nmmm.ellipsometry.data import read_data, write_material_csv
    from nmmm.ellipsometry.pseudo_dielectric_function import pseudo_dielectric_material

    data = read_data(data_file, format=fmt)
    mat = pseudo_dielectric_material(data, angle, name=f"<eps> of {Path(data_file).stem}")
    path = write_material_csv(output, mat.wavelength_nm, mat.n_values + 1j * mat.k_values, name=mat.name,
                              reference=mat.reference)
    click.echo(f"{mat!r} -> {path}")


@ellipsometry.command("simulate")
@click.option("--model", "model_file", required=True, type=click.Path(dir_okay=False))
@click.option("--wavelengths", default="300:1000:5", show_default=True, help="start:stop:step or list (nm).")
@click.option("--angles", default="55,65,75", show_default=True, help="Angles of incidence (deg).")
@click.option("--sigma-psi", type=float, default=None, help="Noise sigma of Psi (deg); with --seed adds noise.")
@click.option("--sigma-delta", type=float, default=None, help="Noise sigma of Delta (deg).")
@click.option("--seed", type=int, default=None, help="Random seed for the noise.")
@click.option("--output", "-o", type=click.Path(dir_okay=False), required=True)
def simulate_cmd(model_file, wavelengths, angles, sigma_psi, sigma_delta, seed, output):
    """Write synthetic Psi/Delta of MODEL (its start values) as a CSV."""
    from nmmm.ellipsometry.data import EllipsometryData, write_csv
    from nmmm.ellipsometry.model import read_model

    model = read_model(model_file)
    data = EllipsometryData.from_model(model.build(), _floats(wavelengths, "--wavelengths"), _floats(angles, "--angles"),
                                       sigma_psi, sigma_delta, noise_seed=seed, name=model.name)
    click.echo(f"{data!r} -> {write_csv(data, output)}")


@ellipsometry.command("uniaxial")
@click.argument("parallel_file", type=click.Path(dir_okay=False))
@click.argument("perpendicular_file", type=click.Path(dir_okay=False))
@click.option("--name", default="crystal", show_default=True)
@click.option("--output-dir", "-o", type=click.Path(file_okay=False), default=".", show_default=True)
def uniaxial_cmd(parallel_file, perpendicular_file, name, output_dir):
    """Ordinary, extraordinary and mean constants of a uniaxial crystal from measurements with the
    optic axis parallel and perpendicular to the plane of incidence."""
    from nmmm.ellipsometry.anisotropy import uniaxial_from_two_orientations
    from nmmm.ellipsometry.data import read_data

    res = uniaxial_from_two_orientations(read_data(parallel_file), read_data(perpendicular_file), name=name)
    for key, path in res.write_csv(output_dir).items():
        click.echo(f"{key}: {path}")
