"""Self-contained HTML reports laid out for reading and printing (jinja2 templates in
``nmmm/recipes/templates``): figures embedded compressed, recipes echoed, numbers with units.

- :func:`result_section` — a :class:`~nmmm.recipes.run.RunResult` -> a report section, with a
  summary box first (the colour as a large swatch under the main illuminant, CIELAB, hiding and
  contrast ratio where the run has them, the plate image), sanity warnings, the plots, then the
  tables (long ones folded), and what to run next.
- :func:`hook_section` — the dict a package's demo hook returns
  (``{"title", "figures", "tables", "text"}``) -> a report section.
- :func:`error_section` — a section that shows an error box (a failed demo part).
- :func:`write_report` — sections -> one HTML file (no external resources), fitting a
  1200–1400 px window and an A4 page (a print stylesheet).
- :func:`srgb_note` — the words shown next to a swatch whose colour the display cannot show
  (outside the sRGB gamut, or a reflectance factor above 1: L* > 100).

A section is a dict: ``title``, ``text`` (paragraphs; a paragraph of aligned columns is kept as
a text table), ``figures`` (image paths), ``tables`` ({caption: rows (list of dicts) | dict |
CSV path}), ``swatches`` ([(label, [r, g, b]) or (label, [r, g, b], note)]), ``summary_boxes``
([{"swatch": (label, rgb, note), "items": [(name, value)], "image": path, "heading": str}]),
``summary`` (numbers of a paint system: keys among ``contrast_ratio``, ``hiding_thickness_um``,
``spreading_rate_m2_per_L``, ``masstone_lab``, ``geometry``; shown in the first summary box),
``warnings`` (sentences), ``next`` ([(what, command)]), ``recipe`` (TOML text), ``files``,
``error`` (message), ``elapsed_s``.
"""

from __future__ import annotations

import csv
import datetime as _dt
from pathlib import Path

import numpy as np

__all__ = ["result_section", "hook_section", "error_section", "write_report", "srgb_note", "next_steps",
           "column_header", "COLUMN_UNITS"]

#: unit shown in a table header for each column name (other names are read by
#: :func:`column_header`: ``L_D65`` -> "L* under D65", ``thickness_nm`` -> "thickness (nm)")
COLUMN_UNITS = {
    "L": "L* (1)", "a": "a* (1)", "b": "b* (1)", "C": "C*ab (1)", "h_deg": "h_ab (°)",
    "aspecular_deg": "aspecular angle (°)", "illuminant": "illuminant", "spectrum": "spectrum",
    "dE00": "ΔE00 (1)", "delta_e2000": "ΔE00 (1)",
}

#: tables longer than this are folded behind a "details" toggle
FOLD_ROWS = 12
#: rows of a CSV table shown in the report (the whole file is beside it)
CSV_ROWS = 40

_CONVENTIONS = ("Wavelengths in nm; lengths in nm unless the name says otherwise (film and coat thicknesses "
                "also in µm); angles in degrees; volume fractions in [0, 1]; reflectance, transmittance and "
                "CIELAB values are dimensionless (1); colours for the CIE observer each table names.")

#: words of the numbers a paint system's summary carries (helper F's ``section["summary"]``)
_SUMMARY_WORDS = {
    "contrast_ratio": "contrast ratio (over black / over white)",
    "hiding_thickness_um": "hiding thickness (CR = 0.98)",
    "spreading_rate_m2_per_L": "spreading rate at hiding",
    "masstone_lab": "masstone CIELAB",
    "geometry": "measurement geometry",
}


# --------------------------------------------------------------------------------------
# formatting


