"""``nmmm compare a.toml b.toml``: the substitution view — what changes when a pigment or a
binder is substituted, before anything is manufactured.

- :func:`compare_results` — two :class:`~nmmm.recipes.run.RunResult` -> ΔE2000 rows
  between their primary spectra under each illuminant (and per aspecular angle for flake
  paints), on the wavelengths both share.
- :func:`compare_recipes` — load, compute and write both, overlay their spectra, put their
  images side by side and write one HTML report; returns the rows and the report path.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nmmm.errors import RecipeError

__all__ = ["compare_results", "compare_recipes", "comparison_section", "recipe_names", "recipe_folders"]


def _common(res_a, res_b):
    wa, wb = res_a.wavelength_nm, res_b.wavelength_nm
    lo, hi = max(wa[0], wb[0]), min(wa[-1], wb[-1])
    if hi <= lo:
        raise RecipeError(f"spectral: the recipes share no wavelengths ({wa[0]:g}–{wa[-1]:g} vs {wb[0]:g}–{wb[-1]:g} nm)")
    step = max(np.min(np.diff(wa)), np.min(np.diff(wb)))
    n = int(np.floor((hi - lo) / step + 1e-9))
    return lo + step * np.arange(n + 1)


def compare_results(res_a, res_b, illuminants=None, observer: str = "2") -> list[dict]:
    """ΔE2000 between the primary spectra of two results (linear interpolation onto the
    common grid), under each illuminant (default: those of recipe A)."""
    from nmmm.colour import delta_e2000, spectra_to_lab

    w = _common(res_a, res_b)
    ra = np.interp(w, res_a.wavelength_nm, res_a.spectra[res_a.primary])
    rb = np.interp(w, res_b.wavelength_nm, res_b.spectra[res_b.primary])
    rows = []
    for ill in illuminants or res_a.recipe.lighting.illuminants:
        la = spectra_to_lab(w, ra, illuminant=ill, observer=observer)
        lb = spectra_to_lab(w, rb, illuminant=ill, observer=observer)
        rows.append({"geometry": f"{res_a.primary} vs {res_b.primary}", "illuminant": ill,
                     "L_A": float(la[0]), "a_A": float(la[1]), "b_A": float(la[2]),
                     "L_B": float(lb[0]), "a_B": float(lb[1]), "b_B": float(lb[2]),
                     "dE00": float(delta_e2000(la, lb))})
    if res_a.multiangle and res_b.multiangle:
        # multi-angle CIELAB as each run computed it (first illuminant of each recipe)
        mb = {(r["aspecular_deg"], r["illuminant"]): r for r in res_b.multiangle}
        for ra in res_a.multiangle:
            rb = mb.get((ra["aspecular_deg"], ra["illuminant"]))
            if rb is None:
                continue
            la = np.array([ra["L"], ra["a"], ra["b"]])
            lb = np.array([rb["L"], rb["a"], rb["b"]])
            rows.append({"geometry": f"aspecular {ra['aspecular_deg']:g}° ({res_a.recipe.viewing.illumination_deg:g}° illumination)", "illuminant": ra["illuminant"],
                         "L_A": la[0], "a_A": la[1], "b_A": la[2], "L_B": lb[0], "a_B": lb[1], "b_B": lb[2],
                         "dE00": float(delta_e2000(la, lb))})
    return rows


def compare_recipes(path_a, path_b, out_dir, illuminants=None, progress: bool = True) -> dict:
    """Run both recipes into sub-folders of ``out_dir`` named after them (:func:`recipe_folders`)
    and write ``out_dir/report.html``.

    Returns ``{"rows": [...], "report": path, "a": RunResult, "b": RunResult, "section": dict,
    "names": (name_a, name_b), "folders": (folder_a, folder_b)}`` (``section``: the comparison as a
    report section, for :mod:`nmmm.demo`; ``names``: what the report calls the recipes). The folder
    is locked for the whole comparison (a second one into it is refused); each run is written
    atomically, and the report last, atomically.
    """
    from nmmm.atomic_io import folder_lock
    from nmmm.recipes.schema import load_recipe

    # both recipes are validated before any lock, folder or physics; each run's folder is named
    # after its recipe (never out/A and out/B: "A" reads as illuminant A)
    folders = recipe_folders(load_recipe(path_a).name, load_recipe(path_b).name)
    with folder_lock(out_dir):
        return _compare_recipes(path_a, path_b, out_dir, illuminants, progress, folders)


def _compare_recipes(path_a, path_b, out_dir, illuminants, progress, folders):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from nmmm.recipes.report import result_section, write_report
    from nmmm.recipes.run import _finish, _spectrum_axes, run_recipe

    out = Path(out_dir)
    da, db = folders
    made = not out.exists()
    had_report = (out / "report.html").is_file() or (out / _COMPARE_MARKER).is_file()
    out.mkdir(parents=True, exist_ok=True)
    try:
        a = run_recipe(path_a, out / da, progress=progress, report=False)
        b = run_recipe(path_b, out / db, progress=progress, report=False)
    except BaseException:
        if made:  # a failed comparison leaves no folder behind (each run is atomic; only its locks remain)
            _remove_if_only_locks(out)
        raise
    rows = compare_results(a, b, illuminants, a.recipe.lighting.observer)
    na, nb = recipe_names(a, b)
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(a.wavelength_nm, a.spectra[a.primary], lw=2, label=f"{na} — {a.primary}")
    ax.plot(b.wavelength_nm, b.spectra[b.primary], lw=2, ls="--", label=f"{nb} — {b.primary}")
    _spectrum_axes(ax, [a.primary, b.primary])
    overlay = _finish(fig, out / "spectra_overlay.png")
    figs = [str(overlay)]
    if a.images and b.images:
        from PIL import Image

        ia, ib = next(iter(a.images.values())), next(iter(b.images.values()))
        if ia.shape == ib.shape:
            gap = np.ones((ia.shape[0], 8, 3))
            p = out / "images_side_by_side.png"
            Image.fromarray((np.concatenate([ia, gap, ib], axis=1) * 255 + 0.5).astype(np.uint8)).save(p)
            figs.append(str(p))
    summary = comparison_section(a, b, rows, figs, names=(na, nb))
    from nmmm.atomic_io import atomic_path

    with atomic_path(out / "report.html") as tmp:
        write_report([summary, result_section(a, f"First recipe: {na}"), result_section(b, f"Second recipe: {nb}")],
                     tmp, title=f"nmmm compare — {na} vs {nb}",
                     next_steps=[("the same comparison under other illuminants",
                                  f"nmmm compare {_arg(path_a, 'first.toml')} {_arg(path_b, 'second.toml')} "
                                  f"-i D65 -i A -i FL11 -o {out}")])
    report = out / "report.html"
    _remove_stale_outputs(out, (da, db), figs, had_report)
    return {"rows": rows, "report": str(report), "a": a, "b": b, "section": summary, "names": (na, nb),
            "folders": (str(out / da), str(out / db))}


#: written last into a comparison's folder: what this comparison wrote there
_COMPARE_MARKER = ".nmmm-compare.json"
#: the figures a comparison may write beside its report
_COMPARE_FIGURES = ("spectra_overlay.png", "images_side_by_side.png")


def _remove_stale_outputs(out: Path, folders, figures, had_report: bool) -> None:
    """Leave in ``out`` only this comparison: a run folder of an earlier comparison (a sub-folder
    holding nmmm's run manifest, in a folder that held a comparison report) and its lock file, and
    an earlier comparison's figure this one did not write, are removed; nothing else is touched
    (files and folders nmmm did not write stay). Then :data:`_COMPARE_MARKER` lists what is there."""
    import json
    import shutil

    from nmmm.atomic_io import MANIFEST_NAME, atomic_write_text

    keep = set(folders)
    if had_report:
        for sub in out.iterdir():
            if sub.name in keep or not sub.is_dir() or sub.is_symlink() or not (sub / MANIFEST_NAME).is_file():
                continue
            shutil.rmtree(sub, ignore_errors=True)
            lock = out / f".{sub.name}.nmmm-lock"
            if lock.is_file():
                lock.unlink(missing_ok=True)
        written = {Path(f).name for f in figures}
        for name in _COMPARE_FIGURES:
            if name not in written and (out / name).is_file():
                (out / name).unlink(missing_ok=True)
    atomic_write_text(out / _COMPARE_MARKER, json.dumps(
        {"folders": sorted(keep), "files": ["report.html"] + sorted(Path(f).name for f in figures)}, indent=1))


def _remove_if_only_locks(folder: Path) -> None:
    """Remove ``folder`` when it holds nothing but nmmm's lock files (a comparison that failed)."""
    try:
        entries = list(folder.iterdir())
        if all(e.is_file() and e.name.endswith(".nmmm-lock") for e in entries):
            for e in entries:
                e.unlink()
            folder.rmdir()
    except OSError:
        pass


def _arg(path, placeholder: str) -> str:
    """A recipe argument as the user can retype it (a placeholder for recipes given as text)."""
    try:
        if isinstance(path, (str, Path)) and Path(str(path)).is_file():
            return str(path)
    except (OSError, ValueError):
        pass
    return placeholder


def recipe_names(res_a, res_b) -> tuple[str, str]:
    """The names the report calls the two recipes: their own names, told apart when equal
    (never "A" and "B", which read as illuminant A)."""
    na, nb = res_a.recipe.name, res_b.recipe.name
    if na == nb:
        return f"{na} (first recipe)", f"{nb} (second recipe)"
    return na, nb


def recipe_folders(name_a: str, name_b: str) -> tuple[str, str]:
    """The sub-folders ``nmmm compare`` writes the two runs into: the recipes' names made safe for a
    path (``Hematite paint (7 %)`` -> ``Hematite_paint_7``), ``_first``/``_second`` added when equal."""
    import re

    fa, fb = (_short(re.sub(r"[^A-Za-z0-9]+", "_", n).strip("_") or "recipe", n) for n in (name_a, name_b))
    if fa.lower() == fb.lower():
        return f"{fa}_first", f"{fb}_second"
    return fa, fb


#: longest run-folder name made from a recipe name (file systems allow 255 bytes)
MAX_FOLDER_NAME = 80


def _short(safe: str, name: str) -> str:
    """``safe`` cut to :data:`MAX_FOLDER_NAME` characters, a short hash of the full ``name`` added
    when cut (two long names that start alike still get different folders)."""
    if len(safe) <= MAX_FOLDER_NAME:
        return safe
    import hashlib

    return safe[:MAX_FOLDER_NAME - 9].rstrip("_") + "_" + hashlib.sha1(name.encode("utf-8")).hexdigest()[:8]


def _lab_text(L, a, b) -> str:
    return f"{L:.1f}, {a:.1f}, {b:.1f}"


def comparison_section(res_a, res_b, rows, figures=(), names=None) -> dict:
    """The comparison as a report section: one summary box per recipe (its swatch under the first
    illuminant, ΔE00 under each), the overlay and images, and the ΔE00 table with the recipes'
    names in the headers (illuminants are written "illuminant A", recipes by name)."""
    from nmmm.recipes.report import lab_value, srgb_note

    na, nb = names or recipe_names(res_a, res_b)
    head = rows[0]
    main = [r for r in rows if r["geometry"] == head["geometry"]]
    text = [f"CIEDE2000 between the {res_a.primary!r} spectrum of {na} and the {res_b.primary!r} spectrum of {nb}: "
            + ", ".join(f"ΔE00 = {r['dE00']:.2f} under illuminant {r['illuminant']}" for r in main)
            + ". ΔE00 ≈ 1 is a just-noticeable difference side by side; above ≈ 2–3 the substitution is visible."]
    ill0 = main[0]["illuminant"]
    boxes = []
    for name, res in ((na, res_a), (nb, res_b)):
        c = next((c for c in res.colours if c["spectrum"] == res.primary and c["illuminant"] == ill0),
                 next((c for c in res.colours if c["spectrum"] == res.primary), None))
        if c is None:
            continue
        box = {"heading": name, "swatch": (f"{name} under illuminant {c['illuminant']}", c["srgb"], srgb_note(None, c["L"])),
               "items": [(f"CIELAB, illuminant {c['illuminant']}", lab_value(c['L'], c['a'], c['b']))]}
        boxes.append(box)
    if boxes:
        boxes[-1]["items"] += [(f"ΔE00 from the first, illuminant {r['illuminant']}", f"{r['dE00']:.2f}") for r in main]
    swatches = []
    for name, res in ((na, res_a), (nb, res_b)):
        swatches += [(f"{name} — illuminant {c['illuminant']}", c["srgb"], srgb_note(None, c["L"]))
                     for c in res.colours if c["spectrum"] == res.primary]
    table = [{"geometry": r["geometry"], "illuminant": f"illuminant {r['illuminant']}",
              f"{na}: L*, a*, b*": _lab_text(r["L_A"], r["a_A"], r["b_A"]),
              f"{nb}: L*, a*, b*": _lab_text(r["L_B"], r["a_B"], r["b_B"]), "dE00": r["dE00"]} for r in rows]
    return {"title": f"Substitution: {na} → {nb}", "text": text, "figures": list(figures), "summary_boxes": boxes,
            "tables": {"Colour differences (CIELAB in 1, ΔE00 in 1)": table}, "swatches": swatches}
