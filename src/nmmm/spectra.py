"""Wavelength grids and input checks shared by every scale.

- :func:`wavelength_grid` — the usual visible grids (nm).
- :func:`as_wavelength_nm` — validate a wavelength array (finite, > 0) and return it as float.
- :func:`check_finite` — raise on NaN / infinity with the argument's name.
- :func:`check_fraction` — a volume fraction in [0, 1].
- :func:`check_positive` — strictly positive lengths (diameters, thicknesses).
- :func:`check_nk` — complex refractive indices with k ≥ 0.

Wavelengths are in nanometres at every public interface of nmmm.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from nmmm.errors import InvalidInputError

#: The CIE visible range used by default (nm).
VISIBLE_NM = (380.0, 780.0)


#: most wavelengths :func:`wavelength_grid` makes (0.001 nm over the visible is 400 001)
MAX_GRID_POINTS = 1_000_000


def wavelength_grid(start_nm: float = 380.0, stop_nm: float = 780.0, step_nm: float = 5.0) -> np.ndarray:
    """Return an inclusive, evenly spaced wavelength grid in nm.

    >>> wavelength_grid().size
    81
    >>> wavelength_grid(step_nm=1).size
    401
    """
    if not (np.isfinite(start_nm) and np.isfinite(stop_nm) and np.isfinite(step_nm)):
        raise InvalidInputError(f"need finite start_nm, stop_nm, step_nm, got {start_nm}, {stop_nm}, {step_nm}")
    if not step_nm > 0 or not stop_nm > start_nm:
        raise InvalidInputError(f"need start_nm < stop_nm and step_nm > 0, got {start_nm}, {stop_nm}, {step_nm}")
    if not start_nm > 0:
        raise InvalidInputError(f"start_nm = {start_nm}: wavelengths are > 0 nm (the visible is 380-780 nm)")
    n = (stop_nm - start_nm) / step_nm + 1
    if n > MAX_GRID_POINTS:
        raise InvalidInputError(
            f"step_nm = {step_nm:g} gives {n:.3g} wavelengths from {start_nm:g} to {stop_nm:g} nm "
            f"({n * 16 / 1e9:.3g} GB per complex array), more than {MAX_GRID_POINTS:,}; a spectrum needs a "
            "step of 0.1-10 nm")
    n = int(round(n - 1)) + 1
    return np.linspace(start_nm, start_nm + (n - 1) * step_nm, n)


def check_finite(x: ArrayLike, name: str = "value") -> np.ndarray:
    """Return ``np.asarray(x)``, raising :class:`InvalidInputError` if any entry is NaN or infinite."""
    a = np.asarray(x)
    if a.dtype.kind not in "biufc":
        try:
            a = a.astype(float)
        except (TypeError, ValueError):
            raise InvalidInputError(f"{name} must be numeric, got {a.dtype}") from None
    if not np.all(np.isfinite(a)):
        bad = np.flatnonzero(~np.isfinite(a).ravel())
        raise InvalidInputError(
            f"{name} contains NaN or infinite values (first at flat index {bad[0]}); "
            "give finite numbers"
        )
    return a


def as_wavelength_nm(wavelength_nm: ArrayLike, name: str = "wavelength_nm") -> np.ndarray:
    """Validate wavelengths in nm: finite and strictly positive; returns a float array."""
    w = check_finite(wavelength_nm, name)
    if np.iscomplexobj(w):
        raise InvalidInputError(f"{name} must be real, got complex values")
    w = w.astype(float, copy=False)
    if np.any(w <= 0):
        raise InvalidInputError(f"{name} must be > 0 nm, got min {w.min()!r}")
    return w


def check_fraction(fraction: ArrayLike, name: str = "fraction") -> np.ndarray:
    """Validate a volume fraction in [0, 1] (not percent: 0.05 % is 0.0005)."""
    p = check_finite(fraction, name).astype(float, copy=False)
    if np.any((p < 0) | (p > 1)):
        raise InvalidInputError(
            f"{name} must lie in [0, 1] (a volume fraction, not a percentage); "
            f"got values in [{p.min()!r}, {p.max()!r}]"
        )
    return p


def check_positive(x: ArrayLike, name: str = "value") -> np.ndarray:
    """Validate strictly positive real values (sizes, thicknesses)."""
    a = check_finite(x, name)
    if np.iscomplexobj(a):
        raise InvalidInputError(f"{name} must be real")
    a = a.astype(float, copy=False)
    if np.any(a <= 0):
        raise InvalidInputError(f"{name} must be > 0, got min {a.min()!r}")
    return a


def check_nk(nk: ArrayLike, name: str = "nk") -> np.ndarray:
    """Validate complex refractive indices n + ik: finite, n > 0, k ≥ 0 (absorbing convention)."""
    a = check_finite(nk, name).astype(complex, copy=False)
    if np.any(a.imag < 0):
        raise InvalidInputError(
            f"{name} has k < 0 (min {a.imag.min()!r}); nmmm uses n + ik with k >= 0 for absorption "
            "(time dependence exp(-i omega t))"
        )
    return a
