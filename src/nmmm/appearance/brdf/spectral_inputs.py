"""Reflectance-like spectral inputs of the paint BRDF (the base's ρ(λ)) on a wavelength grid:
a scalar, a function of wavelength (nm), a ``(wavelength_nm, values)`` pair, an array on the
grid, or an object with ``wavelength_nm`` and ``values``/``R``; checked to lie in [0, 1].
"""

from __future__ import annotations

import numpy as np

from nmmm.errors import InvalidInputError, OutOfRangeError
from nmmm.spectra import check_finite


def _spectral_values(value, w, name):
    """A reflectance-like spectral input on the grid ``w``: scalar, callable of the
    wavelength (nm), ``(wavelength_nm, values)`` pair, an array already on ``w``, or an
    object with ``wavelength_nm`` and ``values``/``R`` attributes. Must lie in [0, 1]."""
    if value is None:
        v = np.zeros_like(w)
    elif callable(value) and not hasattr(value, "wavelength_nm"):
        v = np.asarray(value(w), float)
    elif hasattr(value, "wavelength_nm") and (hasattr(value, "values") or hasattr(value, "R")):
        wn = np.asarray(value.wavelength_nm, float)
        vals = np.asarray(getattr(value, "values", None) if hasattr(value, "values") else value.R, float)
        v = _interp_checked(wn, vals, w, name)
    elif isinstance(value, (tuple, list)) and len(value) == 2 and np.ndim(value[0]) == 1:
        v = _interp_checked(np.asarray(value[0], float), np.asarray(value[1], float), w, name)
    else:
        v = np.asarray(value, float)
        if v.ndim == 0:
            v = np.full_like(w, float(v))
        elif v.shape != w.shape:
            raise InvalidInputError(
                f"{name} has shape {v.shape} but the wavelength grid has {w.shape}; pass a scalar, a "
                "function of wavelength_nm, or a (wavelength_nm, values) pair"
            )
    v = check_finite(v, name).astype(float)
    if np.any((v < 0) | (v > 1)):
        raise InvalidInputError(f"{name} must lie in [0, 1]; got values in [{v.min():.4g}, {v.max():.4g}]")
    return np.broadcast_to(v, w.shape).astype(float)


def _interp_checked(wn, vals, w, name):
    if wn.ndim != 1 or vals.shape[-1] != wn.size:
        raise InvalidInputError(f"{name}: wavelength_nm and values must have the same length")
    if w.min() < wn.min() - 1e-9 or w.max() > wn.max() + 1e-9:
        raise OutOfRangeError(
            f"{name} is given on {wn.min():g}–{wn.max():g} nm but asked on {w.min():g}–{w.max():g} nm; "
            "give it on a grid covering the evaluation wavelengths"
        )
    return np.interp(w, wn, vals)
