"""CIE tristimulus values of spectra, vectorised, built on colour-science.

- :func:`weighting_factors` — the (N, 3) weights W with XYZ = R @ W for a wavelength grid,
  an illuminant and an observer (the perfect white has Y = 100).
- :func:`spectra_to_xyz` — reflectance / transmittance spectra (last axis = wavelength) to
  CIE XYZ under an explicit illuminant.
- :func:`white_point` — XYZ of the perfect white under the same illuminant.

The illuminant and observer are always explicit (default D65 and the CIE 1931 2°
observer — colour-science's own default illuminant for ``sd_to_XYZ`` is E, a known trap).
CIE tables come from colour-science, interpolated onto the given grid; integration is the
ASTM E308 / CIE 015 sum with each sample weighted by its wavelength interval.

References
----------
- CIE 015:2018 Colorimetry, 4th ed. (white normalisation Y = 100).
- ASTM E308-22, Standard Practice for Computing the Colors of Objects by Using the CIE System.
- T. Mansencal et al., Colour 0.4.7, Zenodo, https://doi.org/10.5281/zenodo.3757045
"""

from __future__ import annotations

import functools

import numpy as np

from nmmm.colour.illuminants import colour_matching_functions, illuminant_on_grid
from nmmm.errors import InvalidInputError, OutOfRangeError
from nmmm.spectra import as_wavelength_nm, check_finite


def _key(x):
    if isinstance(x, np.ndarray):
        return ("array", x.tobytes(), x.shape)
    return x if isinstance(x, str) else id(x)


@functools.lru_cache(maxsize=64)
def _weights_cached(w_bytes, w_shape, ill_key, obs_key, illuminant, observer):
    w = np.frombuffer(w_bytes, dtype=float).reshape(w_shape)
    cmfs = colour_matching_functions(observer)
    lo, hi = cmfs.wavelengths[0], cmfs.wavelengths[-1]
    if w.min() < lo - 1e-9 or w.max() > hi + 1e-9:
        raise OutOfRangeError(f"wavelengths {w.min():g}–{w.max():g} nm exceed the observer's range ({lo:g}–{hi:g} nm)")
    cmf = np.stack([np.interp(w, cmfs.wavelengths, cmfs.values[:, i]) for i in range(3)], axis=-1)
    s = illuminant_on_grid(illuminant, w)
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

    cmfs = colour_matching_functions(observer)
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
