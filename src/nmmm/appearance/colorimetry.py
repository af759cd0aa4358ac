"""Colorimetry of spectra, vectorised, built on colour-science.

- :func:`weighting_factors` — the (N, 3) weights W with XYZ = R @ W for a wavelength grid,
  an illuminant and an observer (the perfect white has Y = 100).
- :func:`spectra_to_xyz`, :func:`spectra_to_lab` — reflectance / transmittance spectra
  (last axis = wavelength) to CIE XYZ and CIELAB under an explicit illuminant.
- :func:`xyz_to_lab`, :func:`white_point` — CIELAB with the white of the same illuminant.
- :func:`delta_e2000` — CIEDE2000 colour difference.
- :func:`xyz_to_srgb`, :func:`spectra_to_srgb` — display encoding (IEC 61966-2-1 sRGB,
  chromatically adapted from the illuminant's white to D65 with CAT02).

The illuminant and observer are always explicit (default D65 and the CIE 1931 2°
observer — colour-science's own default illuminant for ``sd_to_XYZ`` is E, a known trap).
CIE tables come from colour-science, interpolated onto the given grid; integration is the
ASTM E308 / CIE 015 sum with each sample weighted by its wavelength interval.

References
----------
- CIE 015:2018 Colorimetry, 4th ed. (CIELAB, white normalisation Y = 100).
- ASTM E308-22, Standard Practice for Computing the Colors of Objects by Using the CIE System.
- G. Sharma, W. Wu, E. N. Dalal, Color Res. Appl. 30, 21 (2005) — CIEDE2000.
- IEC 61966-2-1:1999 — sRGB.
- T. Mansencal et al., Colour 0.4.7, Zenodo, https://doi.org/10.5281/zenodo.3757045
"""

from __future__ import annotations

import functools

import numpy as np

from nmmm.errors import InvalidInputError, OutOfRangeError
from nmmm.spectra import as_wavelength_nm, check_finite

OBSERVERS = {
    "2": "CIE 1931 2 Degree Standard Observer",
    "10": "CIE 1964 10 Degree Standard Observer",
    "CIE 1931 2 Degree Standard Observer": "CIE 1931 2 Degree Standard Observer",
    "CIE 1964 10 Degree Standard Observer": "CIE 1964 10 Degree Standard Observer",
}


def _observer(observer) -> "colour.MultiSpectralDistributions":  # noqa: F821
    import colour

    if isinstance(observer, str):
        key = OBSERVERS.get(observer.replace("°", "").strip())
        if key is None:
            raise InvalidInputError(f"unknown observer {observer!r}; use '2' or '10' (or {list(OBSERVERS)[2:]})")
        return colour.MSDS_CMFS[key]
    return observer


def _illuminant_values(illuminant, w):
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


def _key(x):
    if isinstance(x, np.ndarray):
        return ("array", x.tobytes(), x.shape)
    return x if isinstance(x, str) else id(x)


@functools.lru_cache(maxsize=64)
def _weights_cached(w_bytes, w_shape, ill_key, obs_key, illuminant, observer):
    w = np.frombuffer(w_bytes, dtype=float).reshape(w_shape)
    cmfs = _observer(observer)
    lo, hi = cmfs.wavelengths[0], cmfs.wavelengths[-1]
    if w.min() < lo - 1e-9 or w.max() > hi + 1e-9:
        raise OutOfRangeError(f"wavelengths {w.min():g}–{w.max():g} nm exceed the observer's range ({lo:g}–{hi:g} nm)")
    cmf = np.stack([np.interp(w, cmfs.wavelengths, cmfs.values[:, i]) for i in range(3)], axis=-1)
    s = _illuminant_values(illuminant, w)
    dw = np.gradient(w) if w.size > 1 else np.ones(1)
    W = s[:, None] * cmf * dw[:, None]
    norm = W[:, 1].sum()
    if norm <= 0:
        raise InvalidInputError("the illuminant has no power where the observer sees; cannot normalise Y")
    W = W * (100.0 / norm)
    W.setflags(write=False)
    return W


#: least fraction of each colour-matching function's integral a grid must cover before
#: :func:`weighting_factors` warns that colours come from a truncated spectrum
#: (400–700 nm covers ≥ 99.5 % of x̄, ȳ, z̄; 420–680 nm only 95 % of z̄).
MIN_CMF_COVERAGE = 0.99


def _warn_if_truncated(w, observer):
    import warnings

    cmfs = _observer(observer)
    inside = (cmfs.wavelengths >= w.min()) & (cmfs.wavelengths <= w.max())
    coverage = cmfs.values[inside].sum(axis=0) / cmfs.values.sum(axis=0)
    if np.any(coverage < MIN_CMF_COVERAGE):
        warnings.warn(
            f"the wavelength grid {w.min():g}–{w.max():g} nm covers only "
            f"{100 * coverage.min():.1f} % of a colour-matching function: colours are computed from a "
            "truncated spectrum (use at least 400–700 nm, ideally 380–780 nm)", UserWarning, stacklevel=3)


