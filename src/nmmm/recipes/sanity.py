"""Sanity checks of a recipe and of a series: values a paint does not have are said, not run
silently.

- :func:`sanity_warnings` — sentences about a recipe's unusual values: a pigmented coat thinner
  than :data:`PIGMENTED_COAT_MIN_UM` or thicker than :data:`PIGMENTED_COAT_MAX_UM` (the value in
  µm, and the ``thickness_nm`` that the usual slip — µm written as nm — would have meant), a clear
  coat thicker than :data:`PIGMENTED_COAT_MAX_UM`.
- :func:`warn_if_unusual` — the same as :class:`UnusualRecipeWarning` warnings (``nmmm run``
  prints them; the report shows them in its warning box).
- :func:`masstone_unchanged_note` — for a concentration series whose masstone does not change
  (ΔE00 below :data:`UNCHANGED_DE00` from the lowest to the highest fraction), the words that
  say why (the film hides its substrate: opacity) and what shows concentration instead (a tint
  let down with white, or the draw-down over black).
"""

from __future__ import annotations

import warnings

import numpy as np

__all__ = ["sanity_warnings", "warn_if_unusual", "masstone_unchanged_note", "UnusualRecipeWarning",
           "PIGMENTED_COAT_MIN_UM", "PIGMENTED_COAT_MAX_UM", "UNCHANGED_DE00"]

#: thinnest pigmented coat a paint has (µm): below it a "film" is a thin-film optics problem
PIGMENTED_COAT_MIN_UM = 1.0
#: thickest coat a paint has (µm): thick-film coatings reach a few hundred µm
PIGMENTED_COAT_MAX_UM = 500.0
#: a masstone series whose ΔE00 stays below this is "unchanged" (≈ 1 is just noticeable)
UNCHANGED_DE00 = 1.0


class UnusualRecipeWarning(UserWarning):
    """A recipe value outside the range real paints have (it is computed all the same)."""


def _coat_message(key: str, thickness_nm: float) -> str | None:
    um = float(thickness_nm) / 1000.0
    if um < PIGMENTED_COAT_MIN_UM:
        hint = (f" If you meant {thickness_nm:g} µm, write {key} = {thickness_nm * 1000:g}."
                if 1 <= thickness_nm <= PIGMENTED_COAT_MAX_UM else "")
        return (f"{key} = {thickness_nm:g} nm is a {um:.3g} µm pigmented coat, thinner than paint films are "
                f"({PIGMENTED_COAT_MIN_UM:g}–{PIGMENTED_COAT_MAX_UM:g} µm; a usual coat is 20–80 µm): the pigment "
                f"particles are about as large as the film.{hint}")
    if um > PIGMENTED_COAT_MAX_UM:
        return (f"{key} = {thickness_nm:g} nm is a {um:.4g} µm ({um / 1000:.3g} mm) coat, thicker than paint films "
                f"are ({PIGMENTED_COAT_MIN_UM:g}–{PIGMENTED_COAT_MAX_UM:g} µm). If you meant {um:g} µm, write "
                f"{key} = {thickness_nm / 1000:g}.")
    return None


def sanity_warnings(recipe) -> list[str]:
    """Sentences about the values of ``recipe`` (a :class:`~nmmm.recipes.schema.Recipe`) that
    paints do not have; empty when every film and coat thickness is in range."""
    out = []
    film = getattr(recipe, "film", None)
    if film is not None and recipe.macro == "film":
        pigmented = getattr(recipe, "pigment", None) is not None or bool(getattr(recipe, "pigments", None))
        t = getattr(film, "thickness_nm", None)
        if t is not None:
            msg = _coat_message("film.thickness_nm", t) if pigmented else None
            if msg:
                out.append(msg)
        cc = getattr(film, "clear_coat_nm", 0.0) or 0.0
        if cc / 1000.0 > PIGMENTED_COAT_MAX_UM:
            out.append(_coat_message("film.clear_coat_nm", cc))
    for i, coat in enumerate(getattr(recipe, "coats", None) or []):
        t = getattr(coat, "thickness_nm", None)
        if t is None:
            continue
        key = f"coats[{i}].thickness_nm"
        if getattr(coat, "pigments", None) or getattr(coat, "pigment", None):
            msg = _coat_message(key, t)
        else:
            msg = _coat_message(key, t) if t / 1000.0 > PIGMENTED_COAT_MAX_UM else None
        if msg:
            out.append(msg)
    return out


def warn_if_unusual(recipe) -> list[str]:
    """Issue each of :func:`sanity_warnings` as an :class:`UnusualRecipeWarning`; returns them."""
    msgs = sanity_warnings(recipe)
    for m in msgs:
        warnings.warn(m, UnusualRecipeWarning, stacklevel=3)
    return msgs


def masstone_unchanged_note(fractions, labs, film_thickness_um: float | None = None,
                            illuminant: str | None = None) -> str:
    """Why a masstone does not change over a concentration series, or "" when it does.

    ``fractions``: pigment volume fractions of the series; ``labs``: their CIELAB (N, 3) under one
    illuminant (named by ``illuminant`` in the sentence when given). When ΔE00 between the lowest and the highest fraction is below
    :data:`UNCHANGED_DE00`, the film hides its substrate at every fraction: its reflectance is the
    infinite-thickness one, set by K/S, which independent scattering keeps constant."""
    from nmmm.colour import delta_e2000

    f = np.asarray(fractions, float)
    lab = np.asarray(labs, float)
    if f.size < 2 or np.ptp(f) == 0:
        return ""
    i, j = int(np.argmin(f)), int(np.argmax(f))
    de = float(delta_e2000(lab[i], lab[j]))
    if de >= UNCHANGED_DE00:
        return ""
    film = f"the {film_thickness_um:g} µm film" if film_thickness_um else "the film"
    under = f" under {illuminant}" if illuminant else ""
    return (f"The masstone hardly changes from {f[i]:g} to {f[j]:g} volume fraction (ΔE00 = {de:.2f}{under}): {film} hides "
            "its substrate at every one of these fractions (it is opaque), so its colour is the colour of an "
            "infinitely thick layer, set by the ratio K/S, which more pigment leaves unchanged. Concentration "
            "shows in a tint (the pigment let down with a white) or in a draw-down over black "
            "(film.substrate_reflectance = 0, or a thinner film).")
