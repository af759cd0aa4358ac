"""Figures of the reports: axis labels checked on the figure object, curves told apart, legends
in words, images compressed for embedding.

- :func:`missing_axis_labels` — what a figure lacks: an axis without a label, or a label
  without a unit (``"wavelength (nm)"``, ``"L* (1)"``, ``"n [1]"``); empty when complete.
- :func:`save_figure` — lay out, check the labels (a :class:`MissingAxisLabelWarning` naming the
  axes), save as PNG and close; every plot path of :mod:`nmmm.recipes` goes through it.
- :func:`audit_axis_labels` — a context manager that records the check for every figure saved
  while it is active (``Figure.savefig`` and ``plt.savefig``, whoever calls them): the test of the
  demo report uses it to see the figures of every section.
- :func:`curve_styles` — a colour and line style per curve, distinct for any number of curves
  (ten colours, then the next line style).
- :func:`quantity_label` / :func:`legend_label` — ``pigment.fraction`` -> "pigment volume
  fraction (1)"; ``("pigment.fraction", 0.05)`` -> "pigment volume fraction = 0.05".
- :func:`embed_image` — an image file as a compact data URI: plots as palette PNG, photographs
  and renders as JPEG, wide images scaled to the report's width.
"""

from __future__ import annotations

import base64
import io
import re
import warnings
from contextlib import contextmanager
from pathlib import Path

__all__ = ["missing_axis_labels", "save_figure", "audit_axis_labels", "MissingAxisLabelWarning", "curve_styles",
           "quantity_label", "legend_label", "embed_image"]

_UNIT = re.compile(r"\([^()]*\)\s*$|\[[^\[\]]*\]\s*$|\([^()]+\)|/\s*\S+")


class MissingAxisLabelWarning(UserWarning):
    """A figure is saved with an axis that has no label, or a label without a unit."""


def _axis_shows_ticks(axis) -> bool:
    if not axis.get_visible():
        return False
    try:
        labels = axis.get_ticklabels()
    except Exception:  # noqa: BLE001 - a custom axis: assume it shows ticks
        return True
    return any(t.get_visible() for t in labels) and len(axis.get_ticklocs()) > 0


def _categorical(axis) -> bool:
    """An axis whose ticks are words (``set_xticklabels``, categorical data), not numbers."""
    from matplotlib.category import StrCategoryFormatter
    from matplotlib.ticker import FixedFormatter

    fmt = axis.get_major_formatter()
    if isinstance(fmt, (FixedFormatter, StrCategoryFormatter)):
        return True
    locs = list(axis.get_ticklocs())
    try:
        fmt.set_locs(locs)
        texts = [str(fmt(x, i)) for i, x in enumerate(locs)]
    except Exception:  # noqa: BLE001 - a formatter that cannot say: treat as numbers
        return False
    words = [re.sub(r"\$[^$]*\$", "", s) for s in texts]  # drop mathtext numbers (10^-8)
    return any(re.search(r"[A-Za-df-zµ%]", w) for w in words)


def missing_axis_labels(fig) -> list[str]:
    """Descriptions of the axes of ``fig`` that show tick labels but no axis label, or a label
    without a unit in parentheses or brackets (``(1)`` for a dimensionless quantity). Axes turned
    off (images), axes without tick labels (shared ones, swatches), axes whose ticks are words
    (categories) and 3-D axes' z are not checked."""
    out = []
    for i, ax in enumerate(fig.axes):
        if not ax.axison:
            continue
        name = ax.get_title() or ax.get_label() or f"axes {i}"
        cbar = getattr(ax, "_colorbar", None)
        axes = (("x", ax.xaxis), ("y", ax.yaxis))
        if cbar is not None:  # a colour bar: its long axis carries the label
            axes = (("colour bar", ax.yaxis if cbar.orientation == "vertical" else ax.xaxis),)
        for which, axis in axes:
            if not _axis_shows_ticks(axis):
                continue
            text = axis.get_label_text().strip()
            if _categorical(axis):  # named ticks (swatch rows, observers): they say what they are
                continue
            if not text:
                out.append(f"{name}: no {which} label")
            elif not _UNIT.search(text):
                out.append(f"{name}: {which} label {text!r} has no unit (write e.g. 'wavelength (nm)' or 'L* (1)')")
    return out


def save_figure(fig, path, dpi: int = 110):
    """Lay out, check (see :func:`missing_axis_labels`), save and close ``fig``; returns ``path``."""
    import matplotlib.pyplot as plt

    missing = missing_axis_labels(fig)
    if missing:
        warnings.warn(f"{Path(path).name}: " + "; ".join(missing), MissingAxisLabelWarning, stacklevel=2)
    if fig.get_layout_engine() is None:
        try:
            fig.tight_layout()
        except Exception:  # noqa: BLE001 - a layout that cannot be tightened is still saved
            pass
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


@contextmanager
def audit_axis_labels():
    """Record ``(file name, missing labels)`` for every figure saved inside the block.

    >>> with audit_axis_labels() as saved:   # doctest: +SKIP
    ...     run_demo(...)
    >>> [s for s in saved if s[1]]           # doctest: +SKIP
    []
    """
    from matplotlib.figure import Figure

    saved: list[tuple[str, list[str]]] = []
    original = Figure.savefig

    def savefig(self, fname, *args, **kwargs):
        saved.append((str(getattr(fname, "name", fname)), missing_axis_labels(self)))
        return original(self, fname, *args, **kwargs)

    Figure.savefig = savefig
    try:
        yield saved
    finally:
        Figure.savefig = original