def _fmt(v) -> str:
    """A number as a reader wants it (4 significant digits, complex as a ± bi); plain text."""
    if isinstance(v, str) and v.startswith("(") and v.endswith("j)"):  # a complex number read back from CSV
        try:
            v = complex(v)
        except ValueError:
            pass
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (complex, np.complexfloating)):
        v = complex(v)
        return f"{_fmt(v.real)} {'−' if v.imag < 0 else '+'} {_fmt(abs(v.imag))}i"
    if isinstance(v, (float, np.floating)):
        v = float(v)
        if not np.isfinite(v):
            return str(v)
        if v != 0 and (abs(v) >= 1e5 or abs(v) < 1e-3):
            return f"{v:.4g}"
        return f"{v:.4g}" if abs(v) >= 100 else f"{v:.3f}".rstrip("0").rstrip(".") if v != int(v) else f"{v:g}"
    if isinstance(v, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    return str(v)


def column_header(col: str) -> str:
    """The header of a table column: :data:`COLUMN_UNITS`, else the name in words with the unit
    of its suffix (``L_D65`` -> "L* under D65", ``hiding_thickness_um`` -> "hiding thickness (µm)")."""
    col = str(col)
    if col in COLUMN_UNITS:
        return COLUMN_UNITS[col]
    if col[:2] in ("L_", "a_", "b_") and col[2:] and col[2:].replace("_", "").isalnum() and len(col) <= 12:
        return f"{col[0]}* under {col[2:]}"
    from nmmm.recipes.figures import _SUFFIX_UNITS

    for suffix, unit in _SUFFIX_UNITS:
        if col.endswith(suffix) and len(col) > len(suffix):
            return f"{col[:-len(suffix)].replace('_', ' ')} ({unit})"
    return col.replace("_", " ") if "_" in col and " " not in col else col


def _normalise_table(caption, rows) -> dict:
    note = ""
    if isinstance(rows, (str, Path)) and Path(rows).suffix.lower() == ".csv" and Path(rows).exists():
        path = Path(rows)
        with open(path, newline="") as fh:
            rows = list(csv.DictReader(fh))
        if len(rows) > CSV_ROWS:
            note = f"first {CSV_ROWS} of {len(rows)} rows; all in {path.name}"
            rows = rows[:CSV_ROWS]
    if isinstance(rows, dict) and rows and all(isinstance(v, (list, tuple, np.ndarray)) for v in rows.values()) \
            and len({len(v) for v in rows.values()}) == 1:  # columns -> rows
        rows = [dict(zip(rows, vals)) for vals in zip(*rows.values())]
    elif isinstance(rows, dict):
        rows = [{"quantity": k, "value": v} for k, v in rows.items()]
    if not isinstance(rows, list) or not rows or not isinstance(rows[0], dict):
        return {"caption": str(caption), "scalar": _fmt(rows)}
    cols = list(dict.fromkeys(c for r in rows for c in r))
    return {"caption": str(caption), "headers": [column_header(c) for c in cols],
            "rows": [[_fmt(r.get(c, "")) for c in cols] for r in rows], "folded": len(rows) > FOLD_ROWS, "note": note}


def _css_rgb(rgb) -> str:
    r, g, b = (int(round(255 * min(max(float(v), 0.0), 1.0))) for v in rgb)
    return f"rgb({r},{g},{b})"


def lab_value(L: float, a: float, b: float) -> str:
    """CIELAB as a summary box shows it, ``L* 24.8   a* 20.6   b* 18.8``: each name kept with its
    number by a no-break space, so a narrow box wraps between the pairs, never inside one."""
    return "   ".join(f"{q}\u00a0{v:.1f}" for q, v in (("L*", L), ("a*", a), ("b*", b)))


def srgb_note(rgb_unclipped=None, L=None) -> str:
    """Words for a swatch the display cannot show as computed: "" when it can.

    ``L`` > 100 (a reflectance factor above 1, e.g. flakes near the specular direction) reads
    "brighter than white (L* = 140): shown clipped"; an sRGB value outside [0, 1] reads "outside
    the sRGB gamut: shown clipped"."""
    if L is not None and float(L) > 100.0:
        return f"brighter than white (L* = {float(L):.0f}): shown clipped"
    if rgb_unclipped is not None:
        v = np.asarray(rgb_unclipped, float)
        tol = 0.5 / 255
        if np.any(v < -tol) or np.any(v > 1 + tol):
            return "outside the sRGB gamut: shown clipped"
    return ""


def _swatch(item) -> dict:
    label, rgb, note = (tuple(item) + ("",))[:3]
    return {"label": str(label), "css": _css_rgb(rgb), "gamut": note or ""}


def _figure(path) -> dict | None:
    from nmmm.recipes.figures import embed_image

    p = Path(path)
    if not p.exists() or p.suffix.lower() not in (".png", ".jpg", ".jpeg", ".svg"):
        return None
    uri, w, h = embed_image(p)
    return {"uri": uri, "name": p.name, "width": w, "height": h}


def _split_text(text) -> tuple[list[str], list[dict]]:
    """Paragraphs, and paragraphs of aligned columns kept as text tables (long ones folded)."""
    paras, pres = [], []
    for para in ([text] if isinstance(text, str) else text or []):
        for p in str(para).split("\n\n"):
            if not p.strip():
                continue
            lines = p.strip("\n").splitlines()
            if len(lines) > 1 and any("  " in ln.strip() for ln in lines):
                body = p.strip("\n")
                pres.append({"text": body, "folded": len(lines) > FOLD_ROWS + 1,
                             "caption": f"{lines[0].strip()[:80]} … ({len(lines)} lines)"})
            else:
                paras.append(p.strip())
    return paras, pres


def _box(box: dict, summary: dict | None) -> dict:
    out = {"heading": box.get("heading", ""), "lines": [(str(k), str(v)) for k, v in box.get("items", [])],
           "swatch": _swatch(box["swatch"]) if box.get("swatch") else None, "image": None}
    for k, v in (summary or {}).items():
        out["lines"].append((_SUMMARY_WORDS.get(k, column_header(k)), _summary_value(k, v)))
    img = box.get("image")
    if img:
        fig = _figure(img)
        if fig:
            out["image"] = dict(fig, caption=box.get("image_caption", Path(img).name))
    return out


def _summary_value(key: str, v) -> str:
    if key == "contrast_ratio":
        return f"{float(v):.3f} ({100 * float(v):.1f} %)"
    if key == "hiding_thickness_um":
        return "not reached in the range computed" if v is None or not np.isfinite(float(v)) else f"{float(v):.1f} µm"
    if key == "spreading_rate_m2_per_L":
        return f"{float(v):.1f} m²/L"
    if key == "masstone_lab":
        L, a, b = (float(x) for x in v)
        return f"L* {L:.1f}, a* {a:.1f}, b* {b:.1f}"
    return _fmt(v)


def _prepare(s: dict) -> dict:
    paras, pres = _split_text(s.get("text"))
    boxes = [_box(b, s.get("summary") if i == 0 else None) for i, b in enumerate(s.get("summary_boxes") or [])]
    if not boxes and s.get("summary"):
        boxes = [_box({}, s["summary"])]
    return {"title": s.get("title", "section"), "error": s.get("error"), "elapsed_s": s.get("elapsed_s"),
            "boxes": boxes, "warnings": list(s.get("warnings") or []), "paragraphs": paras, "pres": pres,
            "swatches": [_swatch(x) for x in s.get("swatches") or []],
            "figures": [f for f in (_figure(p) for p in s.get("figures") or [] if p) if f],
            "tables": [_normalise_table(c, r) for c, r in (s.get("tables") or {}).items()],
            "recipe": s.get("recipe"), "files": {str(k): str(v) for k, v in (s.get("files") or {}).items()},
            "next": [(str(a), str(b)) for a, b in s.get("next") or _files_next(s)]}


def _files_next(s: dict) -> list:
    """Default "what next" of a run's section: from the recipe copy it wrote (final paths)."""
    rec = (s.get("files") or {}).get("recipe")
    if not rec or s.get("error"):
        return []
    return next_steps(rec, out_dir=str(Path(rec).parent))


def _environment():
    import jinja2

    return jinja2.Environment(loader=jinja2.PackageLoader("nmmm.recipes", "templates"),
                              autoescape=True, trim_blocks=True, lstrip_blocks=True)


def write_report(sections, path, title: str = "nmmm report", intro: str = "", next_steps=None) -> Path:
    """Write ``sections`` (dicts, see the module docstring) into one self-contained HTML file.

    ``next_steps``: ``[(what, command)]`` listed at the end ("what next")."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        from importlib.metadata import version

        ver = version("nmmm")
    except Exception:  # pragma: no cover
        ver = "?"
    env = _environment()
    css = env.loader.get_source(env, "report.css")[0]
    doc = env.get_template("report.html.j2").render(
        title=title, css=css, version=ver, now=_dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        conventions=_CONVENTIONS, intro=[p for p in str(intro or "").split("\n\n") if p.strip()],
        failed=[s.get("title", "?") for s in sections if s.get("error")],
        sections=[_prepare(s) for s in sections], outro=[(str(a), str(b)) for a, b in next_steps or []])
    path.write_text(doc, encoding="utf-8")
    return path


# --------------------------------------------------------------------------------------
# sections


def _scalar_label(key: str, primary: str) -> str:
    """A readable name with its unit for a key of :attr:`RunResult.scalars`."""
    if key[:2] in ("L_", "a_", "b_"):
        return f"{key[0]}* of {primary}, {key[2:]} (1)"
    if key == "mean_primary":
        return f"mean of {primary} over wavelength (1)"
    if key == "flop_index":
        return "flop index, Alman 1987 (1)"
    for suffix, unit in (("_nm", "nm"), ("_um", "µm"), ("_deg", "°"), ("_s", "s"), ("_m2_per_L", "m²/L")):
        if key.endswith(suffix):
            return f"{key[:-len(suffix)].replace('_', ' ')} ({unit})"
    return key


def _unclipped_srgb(res, row):
    """The sRGB of a colour row before clipping (None when its spectrum is not kept)."""
    from nmmm.colour import spectra_to_xyz, white_point, xyz_to_srgb

    spec = res.spectra.get(row["spectrum"])
    if spec is None:
        return None
    try:
        obs = res.recipe.lighting.observer
        xyz = spectra_to_xyz(res.wavelength_nm, np.clip(spec, 0, None), row["illuminant"], obs)
        return np.asarray(xyz_to_srgb(xyz, white_point(res.wavelength_nm, row["illuminant"], obs), clip=False))
    except Exception:  # noqa: BLE001 - the mark is a courtesy; never lose the report over it
        return None


def _main_image(res):
    """The plate image of the summary box (the left eye of a stereo pair) and its caption."""
    for key in ("image view", "image left eye"):
        if key in res.files:
            return res.files[key], key.replace("image ", "image: ") + (" (the pair is below)" if "stereo pair" in res.files else "")
    img = next((v for k, v in res.files.items() if k.startswith("image") and not k.startswith("image right")), None)
    return img, "image"


def _paint_summary(res) -> dict:
    """Contrast ratio, hiding and masstone numbers of a run, where it computed them."""
    out = dict(getattr(res, "summary", None) or {})
    for k, v in res.scalars.items():
        for key in _SUMMARY_WORDS:
            if key not in out and k == key:
                out[key] = v
    return out


def result_section(res, title: str | None = None, source: str | None = None, command: str | None = None) -> dict:
    """A report section from a :class:`~nmmm.recipes.run.RunResult` (after ``write_outputs``).

    ``source``: the recipe file to start from (default: the copy the run wrote);
    ``command``: the command that reproduces the section (default: ``nmmm run SOURCE -o FOLDER``)."""
    from nmmm.recipes.sanity import sanity_warnings

    r = res.recipe
    obs = r.lighting.observer
    figs = [v for k, v in res.files.items() if k.endswith("plot") or k == "stereo pair"]
    colours = [{"spectrum": c["spectrum"], "illuminant": c["illuminant"], "L": c["L"], "a": c["a"], "b": c["b"],
                "C": c["C"], "h_deg": c["h_deg"]} for c in res.colours]
    tables = {"CIELAB (CIE 1931 2° observer)" if obs == "2" else "CIELAB (CIE 1964 10° observer)": colours}
    if res.multiangle:
        tables["Multi-angle colour"] = res.multiangle
    if res.scalars:
        tables["Summary numbers"] = {_scalar_label(k, res.primary): v for k, v in res.scalars.items()}
    tables["Timings (s)"] = {f"{k} (s)": round(float(v), 3) for k, v in res.timings_s.items()}
    sw, main = [], None
    for c in res.colours:
        note = srgb_note(_unclipped_srgb(res, c), c["L"])
        sw.append((f"{c['spectrum']} — illuminant {c['illuminant']}", c["srgb"], note))
        if main is None and c["spectrum"] == res.primary:
            main = (c, note)
    box = {}
    if main is not None:
        c, note = main
        box["swatch"] = (f"{c['spectrum']} under illuminant {c['illuminant']} (CIE {obs}° observer)", c["srgb"], note)
        box["heading"] = r.name
        items = [(f"CIELAB, illuminant {c['illuminant']}", lab_value(c['L'], c['a'], c['b'])),
                 ("chroma, hue", f"C*ab {c['C']:.1f}, h {c['h_deg']:.0f}°")]
        for o in res.colours:
            if o["spectrum"] == res.primary and o["illuminant"] != c["illuminant"]:
                items.append((f"CIELAB, illuminant {o['illuminant']}", lab_value(o['L'], o['a'], o['b'])))
        if "flop_index" in res.scalars:
            items.append(("flop index (Alman 1987)", f"{res.scalars['flop_index']:.1f}"))
        box["items"] = items
    img, cap = _main_image(res)
    if img:
        box["image"], box["image_caption"] = img, cap
    warnings_ = sanity_warnings(r) + list(getattr(res, "warnings", None) or [])
    bright = [m for m in res.multiangle if m["L"] > 100]
    if bright:
        warnings_.append("L* above 100 at aspecular " + ", ".join(f"{m['aspecular_deg']:g}°" for m in bright)
                         + f" (up to {max(m['L'] for m in bright):.0f}): near the specular direction the flakes reflect "
                         "more than a white diffuser (reflectance factor above 1). The display cannot show it; those "
                         "swatches are clipped to white.")
    text = [r.description] if r.description else []
    text += res.notes
    sec = {"title": title or r.name, "text": text, "figures": figs, "tables": tables, "swatches": sw,
           "summary_boxes": [box] if box else [], "summary": _paint_summary(res), "warnings": warnings_,
           "recipe": res.recipe_text, "files": dict(res.files), "elapsed_s": sum(res.timings_s.values())}
    if source or command:
        sec["next"] = next_steps(source or res.files.get("recipe", "recipe.toml"), command=command)
    return sec


def next_steps(recipe_file, out_dir=None, command: str | None = None) -> list[tuple[str, str]]:
    """The "what next" of a recipe's section: the command that reproduces it, the file to start
    from, and the comparison that shows what one change does."""
    out = out_dir or f"out-{Path(str(recipe_file)).stem}"
    return [("reproduce this section", command or f"nmmm run {recipe_file} -o {out}"),
            ("start your own recipe from this one", f"cp {recipe_file} my_recipe.toml"),
            ("change one thing in it and see the difference", f"nmmm compare {recipe_file} my_recipe.toml -o compare-out")]


def hook_section(summary: dict, elapsed_s: float | None = None) -> dict:
    """A report section from a package demo hook's returned dict."""
    tables = {}
    for k, v in (summary.get("tables") or {}).items():
        tables[k] = v
    return {"title": summary.get("title", "demo"), "text": summary.get("text", ""),
            "figures": [str(f) for f in summary.get("figures") or []], "tables": tables, "elapsed_s": elapsed_s,
            "warnings": list(summary.get("warnings") or []), "next": list(summary.get("next") or [])}


def error_section(title: str, message: str, elapsed_s: float | None = None) -> dict:
    """A section showing an error box (the rest of the report is unaffected)."""
    return {"title": title, "error": message, "elapsed_s": elapsed_s}
