"""``nmmm match TARGET RECIPE --vary KEY=LO:HI … -o OUT``: a recipe matched to a measured colour."""

from __future__ import annotations

import click

__all__ = ["match", "calibrate"]


def _target(target: str, unit: str, geometry, sample):
    """(spectra or None, lab or None, name) of a TARGET argument: a measured file or ``lab:L,a,b``."""
    from nmmm.errors import InvalidInputError
    from nmmm.matching.measured_files import read_measured

    if target.lower().startswith("lab:"):
        try:
            lab = [float(v) for v in target[4:].split(",")]
        except ValueError:
            lab = []
        if len(lab) != 3:
            raise InvalidInputError(f"TARGET {target!r}: write lab:L,a,b (three numbers, e.g. lab:45,30,25)")
        return None, lab, target
    ms = read_measured(target, unit=unit, geometry=geometry)
    name = ms.names[0] if sample is None else sample
    return ms, None, name


@click.command("match")
@click.argument("target")
@click.argument("recipe")
@click.option("--vary", "varies", multiple=True, required=True, metavar="KEY=LO:HI",
              help="A free key of the recipe and its bounds (repeat): pigments.0.fraction=0:0.2, film.thickness_nm=2e4:8e4.")
@click.option("-o", "--output", default=None, help="Result folder (default match-<recipe>).")
@click.option("--mode", type=click.Choice(["colorimetric", "spectral"]), default="colorimetric", show_default=True)
@click.option("-i", "--illuminant", default="D65", show_default=True, help="Primary illuminant (F11, TL84, CWF accepted).")
@click.option("-t", "--test-illuminant", "tests", multiple=True, default=("A", "F11"), show_default=True,
              help="Illuminants of the metamerism index (repeat).")
@click.option("--metamerism-weight", default=0.0, show_default=True, type=click.FloatRange(min=0),
              help="Penalty weight of the metamerism index in a colorimetric match.")
@click.option("--sample", default=None, help="Which sample of a multi-sample file (default: the first).")
@click.option("--geometry", default=None, help="Which geometry of a multi-angle CxF3 file.")
@click.option("--percent", is_flag=True, help="The file's reflectances are in percent (0-100).")
@click.option("--delta-e", "delta_e_method", default="CIE 2000", show_default=True, metavar="METHOD",
              help="Reported colour difference (the fit stays on dE00): CIE 1976, CIE 1994[(textiles)], CMC[(l:c)], "
                   "CIE 2000[(kL:kC:kH)]; aliases dE76, dE94, dE00, e.g. 'CMC(2:1)'.")
@click.option("--tolerance", default=None, type=float, metavar="DE",
              help="Pass/fail of the match: the reported difference (--delta-e) <= DE.")
@click.option("--no-progress", is_flag=True)
@click.option("--max-colourants", default=None, type=int, metavar="N",
              help="Colourant selection: the varied pigments.<i>.fraction keys are a palette; rank its subsets of at most "
                   "N colourants (the others at fraction 0); matches.csv has one row per subset.")
def match(target, recipe, varies, output, mode, illuminant, tests, metamerism_weight, sample, geometry, percent, no_progress,
          max_colourants=None, delta_e_method="CIE 2000", tolerance=None):
    """Match RECIPE's free keys (--vary) to TARGET: a CGATS.17 / CxF3 / CSV file, or lab:L,a,b."""
    import warnings
    from pathlib import Path

    from nmmm.matching.measured_files import geometry_mismatch
    from nmmm.matching.outputs import write_match_outputs
    from nmmm.matching.recipe_match import IdentifiabilityWarning, RecipeModel, match_recipe

    method, k, label = _delta_e_spec(delta_e_method, tolerance)
    ms, lab, name = _target(target, "percent" if percent else "auto", geometry, sample)
    model = RecipeModel(recipe, varies)
    R = None
    if ms is not None:
        ms.spectrum(name)  # an unknown --sample names the file's samples
        R = ms.on_grid(model.wavelength_nm)[ms.names.index(name)]
        if len(ms) > 1:
            click.echo(f"matching sample {name!r} ({ms.names.index(name) + 1} of {len(ms)}; --sample chooses another)")
    differs = geometry_mismatch(ms.geometry, model.geometry) if ms is not None else None
    if differs:
        click.echo(f"warning: {differs}", err=True)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if max_colourants is None:
            res = match_recipe(model, R, lab, mode=mode, illuminant=illuminant, test_illuminants=tests,
                               metamerism_weight=metamerism_weight, progress=not no_progress)
        else:  # colourant selection: the best subset's match, its candidates one row per subset
            from nmmm.matching.colourant_selection import select_colourants, subset_rows

            sel = select_colourants(model, max_colourants, R, lab, mode=mode, illuminant=illuminant, test_illuminants=tests,
                                    metamerism_weight=metamerism_weight, progress=not no_progress)
            res = sel[0].result
            res.candidates = subset_rows(sel, illuminant)
            res.recipe_raw = model.matched_raw(list(sel[0].values.values()))
            res.values = dict(sel[0].values)  # every palette key, the excluded ones at 0
            res.evaluations = dict(model.evaluations)  # every subset's KM ranking and finish
            click.echo(f"best of {len(sel)} subsets of at most {max_colourants}: {' + '.join(sel[0].colourants)}")
    for w in caught:  # an unidentifiable key is part of the result (stdout and report.md), others on stderr
        click.echo(f"warning: {w.message}", err=not issubclass(w.category, IdentifiabilityWarning))
    out = Path(output) if output else Path(f"match-{Path(recipe).stem}")
    difference = _difference(res, method, k, label, tolerance)
    files = write_match_outputs(res, out, name, difference=difference)
    click.echo("  ".join(f"{k} = {v:.5g}" for k, v in res.values.items()))
    click.echo(f"dE00 = {res.de00:.4f} under {res.illuminant}; metamerism index "
               + (", ".join(f"{k} {v:.3f}" for k, v in res.metamerism.items()) or "n/a")
               + f"; {sum(res.evaluations.values())} model evaluations in {res.time_s:.1f} s")
    if tolerance is not None or method != "CIE 2000" or k:
        click.echo(f"{label} = {difference['value']:.4f} under {res.illuminant}" + (
            "" if tolerance is None else f"; tolerance {tolerance:g}: {'pass' if difference['passes'] else 'FAIL'}"))
    click.echo(f"results: {files['matches'].parent.resolve()}")


