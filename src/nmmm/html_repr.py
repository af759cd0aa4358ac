"""Rich notebook display shared by the result objects of every floor (ground floor).

- :func:`figure_png_base64` — a small matplotlib figure of curves against wavelength, as a
  base64 PNG (Agg, no pyplot state: safe in worker processes and notebooks alike).
- :func:`result_html` — the HTML a ``_repr_html_`` returns: a title, a two-column table of
  (quantity, value) rows and an embedded ``<img>`` of the curves.

Jupyter calls ``obj._repr_html_()`` when a cell's value is displayed (IPython's rich display
protocol); :class:`nmmm.materials.Material`, :class:`nmmm.layers.mie_scattering.MieResult` and
:class:`nmmm.recipes.RunResult` return :func:`result_html` of their own quantities.
"""

from __future__ import annotations

import base64
import html
import io
from collections.abc import Iterable, Mapping, Sequence

import numpy as np

__all__ = ["figure_png_base64", "result_html"]


def figure_png_base64(x, curves: Mapping[str, np.ndarray], xlabel: str = "wavelength (nm)",
                      ylabel: str = "", title: str = "", size_in: tuple[float, float] = (5.0, 2.6)) -> str:
    """Base64 PNG of ``curves`` (label -> y on ``x``), one line each, 90 dpi."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size_in, dpi=90)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    x = np.asarray(x, float)
    for label, y in curves.items():
        ax.plot(x, np.asarray(y, float), lw=1.4, label=str(label))
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    if 1 < len(curves) <= 10:
        ax.legend(fontsize=7)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return base64.b64encode(buf.getvalue()).decode("ascii")


def result_html(title: str, rows: Iterable[tuple[str, object]], png_base64: str | None = None,
                tables: Mapping[str, Sequence[Mapping[str, object]]] | None = None) -> str:
    """``<div>`` with a heading, a table of ``rows`` and optionally an image and more tables
    (each a list of dicts with the same keys). Every text is HTML-escaped."""
    esc = html.escape
    parts = [f'<div class="nmmm-repr"><strong>{esc(title)}</strong>',
             '<table style="border-collapse:collapse;font-size:90%">']
    for k, v in rows:
        parts.append(f'<tr><th style="text-align:left;padding-right:1em">{esc(str(k))}</th>'
                     f'<td style="text-align:left">{esc(str(v))}</td></tr>')
    parts.append("</table>")
    for name, table in (tables or {}).items():
        table = list(table)
        if not table:
            continue
        cols = list(table[0])
        parts.append(f"<p><em>{esc(name)}</em></p>"
                     '<table style="border-collapse:collapse;font-size:85%"><tr>'
                     + "".join(f"<th>{esc(str(c))}</th>" for c in cols) + "</tr>")
        for r in table:
            parts.append("<tr>" + "".join(f"<td>{esc(_fmt(r.get(c)))}</td>" for c in cols) + "</tr>")
        parts.append("</table>")
    if png_base64:
        parts.append(f'<img alt="{esc(title)}" src="data:image/png;base64,{png_base64}"/>')
    parts.append("</div>")
    return "\n".join(parts)


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    return "" if v is None else str(v)
