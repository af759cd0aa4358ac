"""Direct inversion of a bulk sample: the pseudo-dielectric function ⟨ε⟩.

Public functions
----------------
- :func:`pseudo_dielectric` — ⟨ε⟩ from Ψ, Δ and the angle of incidence (two-phase model).
- :func:`pseudo_dielectric_from_rho` — the same from nmmm's complex ratio r_p/r_s.
- :func:`pseudo_dielectric_material` — ⟨ε⟩ of an :class:`~nmmm.ellipsometry.data.EllipsometryData`
  set at one angle as a :class:`nmmm.materials.material.TabulatedMaterial`.

For an ideal, clean, isotropic, semi-infinite substrate under an ambient of permittivity
ε_a, inverting the Fresnel equations gives exactly (Fujiwara 2007, eq. 5.3; Aspnes 1980)

    ⟨ε⟩ = ε_a sin²θ [1 + tan²θ ((1 − ρ)/(1 + ρ))²].

The formula is rational in ρ, so it commutes with complex conjugation: fed nmmm's
r_p/r_s = tan Ψ e^{−iΔ} (exp(−iωt)) it returns ε with Im ε ≥ 0, nmmm's convention; fed the
textbook ρ = tan Ψ e^{iΔ} it returns the conjugate, the exp(+iωt) ε. Surface overlayers and
roughness make ⟨ε⟩ differ from the true ε: it is then a *pseudo* dielectric function.

References
----------
- H. Fujiwara, *Spectroscopic Ellipsometry: Principles and Applications*, Wiley (2007), ch. 5,
  eq. 5.3.
- D. E. Aspnes, in *Handbook of Optical Constants of Solids*, ed. E. D. Palik, Academic Press
  (1985), p. 89.
"""

from __future__ import annotations

import numpy as np

from nmmm.ellipsometry.forward import check_angle_deg, rho_from_psi_delta
from nmmm.errors import InvalidInputError

__all__ = ["pseudo_dielectric", "pseudo_dielectric_from_rho", "pseudo_dielectric_material"]


def pseudo_dielectric_from_rho(rho_value, angle_deg, eps_ambient=1.0):
    """⟨ε⟩ = ε_a sin²θ [1 + tan²θ ((1 − ρ)/(1 + ρ))²] from nmmm's ρ = r_p/r_s.

    Broadcasts over all arguments. At normal incidence the formula is indeterminate
    (ρ = −1 for every material), so θ must be oblique.
    """
    r = np.asarray(rho_value, dtype=complex)
    a = check_angle_deg(angle_deg)
    if np.any(a < 1.0):
        raise InvalidInputError(
            "the pseudo-dielectric function needs oblique incidence (angle_deg >= 1; 55-75 deg "
            "near the Brewster angle is best): at normal incidence r_p/r_s = -1 for any material"
        )
    th = np.radians(a)
    t = (1 - r) / (1 + r)
    return np.asarray(eps_ambient, dtype=complex) * np.sin(th) ** 2 * (1 + np.tan(th) ** 2 * t * t)


def pseudo_dielectric(psi_deg, delta_deg, angle_deg, eps_ambient=1.0):
    """Pseudo-dielectric function ⟨ε⟩ = ⟨ε1⟩ + i⟨ε2⟩ of a bulk sample (nmmm convention, ⟨ε2⟩ ≥ 0
    for 0° < Δ < 180°).

    Parameters
    ----------
    psi_deg, delta_deg : array_like
        Measured Ψ ∈ [0°, 90°] and Δ (degrees), ellipsometry's usual convention
        (Δ = 180° at normal incidence on a dielectric).
    angle_deg : array_like
        Angle of incidence (degrees), broadcast against Ψ and Δ.
    eps_ambient : complex, optional
        Permittivity of the ambient (1 for air).

    Examples
    --------
    Silicon-like ε = 15.25 + 0.17i measured at 70° (Ψ, Δ computed with Fresnel), back again:

    >>> from nmmm.ellipsometry.forward import bulk_rho, psi_delta_from_rho
    >>> psi, delta = psi_delta_from_rho(bulk_rho(15.25 + 0.17j, 70.0))
    >>> complex(np.round(pseudo_dielectric(psi, delta, 70.0), 10))
    (15.25+0.17j)

    References
    ----------
    Fujiwara (2007), eq. 5.3.
    """
    return pseudo_dielectric_from_rho(rho_from_psi_delta(psi_deg, delta_deg), angle_deg, eps_ambient)


def pseudo_dielectric_material(data, angle_deg=None, name: str = "pseudo-dielectric", eps_ambient=1.0):
    """⟨ε⟩ of a measured data set at one angle as a TabulatedMaterial (n, k at the data's wavelengths).

    ``angle_deg`` selects one angle when the data hold several (default: the only one).
    """
    from nmmm.materials.material import TabulatedMaterial, eps_to_nk

    d = data.at_angle(angle_deg)
    eps = pseudo_dielectric(d.psi_deg, d.delta_deg, d.angle_deg, eps_ambient)
    nk = eps_to_nk(eps, allow_gain=True)  # the sign is checked here, with the wavelength and Delta
    if np.any(nk.imag < 0):
        i = int(np.flatnonzero(nk.imag < 0)[0])
        raise InvalidInputError(
            f"the pseudo-dielectric function has Im <eps> < 0 at {d.wavelength_nm[i]:g} nm "
            f"(Delta = {d.delta_deg[i]:g} deg): the data are not those of a bulk absorber in "
            "this Delta convention (expected 0 < Delta < 180 deg); check the instrument's sign of Delta"
        )
    return TabulatedMaterial(name=name, wavelength_nm=d.wavelength_nm, n_values=nk.real, k_values=nk.imag,
                             reference="pseudo-dielectric function, Fujiwara (2007) eq. 5.3")