def _ladder(path):
    """Samples of a ladder file (TOML: ``compound``, ``fit``, ``measured``, ``[[samples]]`` with
    ``name``, ``recipe``, optional ``set = {key = value}``, ``sample`` (name in the measured file),
    ``left_out``)."""
    import tomllib
    from pathlib import Path

    from nmmm.errors import InvalidInputError
    from nmmm.matching.calibration import LadderSample
    from nmmm.matching.measured_files import read_measured
    from nmmm.recipes.run import _grid
    from nmmm.recipes.schema import parse_recipe, read_toml, set_key

    p = Path(path)
    try:
        spec = tomllib.loads(p.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise InvalidInputError(f"{p.name}: not valid TOML ({exc})") from None
    for key in ("compound", "measured", "samples"):
        if key not in spec:
            raise InvalidInputError(f"{p.name}: missing '{key}' (a ladder file names compound, measured and [[samples]])")
    base = p.parent
    measured = read_measured(base / spec["measured"], unit=spec.get("unit", "auto"), geometry=spec.get("geometry"))
    samples, left = [], []
    for i, s in enumerate(spec["samples"]):
        if "name" not in s or "recipe" not in s:
            raise InvalidInputError(f"{p.name}: samples[{i}] needs name and recipe")
        raw, _, rbase = read_toml(base / s["recipe"])
        for k, v in s.get("set", {}).items():
            raw = set_key(raw, k, v)
        raw.setdefault("name", s["name"])
        w = _grid(parse_recipe(raw, base_dir=rbase))
        which = s.get("sample", s["name"])
        measured.spectrum(which)  # an unknown sample names the file's samples
        R = measured.on_grid(w)[measured.names.index(which)]
        samples.append(LadderSample(s["name"], raw, R, rbase))
        if s.get("left_out", False):
            left.append(s["name"])
    return spec, samples, tuple(left)


@click.command("calibrate")
@click.argument("ladder")
@click.option("-o", "--output", default=None, help="Result folder (default calibrate-<ladder>).")
@click.option("-i", "--illuminant", default="D65", show_default=True)
def calibrate(ladder, output, illuminant):
    """Fit a colourant's k scale and grain-size scale on a measured LADDER (TOML: compound, fit,
    measured file, [[samples]] with recipe, set, left_out); writes the calibrated compound."""
    import csv
    import io
    import json
    from pathlib import Path

    from nmmm.atomic_io import atomic_output_dir
    from nmmm.matching.calibration import CALIBRATION_PARAMETERS, calibrate_colourant, write_calibrated_material

    spec, samples, left = _ladder(ladder)
    res = calibrate_colourant(samples, spec["compound"], fit=tuple(spec.get("fit", CALIBRATION_PARAMETERS)), left_out=left,
                              illuminant=illuminant)
    out = Path(output) if output else Path(f"calibrate-{Path(ladder).stem}")
    with atomic_output_dir(out) as tmp:
        buf = io.StringIO()
        wr = csv.writer(buf)
        wr.writerow(["sample", "role", f"dE00_before_{illuminant}", f"dE00_after_{illuminant}"])
        for s in samples:
            wr.writerow([s.name, "left out" if s.name in left else "fitted", f"{res.de00_before[s.name]:.4f}",
                         f"{res.de00_after[s.name]:.4f}"])
        (tmp / "calibration.csv").write_text(buf.getvalue(), encoding="utf-8")
        write_calibrated_material(res, tmp / f"{spec['compound']}_calibrated.csv")
        (tmp / "calibration.json").write_text(json.dumps(dict(compound=res.compound, values=res.values,
                                                              standard_errors=res.standard_errors, de00_before=res.de00_before,
                                                              de00_after=res.de00_after, left_out=list(left),
                                                              model_evaluations=res.evaluations, time_s=res.time_s), indent=1),
                                              encoding="utf-8")
    click.echo("  ".join(f"{k} = {v:.4f} ± {res.standard_errors[k]:.4f}" for k, v in res.values.items()))
    for s in samples:
        click.echo(f"{s.name}{' (left out)' if s.name in left else ''}: dE00 {res.de00_before[s.name]:.2f} -> "
                   f"{res.de00_after[s.name]:.2f}")
    for line in _calibration_instructions(samples, spec["compound"], res.values):
        click.echo(line)
    click.echo(f"results: {out.resolve()}")


def _calibration_instructions(samples, compound, values):
    """What the calibrated material file does not carry, as recipe instructions: the grain-size
    correction (a recipe key, not an optical constant) and a uniaxial compound's single n, k."""
    keys, uniaxial = [], None
    for s in samples:
        raw = s.recipe if isinstance(s.recipe, dict) else {}
        for i, pg in enumerate(raw.get("pigments") or []):
            if pg.get("compound") == compound and "diameter_nm" in pg and f"pigments.{i}.diameter_nm" not in keys:
                keys.append(f"pigments.{i}.diameter_nm")
        uniaxial = uniaxial or ((raw.get("compounds") or {}).get(compound) or {}).get("uniaxial")
    out = []
    if "size_scale" in values and keys:
        out.append(f"size: the calibrated file holds n, k only — in recipes using it, multiply {' and '.join(keys)} by "
                   f"{values['size_scale']:.4g}")
    if uniaxial:
        out.append(f"note: {compound} is uniaxial ({' + '.join(uniaxial)}, mean index); the calibrated file is written "
                   "as one isotropic n, k (use it with compound file = ..., not uniaxial = [...])")
    return out


def _delta_e_spec(text: str, tolerance: float | None) -> tuple[str, dict, str]:
    """(method, parameters, label) of ``--delta-e`` (``CMC(2:1)``, ``dE00(2:1:1)``, ``dE94(textiles)``)."""
    from nmmm.colour.difference import canonical_delta_e_method
    from nmmm.errors import InvalidInputError

    head, _, tail = text.strip().partition("(")
    method = canonical_delta_e_method(head.strip())
    args = [a.strip() for a in tail.rstrip(")").split(":")] if tail else []
    names = {"CIE 1976": (), "CIE 1994": ("textiles",), "CMC": ("l", "c"), "CIE 2000": ("kL", "kC", "kH")}[method]
    if method == "CIE 1994":
        if args not in ([], ["textiles"], ["graphic arts"]):
            raise InvalidInputError(f"--delta-e {text!r}: CIE 1994 takes (textiles) or (graphic arts)")
        k = {"textiles": True} if args == ["textiles"] else {}
    else:
        try:
            values = [float(a) for a in args]
        except ValueError:
            values = []
        if args and (len(values) != len(names) or not all(v > 0 for v in values)):
            raise InvalidInputError(f"--delta-e {text!r}: {method} takes ({':'.join(names)}) as numbers > 0 "
                                    f"or none, e.g. {'CMC(2:1)' if method == 'CMC' else 'CIE 2000(2:1:1)'}")
        k = dict(zip(names, values))
    if tolerance is not None and not (tolerance > 0 and tolerance < float("inf")):
        raise InvalidInputError(f"--tolerance {tolerance:g}: a colour-difference tolerance is a number > 0 (e.g. 1.0)")
    label = {"CIE 1976": "dE*ab", "CIE 1994": "dE94", "CMC": "dE CMC", "CIE 2000": "dE00"}[method]
    if k:
        label += "(" + ":".join("textiles" if v is True else f"{v:g}" for v in k.values()) + ")"
    elif method == "CMC":
        label += "(2:1)"
    return method, k, label


def _difference(res, method: str, k: dict, label: str, tolerance: float | None) -> dict:
    """The reported colour difference of the match against the target under its illuminant, with pass/fail."""
    from nmmm.colour.difference import delta_e, delta_lch

    value = float(delta_e(res.target_lab, res.lab, method, **k))
    d = dict(method=method, parameters=k, label=label, value=value, illuminant=res.illuminant,
             dL_dC_dH_ab=[float(v) for v in delta_lch(res.target_lab, res.lab)], tolerance=tolerance)
    if tolerance is not None:
        d["passes"] = value <= tolerance
    return d
