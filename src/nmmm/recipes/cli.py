"""Click commands ``nmmm run``, ``nmmm compare`` and ``nmmm sweep`` (mapped from :mod:`nmmm.cli`;
``nmmm demo`` is :mod:`nmmm.demo.cli`)."""

from __future__ import annotations

from pathlib import Path

import click

from nmmm.errors import NmmmError


class DataError(click.ClickException):
    """A recipe or data error: exit status 2 like click's usage errors, one line (``nmmm.cli.main``)."""

    exit_code = 2

    def show(self, file=None):
        click.echo(f"error: {self.format_message()}", err=True, file=file)


def _output_dir(value, create: bool = True) -> Path:
    """Check (and, for ``create``, make) the output folder now, so that an unwritable path is a clear
    error, not a traceback. ``create=False``: only its parent is made; the run's atomic writer
    (:func:`nmmm.atomic_io.atomic_output_dir`) puts the complete folder in place at the end."""
    out = Path(value)
    try:
        if out.exists() and not out.is_dir():
            raise FileExistsError(17, "a file of that name exists")
        (out if create else out.absolute().parent).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise click.BadParameter(f"cannot create the output folder {str(out)!r}: {exc.strerror or exc}",
                                 param_hint="'-o' / '--output'") from None
    return out


def _recipe_path(value: str) -> str:
    """A recipe path, or the name of a shipped example (``hematite_paint``)."""
    if Path(value).is_dir():
        raise click.BadParameter(f"{value!r} is a folder; give a recipe file (.toml) or a shipped example's name")
    if Path(value).exists():
        return value
    from nmmm.recipes.schema import example_recipes

    ex = example_recipes()
    stem = value[:-5] if value.endswith(".toml") else value
    if stem in ex:
        return str(ex[stem])
    raise click.BadParameter(f"no file {value!r} and no shipped example of that name "
                             f"(shipped: {', '.join(sorted(ex))})")


@click.command("run")
@click.argument("recipe")
@click.option("-o", "--output", "output", default=None, help="Output folder (default: out-<recipe name>).")
@click.option("--set", "overrides", multiple=True, metavar="KEY=VALUE",
              help="Override a recipe key (repeatable), e.g. --set pigment.fraction=0.1.")
@click.option("--no-progress", is_flag=True, help="Hide progress bars.")
@click.option("--pair-with", "pair_with", default=None, metavar="PHOTO",
              help="Also write OUTPUT/pairs.toml for 'nmmm experiment serve': the computed image "
                   "(or colour swatch) beside this photograph of the real plate.")
@click.option("--allow-outside-files", is_flag=True,
              help="Let the recipe's compound 'file' paths lie outside its folder (only for recipes you trust).")
def run(recipe, output, overrides, no_progress, pair_with, allow_outside_files):
    """Run a TOML RECIPE (a path, or a shipped example's name) into an output folder:
    spectra (CSV, NetCDF), CIELAB colours, plots, images and report.html."""
    from nmmm.recipes.run import run_recipe
    from nmmm.recipes.schema import files_outside_allowed

    path = _recipe_path(recipe)
    out = Path(output or f"out-{Path(path).stem}")
    try:
        with files_outside_allowed(allow_outside_files):
            res = _run(path, out, overrides, no_progress, pair_with, run_recipe)
    except NmmmError as exc:
        raise DataError(str(exc)) from None
    pairs = res.files.get("pairs")
    for row in res.colours:
        if row["spectrum"] == res.primary:
            click.echo(f"{res.primary} under {row['illuminant']}: L* = {row['L']:.2f}, a* = {row['a']:.2f}, b* = {row['b']:.2f}")
    click.echo(f"report: {Path(res.files['report']).resolve()}" if "report" in res.files else f"outputs in {out.resolve()}")
    if pair_with is not None:
        click.echo(f"pairs: {pairs} (nmmm experiment serve {pairs})")


def _run(path, out, overrides, no_progress, pair_with, run_recipe):
    """The body of ``nmmm run`` (NmmmErrors become one line in :func:`run`)."""
    if pair_with is not None:  # a bad photograph is reported before the physics runs
        from nmmm.experiment.pairs import check_image

        check_image(pair_with, what="photograph (--pair-with)")
    _output_dir(out, create=False)
    if overrides:
        from nmmm.recipes.run import _dump_toml
        from nmmm.recipes.schema import read_toml, set_key
        from nmmm.recipes.sweep import parse_vary

        raw, _, base = read_toml(path)
        for ov in overrides:
            try:
                key, vals = parse_vary(ov)
            except NmmmError as exc:
                raise click.BadParameter(str(exc).replace("--vary ", "", 1), param_hint="'--set'") from None
            raw = set_key(raw, key, vals[0] if len(vals) == 1 else vals)
        # relative 'file' paths stay relative to (and confined to) the recipe's folder
        res = run_recipe(_dump_toml(raw), out, progress=not no_progress, base_dir=base)
    else:
        res = run_recipe(path, out, progress=not no_progress)
    if pair_with is not None:
        from nmmm.recipes.pairs import make_experiment_pairs

        res.files["pairs"] = str(make_experiment_pairs([(res, pair_with)], out / "pairs.toml",
                                                       progress=not no_progress))
    return res


