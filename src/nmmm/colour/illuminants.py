"""Illuminants and standard observers, by name or by data, on a wavelength grid.

- :data:`OBSERVERS` — the accepted observer names and their aliases (``"2"``, ``"10"``, the
  colour-science names), each mapped to colour-science's colour-matching functions.
- :func:`colour_matching_functions` — an observer (alias, name or
  ``colour.MultiSpectralDistributions``) as colour-science's CMFs.
- :func:`illuminant_on_grid` — an illuminant (a colour-science name such as ``"D65"``, a
  ``colour.SpectralDistribution``, or values already sampled on the grid) as spectral power on the
  grid, with the range and sign checked.

References
----------
- CIE 015:2018 Colorimetry, 4th ed. (standard illuminants, CIE 1931 2° and CIE 1964 10° observers).
- T. Mansencal et al., Colour 0.4.7, Zenodo, https://doi.org/10.5281/zenodo.3757045
"""

from __future__ import annotations

import numpy as np

from nmmm.errors import InvalidInputError, OutOfRangeError
from nmmm.spectra import check_finite

OBSERVERS = {
    "2": "CIE 1931 2 Degree Standard Observer",
    "10": "CIE 1964 10 Degree Standard Observer",
    "CIE 1931 2 Degree Standard Observer": "CIE 1931 2 Degree Standard Observer",
    "CIE 1964 10 Degree Standard Observer": "CIE 1964 10 Degree Standard Observer",
}


def colour_matching_functions(observer) -> "colour.MultiSpectralDistributions":  # noqa: F821
    """colour-science's CMFs of ``observer`` (a key of :data:`OBSERVERS`, with or without "°",
    or CMFs already)."""
    import colour

    if isinstance(observer, str):
        key = OBSERVERS.get(observer.replace("°", "").strip())
        if key is None:
            raise InvalidInputError(f"unknown observer {observer!r}; use '2' or '10' (or {list(OBSERVERS)[2:]})")
        return colour.MSDS_CMFS[key]
    return observer


def illuminant_on_grid(illuminant, w) -> np.ndarray:
    """Illuminant SPD on the grid ``w``: a colour-science name, a SpectralDistribution, or
    an array of values already on ``w``."""
    import colour

    if isinstance(illuminant, str):
        if illuminant not in colour.SDS_ILLUMINANTS:
            import difflib

            close = difflib.get_close_matches(illuminant, list(colour.SDS_ILLUMINANTS), n=5)
            raise InvalidInputError(f"unknown illuminant {illuminant!r}; close matches: {close}")
        illuminant = colour.SDS_ILLUMINANTS[illuminant]
    if isinstance(illuminant, colour.SpectralDistribution):
        lo, hi = illuminant.wavelengths[0], illuminant.wavelengths[-1]
        if w.min() < lo - 1e-9 or w.max() > hi + 1e-9:
            raise OutOfRangeError(
                f"wavelengths {w.min():g}–{w.max():g} nm exceed the illuminant '{illuminant.name}' "
                f"data ({lo:g}–{hi:g} nm); restrict the grid (e.g. 380–780 nm)")
        return np.asarray(illuminant[w], dtype=float)
    s = check_finite(illuminant, "illuminant").astype(float)
    if s.shape != w.shape:
        raise InvalidInputError(f"illuminant values must be sampled on the wavelength grid (shape {w.shape}), got {s.shape}")
    if np.any(s < 0):
        raise InvalidInputError("illuminant spectral power must be >= 0")
    return s

