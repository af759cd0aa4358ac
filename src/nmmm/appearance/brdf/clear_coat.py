"""The clear coat of a paint: a non-absorbing dielectric and the GGX roughness of its top.

- :class:`ClearCoat` — index n(λ) (a Material or a constant) and roughness α.
- :func:`ggx_distribution`, :func:`smith_g1_ggx` — the GGX microfacet lobe of a rough coat
  (term 1 of :class:`~nmmm.appearance.brdf.PaintBRDF`).

References
----------
- B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet models for refraction
  through rough surfaces", EGSR 2007 — GGX distribution (eq. 33), Smith G1 (eq. 34).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.spectra import check_finite

__all__ = ["ClearCoat", "ggx_distribution", "smith_g1_ggx"]


def ggx_distribution(cos_h, alpha):
    """GGX / Trowbridge–Reitz normal distribution D(h) per sr (Walter et al. 2007, eq. 33),
    normalised so that ∫ D(h) cos θ_h dω_h = 1."""
    c2 = np.asarray(cos_h, float) ** 2
    a2 = alpha * alpha
    d = c2 * (a2 - 1.0) + 1.0
    return np.where(c2 > 0, a2 / (np.pi * d * d), 0.0)


def smith_g1_ggx(cos_v, alpha):
    """Smith masking G1 for GGX (Walter et al. 2007, eq. 34)."""
    c = np.clip(np.asarray(cos_v, float), 1e-12, 1.0)
    t2 = (1.0 - c * c) / (c * c)
    return 2.0 / (1.0 + np.sqrt(1.0 + alpha * alpha * t2))


@dataclass(frozen=True)
class ClearCoat:
    """The clear coat: a non-absorbing dielectric (a Material or a constant index) and
    the GGX roughness α of its top surface (0: optically smooth, a mirror Dirac)."""

    material: object = 1.5
    roughness: float = 0.0

    def __post_init__(self):
        a = float(check_finite(self.roughness, "roughness"))
        if not 0 <= a <= 1:
            raise InvalidInputError(f"coat roughness (GGX alpha) must lie in [0, 1], got {a!r}")
        object.__setattr__(self, "roughness", a)

    def index(self, wavelength_nm) -> np.ndarray:
        """Real refractive index n(λ) of the coat (k must be negligible)."""
        from nmmm.materials import as_material

        nk = np.asarray(as_material(self.material).nk(wavelength_nm), complex)
        if np.any(nk.imag > 1e-3):
            raise InvalidInputError(
                f"the clear coat absorbs (k up to {nk.imag.max():.3g}); PaintBRDF models a non-absorbing "
                "coat: put the absorption in the base reflectance instead"
            )
        if np.any(nk.real <= 1.0):
            raise InvalidInputError("the clear coat index must be > 1")
        if np.any(nk.real > 4.0):
            raise InvalidInputError(
                f"the clear coat index reaches {nk.real.max():.4g}; a clear coat or binder is a dielectric "
                "with n of about 1.3-2 (at most ~3): check the material's units (e.g. Cauchy B is in µm²)"
            )
        return nk.real
