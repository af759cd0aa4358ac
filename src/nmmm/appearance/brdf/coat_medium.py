"""The pigmented binder of an effect coat: :class:`CoatMedium` — absorption μa(λ), scattering
μs(λ) and asymmetry g(λ) of the pigments between and above the flakes, and the coat thickness.

A :class:`~nmmm.appearance.brdf.PaintBRDF` given a ``medium`` treats the basecoat as a
scattering, absorbing slab of vertical optical thickness κ(λ) = (μa + μs) H holding the flake
layer (uniform within ``FlakeLayer.depth_range``), over the substrate (``body_reflectance``);
see :mod:`~nmmm.appearance.brdf.effect_tables` for the model. The coefficients are those of
:func:`nmmm.layers.paint.film_coefficients` (Mie pigments in a binder, issue 16).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nmmm.errors import InvalidInputError, OutOfRangeError
from nmmm.spectra import check_finite

__all__ = ["CoatMedium"]


@dataclass(frozen=True, repr=False)
class CoatMedium:
    """Pigmented binder of the basecoat, per nm of path, over wavelength.

    Parameters
    ----------
    wavelength_nm : (K,) array
        Grid (nm, increasing) on which the coefficients are given (linearly interpolated to
        the BRDF's grid, which must lie inside it).
    mu_a_per_nm, mu_s_per_nm : (K,) arrays or scalars
        Absorption and scattering coefficients (1/nm, ≥ 0) of the binder with its pigments.
    g : (K,) array or scalar
        Asymmetry parameter of the pigments' phase function (Henyey–Greenstein), |g| < 1.
    thickness_nm : float
        Thickness H of the basecoat (nm, > 0); the flakes lie inside it.
    """

    wavelength_nm: np.ndarray
    mu_a_per_nm: np.ndarray
    mu_s_per_nm: np.ndarray
    g: np.ndarray
    thickness_nm: float

    def __post_init__(self):
        w = np.atleast_1d(check_finite(self.wavelength_nm, "CoatMedium wavelength_nm")).astype(float)
        if w.ndim != 1 or (w.size > 1 and np.any(np.diff(w) <= 0)) or np.any(w <= 0):
            raise InvalidInputError("CoatMedium wavelength_nm must be a 1-D increasing grid of positive nm")
        vals = {}
        for name in ("mu_a_per_nm", "mu_s_per_nm", "g"):
            v = np.asarray(check_finite(getattr(self, name), f"CoatMedium {name}"), float)
            v = np.broadcast_to(v, w.shape).astype(float) if v.ndim == 0 or v.shape == w.shape else None
            if v is None:
                raise InvalidInputError(f"CoatMedium {name} must be a scalar or have the shape of wavelength_nm {w.shape}")
            vals[name] = v
        if np.any(vals["mu_a_per_nm"] < 0) or np.any(vals["mu_s_per_nm"] < 0):
            raise InvalidInputError("CoatMedium mu_a_per_nm and mu_s_per_nm must be >= 0 (coefficients per nm)")
        if np.any(np.abs(vals["g"]) >= 1):
            raise InvalidInputError("CoatMedium g (phase-function asymmetry) must lie in (-1, 1)")
        H = float(check_finite(self.thickness_nm, "CoatMedium thickness_nm"))
        if not H > 0:
            raise InvalidInputError(f"CoatMedium thickness_nm must be > 0 (the basecoat thickness in nm), got {H!r}")
        object.__setattr__(self, "wavelength_nm", w)
        for k, v in vals.items():
            object.__setattr__(self, k, v)
        object.__setattr__(self, "thickness_nm", H)

    @classmethod
    def from_coefficients(cls, coefficients, thickness_nm: float) -> "CoatMedium":
        """From any object with ``wavelength_nm``, ``mu_a_per_nm``, ``mu_s_per_nm`` and ``g``
        (e.g. :class:`nmmm.layers.paint.FilmCoefficients`)."""
        for a in ("wavelength_nm", "mu_a_per_nm", "mu_s_per_nm", "g"):
            if not hasattr(coefficients, a):
                raise InvalidInputError(f"coefficients lack '{a}' (give e.g. nmmm.layers.paint.film_coefficients(...))")
        return cls(np.asarray(coefficients.wavelength_nm, float), np.asarray(coefficients.mu_a_per_nm, float),
                   np.asarray(coefficients.mu_s_per_nm, float), np.asarray(coefficients.g, float), thickness_nm)

    @classmethod
    def clear(cls, thickness_nm: float) -> "CoatMedium":
        """A non-absorbing, non-scattering binder (the flakes alone)."""
        return cls(np.array([1.0, 1e6]), 0.0, 0.0, 0.0, thickness_nm)

    def on_grid(self, wavelength_nm):
        """Vertical optical thicknesses of the whole coat on a grid: (κa, κs, g), each (L,)."""
        w = np.asarray(wavelength_nm, float).ravel()
        wn = self.wavelength_nm
        if wn.size == 1:
            if not np.allclose(w, wn[0]):
                raise OutOfRangeError(f"CoatMedium is given at {wn[0]:g} nm only; asked on {w.min():g}-{w.max():g} nm")
            f = lambda v: np.full(w.shape, v[0])  # noqa: E731
        else:
            if w.min() < wn[0] - 1e-9 or w.max() > wn[-1] + 1e-9:
                raise OutOfRangeError(
                    f"CoatMedium is given on {wn[0]:g}-{wn[-1]:g} nm but the BRDF is asked on {w.min():g}-{w.max():g} nm; "
                    "give the coefficients on a grid covering the evaluation wavelengths")
            f = lambda v: np.interp(w, wn, v)  # noqa: E731
        H = self.thickness_nm
        return f(self.mu_a_per_nm) * H, f(self.mu_s_per_nm) * H, f(self.g)

    def __repr__(self):
        return (f"<CoatMedium H={self.thickness_nm / 1e3:g} um, mu_s*H {np.min(self.mu_s_per_nm) * self.thickness_nm:.3g}-"
                f"{np.max(self.mu_s_per_nm) * self.thickness_nm:.3g}, mu_a*H {np.min(self.mu_a_per_nm) * self.thickness_nm:.3g}-"
                f"{np.max(self.mu_a_per_nm) * self.thickness_nm:.3g}>")
