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
@click.option("--fraction", is_flag=True,
              help="The file's reflectances are factors whatever their size (a metallic near the specular exceeds 1).")
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
          max_colourants=None, delta_e_method="CIE 2000", tolerance=None, fraction=False):
    """Match RECIPE's free keys (--vary) to TARGET: a CGATS.17 / CxF3 / CSV file, or lab:L,a,b."""
    import warnings
    from pathlib import Path

    from nmmm.matching.measured_files import geometry_mismatch
    from nmmm.matching.outputs import write_match_outputs
    from nmmm.matching.recipe_match import IdentifiabilityWarning, RecipeModel, match_recipe

    method, k, label = _delta_e_spec(delta_e_method, tolerance)
    if percent and fraction:
        from nmmm.errors import InvalidInputError

        raise InvalidInputError("--percent and --fraction: give one (percent: 0-100; fraction: factors)")
    ms, lab, name = _target(target, "percent" if percent else "fraction" if fraction else "auto", geometry, sample)
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

    import difflib

    import click

    from nmmm.errors import DataFileError
    from nmmm.matching.measured_files import geometry_mismatch
    from nmmm.recipes.paint_stack import geometry_of

    p = Path(path)
    if not p.is_file():
        raise DataFileError(f"ladder file {str(p)!r} not found (a TOML file: compound, measured, [[samples]]; "
                            "e.g. examples/data/matching/ladder.toml in the nmmm source tree)")
    try:
        spec = tomllib.loads(p.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise InvalidInputError(f"{p.name}: not valid TOML ({exc})") from None
    _check_keys(spec, _LADDER_KEYS, p.name, difflib)
    for key in ("compound", "measured", "samples"):
        if key not in spec:
            raise InvalidInputError(f"{p.name}: missing '{key}' (a ladder file names compound, measured and [[samples]])")
    if isinstance(spec.get("fit"), str):  # fit = "k_scale, size_scale" as well as a list
        spec["fit"] = [f.strip() for f in spec["fit"].split(",") if f.strip()]
    base = p.parent
    try:
        measured = read_measured(base / spec["measured"], unit=spec.get("unit", "auto"), geometry=spec.get("geometry"))
    except (InvalidInputError, DataFileError) as exc:
        if "percent" not in str(exc):
            raise
        raise type(exc)(f"{exc} [in a ladder file: unit = \"percent\" (or \"fraction\") beside measured]") from None
    samples, left, said = [], [], set()
    for i, s in enumerate(spec["samples"]):
        _check_keys(s, _SAMPLE_KEYS, f"{p.name}: samples[{i}]", difflib)
        if "name" not in s or "recipe" not in s:
            raise InvalidInputError(f"{p.name}: samples[{i}] needs name and recipe")
        if not isinstance(s.get("left_out", False), bool):
            raise InvalidInputError(f"{p.name}: samples[{i}] ({s['name']!r}): left_out = {s['left_out']!r}; give true or false")
        raw, _, rbase = read_toml(base / s["recipe"])
        for k, v in s.get("set", {}).items():
            raw = set_key(raw, k, v)
        raw.setdefault("name", s["name"])
        rec = parse_recipe(raw, base_dir=rbase)
        w = _grid(rec)
        which = s.get("sample", s["name"])
        try:
            measured.spectrum(which)  # an unknown sample names the file's samples
        except (InvalidInputError, DataFileError) as exc:
            raise type(exc)(f"{p.name}: samples[{i}] ({s['name']!r}) in {spec['measured']}: {exc} — name it as the file does, "
                            "or add sample = \"<its name in the file>\"") from None
        R = measured.on_grid(w)[measured.names.index(which)]
        samples.append(LadderSample(s["name"], raw, R, rbase))
        if s.get("left_out", False):
            left.append(s["name"])
        differs = geometry_mismatch(measured.geometry, geometry_of(rec))
        if differs and differs not in said:  # as nmmm match says it: a calibration would absorb the difference
            said.add(differs)
            click.echo(f"warning: samples[{i}] ({s['name']!r}): {differs}", err=True)
    return spec, samples, tuple(left)


#: the keys of a ladder file and of its [[samples]] (anything else is refused, never ignored)
_LADDER_KEYS = ("compound", "fit", "measured", "unit", "geometry", "samples")
_SAMPLE_KEYS = ("name", "recipe", "set", "sample", "left_out")


def _check_keys(table, known, where, difflib):
    from nmmm.errors import InvalidInputError

    if not isinstance(table, dict):
        raise InvalidInputError(f"{where}: expected a table of keys {list(known)}")
    for key in table:
        if key not in known:
            close = difflib.get_close_matches(key, known, n=1)
            raise InvalidInputError(f"{where}: unknown key {key!r}" + (f" (did you mean {close[0]!r}?)" if close else "")
                                    + f"; known keys: {', '.join(known)}")


@click.command("calibrate")
@click.argument("ladder")
@click.option("-o", "--output", default=None, help="Result folder (default calibrate-<ladder>).")
@click.option("-i", "--illuminant", default="D65", show_default=True)
@click.option("--mode", type=click.Choice(["physical", "empirical", "both"]), default="physical", show_default=True,
              help="physical: the compound's k(λ) (KK-consistent n) and size through the full model; empirical: the "
                   "industry's two-constant Kubelka-Munk K, S per unit concentration (Duncan, Saunderson); both: and a "
                   "comparison table of their ΔE00 per sample.")
@click.option("--fit", "fit_names", default=None, metavar="P1,P2,…",
              help="Physical parameters to fit (default the ladder's 'fit', else k_scale,size_scale): k_scale, "
                   "k_legendre_1..3 (tilt, bow, S-shape of ln k), size_scale.")
def calibrate(ladder, output, illuminant, mode="physical", fit_names=None):
    """Calibrate a colourant on a measured LADDER (TOML: compound, fit, measured file, unit, geometry,
    [[samples]] with name, recipe, set, sample, left_out; e.g. examples/data/matching/ladder.toml in
    the source tree): the physical mode writes the calibrated compound and a recipe using it; the
    empirical mode K and S per unit concentration; both compares them sample by sample."""
    import json
    from pathlib import Path

    from nmmm.atomic_io import atomic_output_dir
    from nmmm.matching.calibration import DEFAULT_CALIBRATION_FIT

    spec, samples, left = _ladder(ladder)
    compound = spec["compound"]
    fit = tuple(f.strip() for f in fit_names.split(",") if f.strip()) if fit_names else tuple(spec.get("fit", DEFAULT_CALIBRATION_FIT))
    res = emp = None
    if mode in ("physical", "both"):
        import warnings

        from nmmm.matching.calibration import calibrate_colourant
        from nmmm.matching.recipe_match import IdentifiabilityWarning

        with warnings.catch_warnings():  # said on stdout and in report.md, not twice
            warnings.simplefilter("ignore", IdentifiabilityWarning)
            res = calibrate_colourant(samples, compound, fit=fit, left_out=left, illuminant=illuminant)
    if mode in ("empirical", "both"):
        import warnings

        from nmmm.matching.empirical_km import calibrate_empirical
        from nmmm.matching.recipe_match import IdentifiabilityWarning

        with warnings.catch_warnings():  # said on stdout and in report.md, not twice
            warnings.simplefilter("ignore", IdentifiabilityWarning)
            emp = calibrate_empirical(samples, left_out=left, illuminant=illuminant)
    out = Path(output) if output else Path(f"calibrate-{Path(ladder).stem}")
    rows = _comparison_rows(samples, left, res, emp)
    with atomic_output_dir(out) as tmp:
        _write_rows(tmp / "calibration.csv", rows)
        info = dict(compound=compound, mode=mode, illuminant=illuminant, left_out=list(left), samples=rows)
        if res is not None:
            from nmmm.matching.calibration import write_calibrated_material

            mat = f"{compound}_calibrated.csv"
            write_calibrated_material(res, tmp / mat, step_nm=5.0, source=Path(ladder).name)
            (tmp / "calibrated_recipe.toml").write_text(_calibrated_recipe(samples, compound, mat, res.values), encoding="utf-8")
            info.update(values=res.values, standard_errors=res.standard_errors, fit=list(fit), material_file=mat,
                        warnings=res.warnings,
                        de00_before=res.de00_before, de00_after=res.de00_after,
                        model_evaluations=res.evaluations, time_s=res.time_s,
                        correlation=_correlation(res.covariance).tolist())
        if emp is not None:
            _write_rows(tmp / "km_constants.csv", emp.table())
            info.update(colourants=list(emp.colourants), saunderson="k1 Fresnel at normal incidence, k2 internal diffuse "
                        "(Judd 1942), from the binder's index", k1_mean=float(emp.k1.mean()), k2_mean=float(emp.k2.mean()),
                        specular=emp.specular, time_s_empirical=emp.time_s, warnings_empirical=emp.warnings)
        (tmp / "calibration.json").write_text(json.dumps(info, indent=1), encoding="utf-8")
        (tmp / "report.md").write_text(_calibration_report(ladder, compound, rows, res, emp, fit, illuminant), encoding="utf-8")
    if res is not None:
        click.echo("  ".join(f"{k} = {v:.4f} ± {res.standard_errors[k]:.4f}" for k, v in res.values.items()))
        for note in res.warnings:
            click.echo(f"warning: {note}")
    for note in emp.warnings if emp is not None else ():
        click.echo(f"warning (empirical): {note}")
    for r in rows:
        click.echo(f"{r['sample']}{' (left out)' if r['role'] == 'left out' else ''}: dE00 "
                   + "; ".join(f"{k.split('_')[1]} {r[k]}" for k in r if k.startswith("dE00_")))
    if res is not None:
        for line in _calibration_instructions(samples, compound, res.values):
            click.echo(line)
        click.echo(f"calibrated compound: {(out / f'{compound}_calibrated.csv').resolve()} (used by calibrated_recipe.toml)")
    click.echo(f"results: {out.resolve()}")


def _comparison_rows(samples, left, res, emp) -> list[dict]:
    """One row per sample: its role and ΔE00 uncalibrated / physical / empirical (those computed)."""
    rows = []
    for s in samples:
        r = {"sample": s.name, "role": "left out" if s.name in left else "fitted"}
        if res is not None:
            r["dE00_uncalibrated"] = f"{res.de00_before[s.name]:.3f}"
            r["dE00_physical"] = f"{res.de00_after[s.name]:.3f}"
        if emp is not None:
            r["dE00_empirical"] = f"{emp.de00_after[s.name]:.3f}"
        rows.append(r)
    return rows


def _write_rows(path, rows):
    import csv

    with open(path, "w", newline="", encoding="utf-8") as fh:
        wr = csv.DictWriter(fh, fieldnames=list(rows[0]))
        wr.writeheader()
        wr.writerows(rows)


def _correlation(cov):
    import numpy as np

    d = np.sqrt(np.clip(np.diag(cov), 1e-300, None))
    return cov / np.outer(d, d)


def _calibrated_recipe(samples, compound, material_file, values) -> str:
    """The first sample's recipe with ``compound`` read from the calibrated file and its grains scaled."""
    from pathlib import Path

    from nmmm.recipes.run import _dump_toml
    from nmmm.recipes.schema import read_toml

    s = samples[0]
    raw, _, base = read_toml(s.recipe)
    base = base if base is not None else s.base_dir
    raw = dict(raw)
    comps = {k: dict(v) for k, v in (raw.get("compounds") or {}).items()}
    for name, c in comps.items():  # other compounds' files stay where they were
        if "file" in c and base is not None and not Path(c["file"]).is_absolute():
            c["file"] = str((Path(base) / c["file"]).resolve())
    comps[compound] = {"file": material_file}
    raw["compounds"] = comps
    sd = values.get("size_scale")
    if sd is not None and raw.get("pigments"):
        raw["pigments"] = [dict(p, diameter_nm=p["diameter_nm"] * sd) if p.get("compound") == compound and "diameter_nm" in p
                           else p for p in raw["pigments"]]
    raw["name"] = f"{s.name} (ladder sample) — {compound} calibrated"  # not the base recipe's name: the ladder set its fractions
    if raw.get("description"):
        raw["description"] = f"The ladder's base recipe, before its set keys: {raw['description']}"
    head = (f"# {s.name!r} of the ladder with {compound} calibrated by nmmm calibrate (physical mode): optical constants "
            f"from {material_file}" + (f", diameters x {sd:.6g}" if sd is not None else "") + "\n")
    return head + _dump_toml(raw)


def _calibration_report(ladder, compound, rows, res, emp, fit, illuminant) -> str:
    """report.md: what was fitted, the values with their uncertainties, the ΔE00 table."""
    from pathlib import Path

    lines = [f"# Calibration of {compound} on {Path(ladder).name}", ""]
    if res is not None:
        lines += ["## Physical mode", "",
                  f"Fitted {', '.join(fit)} through the full model (Mie + adding-doubling of each recipe); k(λ) multiplied by "
                  "s·exp(Σ c_j P_j(x)) over the calibration window, n changed by the Kramers-Kronig transform of the change "
                  f"of k. {res.evaluations} model evaluations, {res.time_s:.1f} s.", "",
                  "| parameter | value | standard error |", "|---|---|---|"]
        lines += [f"| {k} | {v:.5g} | {res.standard_errors[k]:.2g} |" for k, v in res.values.items()]
        lines += [""] + [f"**Warning:** {n}" for n in res.warnings] + ([""] if res.warnings else [])
    if emp is not None:
        lines += ["## Empirical mode", "",
                  f"Two-constant Kubelka-Munk K, S per unit volume fraction of {', '.join(emp.colourants)} (Duncan mixing), "
                  f"Saunderson k1 {emp.k1.min():.3f}-{emp.k1.max():.3f} (Fresnel, binder index), k2 {emp.k2.min():.3f}-"
                  f"{emp.k2.max():.3f} (internal diffuse, Judd 1942), specular {emp.specular}; constants in km_constants.csv.",
                  ""] + [f"**Warning:** {n}" for n in emp.warnings] + ([""] if emp.warnings else [])
    keys = list(rows[0])
    lines += [f"## ΔE00 per sample ({illuminant}; left-out samples are predictions)", "",
              "| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    lines += ["| " + " | ".join(str(r[k]) for k in keys) + " |" for r in rows]
    return "\n".join(lines) + "\n"


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
