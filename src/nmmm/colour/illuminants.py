"""Illuminants and standard observers, by name or by data, on a wavelength grid.

- :data:`OBSERVERS` — the accepted observer names and their aliases (``"2"``, ``"10"``, the
  colour-science names), each mapped to colour-science's colour-matching functions.
- :func:`colour_matching_functions` — an observer (alias, name or
  ``colour.MultiSpectralDistributions``) as colour-science's CMFs.
- :func:`illuminant_on_grid` — an illuminant (a colour-science name such as ``"D65"``, a
  ``colour.SpectralDistribution``, or values already sampled on the grid) as spectral power on the
  grid, with the range and sign checked.
- :data:`ILLUMINANT_ALIASES`, :func:`canonical_illuminant` — the industry's names of the CIE
  illuminants (``F11``, ``TL84``, ``CWF``, ``LED B3`` …) as colour-science's (``FL11``, ``FL2``,
  ``LED-B3``); every function that takes an illuminant name accepts them.

Aliases. The CIE fluorescent series is written F1–F12 in CIE 15:2004 and in most instruments;
colour-science writes FL1–FL12. Booth lamps are named after a commercial tube whose CIE
representative is the usual stand-in (ASTM D1729, X-Rite/GTI booth documentation): TL84 (Philips
triband 4000 K) = F11, CWF (cool white fluorescent) = F2, TL83 / U30 (triband 3000 K) = F12. The
CIE LED series (CIE 15:2018 Table 11.4: LED-B1 … LED-V2) is accepted with a space, underscore or
no separator. Names are matched without regard to case.

References
----------
- CIE 015:2018 Colorimetry, 4th ed. (standard illuminants, CIE 1931 2° and CIE 1964 10° observers;
  LED illuminants, Table 11.4).
- ASTM D1729-16 Standard practice for visual appraisal of colors and color differences of
  diffusely-illuminated opaque materials (booth sources).
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


#: industry / CIE 15:2004 names -> colour-science names (module notes); matched case-insensitively
ILLUMINANT_ALIASES = {
    **{f"F{i}": f"FL{i}" for i in range(1, 13)},
    "TL84": "FL11", "TL 84": "FL11", "CWF": "FL2", "TL83": "FL12", "TL 83": "FL12", "U30": "FL12",
    **{f"LED{sep}{s}": f"LED-{s}" for s in ("B1", "B2", "B3", "B4", "B5", "BH1", "RGB1", "V1", "V2")
       for sep in (" ", "_", "")},
    "INC A": "A", "ILLUMINANT A": "A", "TUNGSTEN": "A",
}


def canonical_illuminant(name: str) -> str:
    """colour-science's name of an illuminant given by its own or an industry name
    (:data:`ILLUMINANT_ALIASES`, case-insensitive); an unknown name is returned unchanged.

    >>> canonical_illuminant("TL84"), canonical_illuminant("f2"), canonical_illuminant("d65")
    ('FL11', 'FL2', 'D65')
    """
    import colour

    if not isinstance(name, str):
        return name
    s = name.strip()
    up = s.upper()
    for key in colour.SDS_ILLUMINANTS:  # its own spelling (colour-science's mapping is case-blind too)
        if key.upper() == up:
            return key
    return ILLUMINANT_ALIASES.get(up, s)


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
        given, illuminant = illuminant, canonical_illuminant(illuminant)
        if illuminant not in colour.SDS_ILLUMINANTS:
            import difflib

            close = difflib.get_close_matches(given, list(colour.SDS_ILLUMINANTS) + list(ILLUMINANT_ALIASES), n=5)
            raise InvalidInputError(f"unknown illuminant {given!r}; close matches: {close} (colour-science names, "
                                    "or F1-F12, TL84, CWF, TL83, U30, LED B1-V2)")
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

