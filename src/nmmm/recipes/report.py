"""Self-contained HTML reports: figures embedded as base64 PNG, recipes echoed, numbers with units.

- :func:`result_section` — a :class:`~nmmm.recipes.run.RunResult` -> a report section.
- :func:`hook_section` — the dict a package's demo hook returns
  (``{"title", "figures", "tables", "text"}``) -> a report section.
- :func:`error_section` — a section that shows an error box (a failed demo part).
- :func:`write_report` — sections -> one HTML file (no external resources).

A section is a dict: ``title``, ``text`` (paragraphs), ``figures`` (PNG paths),
``tables`` ({caption: rows (list of dicts) | dict | CSV path}), ``swatches``
([(label, [r, g, b])]), ``recipe`` (TOML text), ``error`` (message), ``elapsed_s``.
"""

from __future__ import annotations

import base64
import csv
import datetime as _dt
import html
from pathlib import Path

import numpy as np

__all__ = ["result_section", "hook_section", "error_section", "write_report", "COLUMN_UNITS"]

#: unit shown in a table header for each column name (columns not listed must carry their
#: unit in their own name, e.g. ``thickness_nm``)
COLUMN_UNITS = {
    "L": "L* (1)", "a": "a* (1)", "b": "b* (1)", "C": "C*ab (1)", "h_deg": "h_ab (°)",
    "aspecular_deg": "aspecular angle (°)", "illuminant": "illuminant", "spectrum": "spectrum",
    "dE00": "ΔE00 (1)", "delta_e2000": "ΔE00 (1)",
    "L_A": "L* A (1)", "a_A": "a* A (1)", "b_A": "b* A (1)", "L_B": "L* B (1)", "a_B": "a* B (1)", "b_B": "b* B (1)",
}

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222;line-height:1.45}
h1{border-bottom:2px solid #333;padding-bottom:.2em} h2{margin-top:2em;border-bottom:1px solid #bbb}
figure{display:inline-block;margin:.5em;vertical-align:top;max-width:100%} figure img{max-width:100%;border:1px solid #ddd}
figcaption{font-size:.8em;color:#555}
table{border-collapse:collapse;margin:.6em 0;font-size:.85em} td,th{border:1px solid #ccc;padding:.2em .5em;text-align:right}
th{background:#f2f2f2} td:first-child,th:first-child{text-align:left}
.error{border:2px solid #c00;background:#fee;padding:.8em;border-radius:4px;white-space:pre-wrap;font-family:monospace;font-size:.85em}
.ok{color:#060} .failed{color:#c00;font-weight:bold}
.swatch{display:inline-block;width:90px;margin:.3em;font-size:.72em;text-align:center;vertical-align:top}
.swatch div{height:50px;border:1px solid #999}
details pre,pre.texttable{background:#f7f7f7;padding:.6em;overflow:auto;font-size:.8em}
.meta{color:#666;font-size:.85em}
"""


def _img(path) -> str:
    p = Path(path)
    data = base64.b64encode(p.read_bytes()).decode("ascii")
    mime = "image/png" if p.suffix.lower() == ".png" else ("image/jpeg" if p.suffix.lower() in (".jpg", ".jpeg") else "image/svg+xml")
    return (f'<figure><img src="data:{mime};base64,{data}" alt="{html.escape(p.name)}">'
            f"<figcaption>{html.escape(p.name)}</figcaption></figure>")


def _fmt(v) -> str:
    if isinstance(v, str) and v.startswith("(") and v.endswith("j)"):  # a complex number read back from CSV
        try:
            v = complex(v)
        except ValueError:
            pass
    if isinstance(v, (complex, np.complexfloating)):
        v = complex(v)
        return f"{_fmt(v.real)} {'−' if v.imag < 0 else '+'} {_fmt(abs(v.imag))}i"
    if isinstance(v, (float, np.floating)):
        v = float(v)
        if v != 0 and (abs(v) >= 1e5 or abs(v) < 1e-3):
            return f"{v:.4g}"
        return f"{v:.4g}" if abs(v) >= 100 else f"{v:.3f}".rstrip("0").rstrip(".") if v != int(v) else f"{v:g}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    return html.escape(str(v))


def _header(col: str) -> str:
    return html.escape(COLUMN_UNITS.get(col, col))


def _table(caption, rows) -> str:
    if isinstance(rows, (str, Path)) and Path(rows).suffix.lower() == ".csv" and Path(rows).exists():
        with open(rows, newline="") as fh:
            rows = list(csv.DictReader(fh))
        if len(rows) > 40:
            caption = f"{caption} (first 40 of {len(rows)} rows; full CSV written beside the report)"
            rows = rows[:40]
    if isinstance(rows, dict) and rows and all(isinstance(v, (list, tuple, np.ndarray)) for v in rows.values()) \
            and len({len(v) for v in rows.values()}) == 1:  # columns -> rows
        rows = [dict(zip(rows, vals)) for vals in zip(*rows.values())]
    elif isinstance(rows, dict):
        rows = [{"quantity": k, "value": v} for k, v in rows.items()]
    if not isinstance(rows, list) or not rows or not isinstance(rows[0], dict):
        return f"<p><b>{html.escape(str(caption))}</b>: {_fmt(rows)}</p>"
    cols = list(rows[0])
    out = [f"<table><caption style='text-align:left'><b>{html.escape(str(caption))}</b></caption><tr>"]
    out += [f"<th>{_header(c)}</th>" for c in cols] + ["</tr>"]
    for r in rows:
        out.append("<tr>" + "".join(f"<td>{_fmt(r.get(c, ''))}</td>" for c in cols) + "</tr>")
    out.append("</table>")
    return "".join(out)


def _swatches(items) -> str:
    out = []
    for label, rgb in items:
        r, g, b = (int(round(255 * min(max(float(v), 0), 1))) for v in rgb)
        out.append(f"<div class='swatch'><div style='background:rgb({r},{g},{b})'></div>{html.escape(label)}</div>")
    return "<div>" + "".join(out) + "</div>"


def _section_html(s: dict, idx: int) -> str:
    parts = [f"<section id='s{idx}'><h2>{html.escape(s.get('title', 'section'))}"]
    if s.get("error"):
        parts.append(" <span class='failed'>(failed)</span>")
    parts.append("</h2>")
    if s.get("elapsed_s") is not None:
        parts.append(f"<p class='meta'>computed in {s['elapsed_s']:.1f} s</p>")
    if s.get("error"):
        parts.append(f"<div class='error'>{html.escape(str(s['error']))}</div>")
    for para in ([s["text"]] if isinstance(s.get("text"), str) else s.get("text") or []):
        for p in str(para).split("\n\n"):
            if not p.strip():
                continue
            lines = p.strip("\n").splitlines()
            if len(lines) > 1 and any("  " in ln.strip() for ln in lines):  # a text table: keep its columns
                parts.append(f"<pre class='texttable'>{html.escape(p.strip(chr(10)))}</pre>")
            else:
                parts.append(f"<p>{html.escape(p.strip())}</p>")
    if s.get("swatches"):
        parts.append(_swatches(s["swatches"]))
    for f in s.get("figures") or []:
        if Path(f).exists() and Path(f).suffix.lower() in (".png", ".jpg", ".jpeg", ".svg"):
            parts.append(_img(f))
    for cap, rows in (s.get("tables") or {}).items():
        parts.append(_table(cap, rows))
    if s.get("recipe"):
        parts.append(f"<details><summary>Recipe (TOML)</summary><pre>{html.escape(s['recipe'])}</pre></details>")
    if s.get("files"):
        parts.append("<details><summary>Files written</summary><ul>" +
                     "".join(f"<li>{html.escape(k)}: <code>{html.escape(str(v))}</code></li>" for k, v in s["files"].items())
                     + "</ul></details>")
    parts.append("</section>")
    return "".join(parts)


def write_report(sections, path, title: str = "nmmm report", intro: str = "") -> Path:
    """Write ``sections`` (dicts, see the module docstring) into one self-contained HTML file."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    failed = [s.get("title", "?") for s in sections if s.get("error")]
    toc = "".join(f"<li><a href='#s{i}'>{html.escape(s.get('title', '?'))}</a>"
                  + (" <span class='failed'>failed</span>" if s.get("error") else "") + "</li>"
                  for i, s in enumerate(sections))
    try:
        from importlib.metadata import version

        ver = version("nmmm")
    except Exception:  # pragma: no cover
        ver = "?"
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    body = [f"<h1>{html.escape(title)}</h1>",
            f"<p class='meta'>nmmm {html.escape(ver)} — generated {now}. Wavelengths in nm, lengths in nm "
            "unless stated, angles in degrees, volume fractions in [0, 1]; reflectance, transmittance and "
            "CIELAB values are dimensionless (1).</p>"]
    if intro:
        body.append(f"<p>{html.escape(intro)}</p>")
    if failed:
        body.append(f"<div class='error'>{len(failed)} section(s) failed: {html.escape(', '.join(failed))}</div>")
    if len(sections) > 1:
        body.append(f"<ol>{toc}</ol>")
    body += [_section_html(s, i) for i, s in enumerate(sections)]
    doc = (f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
           f"<style>{_CSS}</style></head><body>{''.join(body)}</body></html>")
    path.write_text(doc, encoding="utf-8")
    return path


def _scalar_label(key: str, primary: str) -> str:
    """A readable name with its unit for a key of :attr:`RunResult.scalars`."""
    if key[:2] in ("L_", "a_", "b_"):
        return f"{key[0]}* of {primary}, {key[2:]} (1)"
    if key == "mean_primary":
        return f"mean of {primary} over wavelength (1)"
    if key == "flop_index":
        return "flop index, Alman 1987 (1)"
    for suffix, unit in (("_nm", "nm"), ("_deg", "°"), ("_s", "s")):
        if key.endswith(suffix):
            return f"{key[:-len(suffix)].replace('_', ' ')} ({unit})"
    return key


def result_section(res, title: str | None = None) -> dict:
    """A report section from a :class:`~nmmm.recipes.run.RunResult` (after ``write_outputs``)."""
    r = res.recipe
    figs = [v for k, v in res.files.items() if k.endswith("plot") or k == "stereo pair"
            or (k.startswith("image") and "stereo pair" not in res.files)]
    colours = [{"spectrum": c["spectrum"], "illuminant": c["illuminant"], "L": c["L"], "a": c["a"], "b": c["b"],
                "C": c["C"], "h_deg": c["h_deg"]} for c in res.colours]
    tables = {f"CIELAB (CIE 1931 2° observer)" if r.lighting.observer == "2" else "CIELAB (CIE 1964 10° observer)": colours}
    if res.multiangle:
        tables["Multi-angle colour"] = res.multiangle
    if res.scalars:
        tables["Summary numbers"] = {_scalar_label(k, res.primary): v for k, v in res.scalars.items()}
    tables["Timings (s)"] = {f"{k} (s)": round(float(v), 3) for k, v in res.timings_s.items()}
    sw = [(f"{c['spectrum']} / {c['illuminant']}", c["srgb"]) for c in res.colours]
    text = [r.description] if r.description else []
    text += res.notes
    return {"title": title or r.name, "text": text, "figures": figs, "tables": tables, "swatches": sw,
            "recipe": res.recipe_text, "files": res.files, "elapsed_s": sum(res.timings_s.values())}


def hook_section(summary: dict, elapsed_s: float | None = None) -> dict:
    """A report section from a package demo hook's returned dict."""
    tables = {}
    for k, v in (summary.get("tables") or {}).items():
        tables[k] = v
    return {"title": summary.get("title", "demo"), "text": summary.get("text", ""),
            "figures": [str(f) for f in summary.get("figures") or []], "tables": tables, "elapsed_s": elapsed_s}


def error_section(title: str, message: str, elapsed_s: float | None = None) -> dict:
    """A section showing an error box (the rest of the report is unaffected)."""
    return {"title": title, "error": message, "elapsed_s": elapsed_s}