@click.command("compare")
@click.argument("recipe_a")
@click.argument("recipe_b")
@click.option("-i", "--illuminant", "illuminants", multiple=True, help="Illuminant (repeatable; default: the first recipe's).")
@click.option("-o", "--output", "output", default="nmmm-compare", show_default=True, help="Output folder.")
@click.option("--no-progress", is_flag=True)
@click.option("--allow-outside-files", is_flag=True,
              help="Let the recipe's compound 'file' paths lie outside its folder (only for recipes you trust).")
def compare(recipe_a, recipe_b, illuminants, output, no_progress, allow_outside_files):
    """Compare two recipes (substitution view): ΔE2000 under each illuminant, spectra
    overlaid, images side by side."""
    from nmmm.recipes.compare import compare_recipes

    from nmmm.recipes.schema import files_outside_allowed

    try:
        with files_outside_allowed(allow_outside_files):
            r = compare_recipes(_recipe_path(recipe_a), _recipe_path(recipe_b), _output_dir(output, create=False),
                                list(illuminants) or None, progress=not no_progress)
    except NmmmError as exc:
        raise DataError(str(exc)) from None
    na, nb = r["names"]  # the recipes' own names: "A"/"B" would read as illuminant A
    click.echo(f"first recipe: {na}\nsecond recipe: {nb}")
    for row in r["rows"]:
        click.echo(f"{row['geometry']}, illuminant {row['illuminant']}: dE00 = {row['dE00']:.3f}  "
                   f"({na}: L* {row['L_A']:.2f} a* {row['a_A']:.2f} b* {row['b_A']:.2f}; "
                   f"{nb}: L* {row['L_B']:.2f} a* {row['a_B']:.2f} b* {row['b_B']:.2f})")
    click.echo(f"runs: {Path(r['folders'][0]).resolve()} and {Path(r['folders'][1]).resolve()}")
    click.echo(f"report: {Path(r['report']).resolve()}")


@click.command("sweep")
@click.argument("recipe")
@click.option("--vary", "varies", multiple=True, required=True,
              help="KEY=START:STOP:NUM or KEY=V1,V2,... (repeatable; the grid is their product).")
@click.option("--scheduler", default=None, help="Address of a running Dask scheduler (tcp://HOST:8786); "
              "default: a local cluster of worker processes.")
@click.option("-n", "--workers", "n_workers", default=2, show_default=True, type=click.IntRange(min=1),
              help="Worker processes of the local cluster (>= 1).")
@click.option("--max-points", default=None, type=click.IntRange(min=1), metavar="N",
              help="Allow a grid of up to N points (default: refuse grids above "
                   "nmmm.recipes.sweep.MAX_POINTS with the estimated time and disk).")
@click.option("--serial", is_flag=True, help="Compute in this process, without Dask.")
@click.option("-o", "--output", "output", default=None, help="Sweep folder (reused to resume; default sweep-<recipe>).")
@click.option("--no-progress", is_flag=True)
@click.option("--allow-outside-files", is_flag=True,
              help="Let the recipe's compound 'file' paths lie outside its folder (only for recipes you trust).")
def sweep(recipe, varies, scheduler, n_workers, serial, max_points, output, no_progress, allow_outside_files):
    """Sweep a recipe over a parameter grid on Dask; one Parquet file per finished point,
    and a rerun resumes where it stopped."""
    from nmmm.recipes.sweep import sweep as run_sweep

    path = _recipe_path(recipe)
    out = _output_dir(output or f"sweep-{Path(path).stem}", create=False)  # made once the grid is valid
    try:
        s = run_sweep(path, list(varies), out, scheduler=scheduler, n_workers=n_workers, serial=serial,
                      progress=not no_progress, max_points=max_points,
                      allow_outside_files=allow_outside_files)
    except NmmmError as exc:
        raise DataError(str(exc)) from None
    for w in s.get("warnings", []):
        click.echo(f"warning: {w}", err=True)
    click.echo(f"{s['n_points']} points: {s['n_computed']} computed, {s['n_skipped']} already done; "
               f"{s['wall_s']:.1f} s wall, {s['physics_s']:.1f} s of physics")
    click.echo(f"results: {(out / 'results.parquet').resolve()} (and results.csv, points/*.parquet)")