def curve_styles(n: int) -> list[dict]:
    """``n`` keyword dicts (``color``, ``linestyle``) for ``ax.plot``: the ten colours of
    matplotlib's tab10 first with solid lines, then again dashed, dotted, dash-dotted — so no two
    curves look the same up to 40 curves."""
    import matplotlib

    colours = matplotlib.colormaps["tab10"].colors
    styles = ("-", "--", ":", "-.")
    return [{"color": colours[i % 10], "linestyle": styles[(i // 10) % len(styles)]} for i in range(n)]


#: words for the recipe keys a formulator sweeps (unit from the key's suffix)
QUANTITY_WORDS = {
    "pigment.fraction": "pigment volume fraction",
    "pigment.dependent_scattering": "dependent scattering (Percus–Yevick packing)",
    "pigment.body_diagonal_nm": "pigment body diagonal",
    "pigment.diameter_nm": "pigment diameter",
    "pigment.size_spread": "pigment size spread (geometric)",
    "film.thickness_nm": "film thickness",
    "film.clear_coat_nm": "clear coat thickness",
    "film.substrate_reflectance": "substrate reflectance",
    "effect.optical_depth": "flake optical depth",
    "effect.tilt_deg": "flake tilt spread σ",
    "effect.tio2_thickness_nm": "TiO2 layer thickness",
}
_SUFFIX_UNITS = (("_m2_per_L", "m²/L"), ("_nm", "nm"), ("_um", "µm"), ("_mm", "mm"), ("_cm", "cm"), ("_deg", "°"),
                 ("_ev", "eV"), ("_pct", "%"), ("_s", "s"))


def _split_unit(key: str) -> tuple[str, str]:
    for suffix, unit in _SUFFIX_UNITS:
        if key.endswith(suffix):
            return key[: -len(suffix)], unit
    return key, "1" if key.endswith(("fraction", "reflectance", "spread", "depth", "ratio")) else ""


def quantity_label(key: str) -> str:
    """An axis label in words with its unit: ``pigment.body_diagonal_nm`` -> "pigment body
    diagonal (nm)", ``L_D65`` -> "L* under D65 (1)", ``pigment.fraction`` -> "pigment volume
    fraction (1)"."""
    if key.startswith("param:"):
        key = key[6:]
    if key[:2] in ("L_", "a_", "b_") and "." not in key:
        return f"{key[0]}* under {key[2:]} (1)"
    base, unit = _split_unit(key)
    words = QUANTITY_WORDS.get(key) or base.replace(".", " ").replace("_", " ")
    if key in QUANTITY_WORDS and "(" in words:
        return words
    return f"{words} ({unit})" if unit else words


def legend_label(key: str, value) -> str:
    """A legend entry in words with the unit: ``("pigment.fraction", 0.05)`` -> "pigment volume
    fraction = 0.05"; ``("film.thickness_nm", 20000)`` -> "film thickness = 20 µm"; booleans
    read on/off."""
    if key.startswith("param:"):
        key = key[6:]
    base, unit = _split_unit(key)
    words = QUANTITY_WORDS.get(key) or base.replace(".", " ").replace("_", " ")
    if isinstance(value, (bool,)) or type(value).__name__ == "bool_":
        return f"{words}: {'on' if value else 'off'}"
    try:
        v = float(value)
    except (TypeError, ValueError):
        return f"{words} = {value}"
    if unit == "nm" and abs(v) >= 10000:
        v, unit = v / 1000.0, "µm"
    if unit == "1" and key.endswith("fraction"):
        return f"{words} = {v:g} ({v * 100:g} %)"
    return f"{words} = {v:g}" + (f" {unit}" if unit and unit != "1" else "")


def _is_photograph(img) -> bool:
    """Many distinct colours (a render, a photograph, a micrograph) rather than a plot's few."""
    small = img.convert("RGB").copy()
    small.thumbnail((160, 160))
    colours = small.getcolors(maxcolors=160 * 160)
    return colours is None or len(colours) > 2500


def embed_image(path, max_width_px: int = 1240) -> tuple[str, int, int]:
    """``(data URI, width, height)`` of an image file, re-encoded smaller: plots as 256-colour PNG,
    photographs/renders as JPEG (quality 85); wider images scaled to ``max_width_px``. SVG files
    are embedded as they are; the original bytes are kept when they are already the smallest."""
    p = Path(path)
    raw = p.read_bytes()
    if p.suffix.lower() == ".svg":
        return "data:image/svg+xml;base64," + base64.b64encode(raw).decode("ascii"), 0, 0
    from PIL import Image

    with Image.open(io.BytesIO(raw)) as im:
        im.load()
        img = im.convert("RGBA") if im.mode in ("RGBA", "LA", "P") and "transparency" in im.info or im.mode == "RGBA" \
            else im.convert("RGB")
    scaled = img.width > max_width_px
    if scaled:
        img = img.resize((max_width_px, round(img.height * max_width_px / img.width)), Image.LANCZOS)
    buf = io.BytesIO()
    if _is_photograph(img) and img.mode == "RGB":
        img.save(buf, "JPEG", quality=85, optimize=True, progressive=True)
        mime = "image/jpeg"
    else:
        q = img.quantize(colors=256, method=Image.Quantize.FASTOCTREE if img.mode == "RGBA" else Image.Quantize.MEDIANCUT,
                         dither=Image.Dither.NONE)
        q.save(buf, "PNG", optimize=True)
        mime = "image/png"
    data = buf.getvalue()
    if not scaled and len(raw) <= len(data) and p.suffix.lower() in (".png", ".jpg", ".jpeg"):
        data, mime = raw, "image/png" if p.suffix.lower() == ".png" else "image/jpeg"
    return f"data:{mime};base64," + base64.b64encode(data).decode("ascii"), img.width, img.height