def weighting_factors(wavelength_nm, illuminant="D65", observer="2") -> np.ndarray:
    """Weights W (N, 3) such that XYZ = values @ W, the perfect white giving Y = 100."""
    w = as_wavelength_nm(wavelength_nm)
    if w.ndim != 1 or w.size < 2 or np.any(np.diff(w) <= 0):
        raise InvalidInputError("wavelength_nm must be a 1-D increasing grid of at least 2 points")
    _warn_if_truncated(w, observer)
    if isinstance(illuminant, np.ndarray) or not isinstance(illuminant, str):
        return _weights_cached.__wrapped__(w.tobytes(), w.shape, None, None, illuminant, observer)
    return _weights_cached(w.tobytes(), w.shape, _key(illuminant), _key(observer), illuminant, observer)


def spectra_to_xyz(wavelength_nm, values, illuminant="D65", observer="2") -> np.ndarray:
    """CIE XYZ (last axis X, Y, Z; white Y = 100) of spectra ``values`` (..., N).

    >>> import numpy as np
    >>> w = np.arange(380, 781, 5.0)
    >>> np.round(spectra_to_xyz(w, np.ones_like(w)), 2)
    array([  95.04,  100.  ,  108.88])
    """
    W = weighting_factors(wavelength_nm, illuminant, observer)
    v = check_finite(values, "spectra").astype(float, copy=False)
    if v.shape[-1] != W.shape[0]:
        raise InvalidInputError(f"spectra's last axis ({v.shape[-1]}) must match the wavelength grid ({W.shape[0]})")
    return v @ W


def white_point(wavelength_nm, illuminant="D65", observer="2") -> np.ndarray:
    """XYZ of the perfect white under the illuminant (Y = 100)."""
    return weighting_factors(wavelength_nm, illuminant, observer).sum(axis=0)


def xyz_to_lab(xyz, white_xyz) -> np.ndarray:
    """CIELAB (CIE 015:2018) of XYZ relative to the white ``white_xyz`` (same scale)."""
    import colour

    white = np.asarray(white_xyz, dtype=float)
    return colour.XYZ_to_Lab(np.asarray(xyz) / white[1], colour.XYZ_to_xy(white / white[1]))


def spectra_to_lab(wavelength_nm, values, illuminant="D65", observer="2") -> np.ndarray:
    """CIELAB (last axis L*, a*, b*) of one spectrum or a stack (last axis = wavelength),
    white normalised to Y = 100 under the same illuminant.

    >>> import numpy as np
    >>> w = np.arange(380, 781, 5.0)
    >>> np.round(spectra_to_lab(w, np.ones_like(w)), 6) + 0.0
    array([ 100.,    0.,    0.])
    """
    xyz = spectra_to_xyz(wavelength_nm, values, illuminant, observer)
    return xyz_to_lab(xyz, white_point(wavelength_nm, illuminant, observer))


def delta_e2000(lab1, lab2) -> np.ndarray:
    """CIEDE2000 colour difference (Sharma, Wu & Dalal 2005), broadcasting."""
    import colour

    lab1, lab2 = _check_triplets(lab1, "lab1"), _check_triplets(lab2, "lab2")
    return colour.delta_E(lab1, lab2, method="CIE 2000")


def _check_triplets(x, name: str) -> np.ndarray:
    """Finite colour coordinates with a last axis of 3 (L*, a*, b* or X, Y, Z)."""
    a = check_finite(x, name).astype(float, copy=False)
    if a.ndim == 0 or a.shape[-1] != 3:
        raise InvalidInputError(f"{name} must have a last axis of 3 colour coordinates, got shape {a.shape}")
    return a


def xyz_to_srgb(xyz, white_xyz=None, clip: bool = True, exposure: float = 1.0) -> np.ndarray:
    """Encoded sRGB in [0, 1] of XYZ (scale: white Y = 100).

    ``white_xyz`` is the adopted white (the illuminant's, default D65); colours are adapted
    from it to sRGB's D65 with CAT02. ``exposure`` multiplies the linear values first.
    """
    import colour

    xyz = _check_triplets(xyz, "xyz") / 100.0 * exposure
    if white_xyz is None:
        xy_w = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    else:
        white = _check_triplets(white_xyz, "white_xyz")
        if white.ndim != 1 or not white[1] > 0:
            raise InvalidInputError(f"white_xyz must be one XYZ triplet with Y > 0, got {white.tolist()}")
        xy_w = colour.XYZ_to_xy(white / white[1])
    rgb = colour.XYZ_to_sRGB(xyz, illuminant=xy_w, chromatic_adaptation_transform="CAT02")
    return np.clip(rgb, 0.0, 1.0) if clip else rgb


def spectra_to_srgb(wavelength_nm, values, illuminant="D65", observer="2", exposure: float = 1.0) -> np.ndarray:
    """Encoded sRGB in [0, 1] of reflectance / transmittance spectra seen under ``illuminant``."""
    xyz = spectra_to_xyz(wavelength_nm, values, illuminant, observer)
    return xyz_to_srgb(xyz, white_point(wavelength_nm, illuminant, observer), exposure=exposure)
