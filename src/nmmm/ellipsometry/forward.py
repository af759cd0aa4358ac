"""Forward model of ellipsometry: Ψ and Δ of a layer stack, and the Δ sign convention.

Public functions
----------------
- :func:`psi_delta` — Ψ and Δ (degrees) of a :class:`nmmm.layers.Stack` at any wavelengths
  and angles of incidence, built on ``Stack.rt`` (no second transfer-matrix code here).
- :func:`rho` — the complex reflection ratio r_p / r_s of a stack (nmmm's convention).
- :func:`psi_delta_from_rho`, :func:`rho_from_psi_delta` — the conversions, with the
  convention stated below.
- :func:`bulk_rho` — r_p / r_s of a bare isotropic substrate in closed form (Fresnel).
- :func:`uniaxial_bulk_rho` — r_p / r_s of a uniaxial crystal whose optic axis lies in the
  surface, parallel or perpendicular to the plane of incidence (closed form).
- :func:`wrap_delta` — differences of Δ brought into (−180°, 180°].

The convention for Δ
--------------------
The textbooks of ellipsometry (Azzam & Bashara ch. 4; Fujiwara 2007, ch. 4) write

    ρ = tan Ψ · exp(iΔ)

with the time dependence exp(+iωt) and the complex index N = n − ik, so that Δ = 180° at
normal incidence on a dielectric (and at all angles below Brewster's), Δ = 0° above
Brewster's angle, and 0° < Δ < 180° for a bulk absorber.

nmmm computes with exp(−iωt) and N = n + ik (k ≥ 0). In that convention every reflection
coefficient is the complex conjugate of the textbook one, hence nmmm's ratio

    r_p / r_s = tan Ψ · exp(−iΔ),   i.e.   Ψ = arctan|r_p/r_s|,   Δ = −arg(r_p/r_s),

gives exactly the Ψ and Δ an ellipsometer reports, with the properties above (r_p is
defined so that r_p = −r_s at normal incidence, as in ``nmmm.layers`` and Fujiwara
2007, §2.3). Δ is returned in [0°, 360°). This is also pyElli's definition
(``elli.Result.delta``: ρ = tan Ψ exp(−iΔ) with n + ik), against which the tests compare.

References
----------
- H. Fujiwara, *Spectroscopic Ellipsometry: Principles and Applications*, Wiley (2007),
  ch. 2 (Fresnel equations), ch. 4 (Ψ and Δ), ch. 5 (pseudo-dielectric function).
- R. M. A. Azzam, N. M. Bashara, *Ellipsometry and Polarized Light*, North-Holland (1977),
  ch. 4 (reflection ellipsometry, incl. uniaxial substrates).
- D. E. Aspnes, "Approximate solution of ellipsometric equations for optically biaxial
  crystals", J. Opt. Soc. Am. 70, 1275 (1980), doi:10.1364/JOSA.70.001275.
"""

from __future__ import annotations

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.layers.fresnel_equations import check_angle_deg  # the one check of angles of incidence
from nmmm.spectra import as_wavelength_nm, check_finite

__all__ = [
    "psi_delta",
    "rho",
    "psi_delta_from_rho",
    "rho_from_psi_delta",
    "bulk_rho",
    "uniaxial_bulk_rho",
    "wrap_delta",
    "check_angle_deg",
    "check_psi_deg",
]


def check_psi_deg(psi_deg, name: str = "psi_deg") -> np.ndarray:
    """Validate Ψ in degrees: finite, in [0°, 90°] (tan Ψ = |r_p/r_s| ≥ 0)."""
    p = check_finite(psi_deg, name)
    if np.iscomplexobj(p):
        raise InvalidInputError(f"{name} must be real (degrees)")
    p = p.astype(float, copy=False)
    if np.any((p < 0) | (p > 90)):
        bad = int(np.flatnonzero((p < 0) | (p > 90))[0])
        raise InvalidInputError(
            f"{name} must lie in [0, 90] degrees (tan Psi = |r_p/r_s|); value {p.ravel()[bad]:g} "
            f"at index {bad} is outside. Psi in radians, or tan(Psi)/cos(Delta) data? Convert first."
        )
    return p


def wrap_delta(delta_deg):
    """Bring Δ differences into (−180°, 180°] (Δ is an angle: 359° and 1° differ by 2°)."""
    d = np.asarray(delta_deg, dtype=float)
    return 180.0 - np.mod(180.0 - d, 360.0)


def psi_delta_from_rho(rho_value):
    """(Ψ, Δ) in degrees from nmmm's r_p/r_s = tan Ψ · exp(−iΔ); Δ in [0°, 360°).

    >>> psi, delta = psi_delta_from_rho(-1.0 + 0j)   # normal incidence on a dielectric
    >>> float(psi), float(delta)
    (45.0, 180.0)
    """
    r = np.asarray(rho_value, dtype=complex)
    psi = np.degrees(np.arctan(np.abs(r)))
    delta = np.mod(-np.degrees(np.angle(r)), 360.0)
    delta = np.where(delta >= 360.0, delta - 360.0, delta)
    return psi, delta


def rho_from_psi_delta(psi_deg, delta_deg, check: bool = True):
    """nmmm's complex ratio r_p/r_s = tan Ψ · exp(−iΔ) from Ψ, Δ in degrees.

    The textbook ρ = tan Ψ exp(+iΔ) (exp(+iωt), N = n − ik) is its complex conjugate.
    """
    psi = check_psi_deg(psi_deg) if check else np.asarray(psi_deg, dtype=float)
    delta = check_finite(delta_deg, "delta_deg").astype(float)
    return np.tan(np.radians(psi)) * np.exp(-1j * np.radians(delta))


def _eps_of(medium, w):
    """ε of a Material or a constant complex index / ε-array at wavelengths ``w``."""
    if hasattr(medium, "eps"):
        return np.asarray(medium.eps(w), dtype=complex)
    return np.asarray(medium, dtype=complex) ** 2


def bulk_rho(eps_substrate, angle_deg, eps_ambient=1.0):
    """r_p / r_s of a bare isotropic substrate (Fresnel, two media, nmmm's convention).

    r_s = (N0 cosθ0 − N1 cosθ1)/(N0 cosθ0 + N1 cosθ1),
    r_p = (N1 cosθ0 − N0 cosθ1)/(N1 cosθ0 + N0 cosθ1)   (Fujiwara 2007, §2.3),

    written with ε: N1 cosθ1 = sqrt(ε1 − ε0 sin²θ0), the root with non-negative imaginary part
    (a decaying wave for exp(−iωt)). Broadcasts over all arguments.
    """
    e1 = np.asarray(eps_substrate, dtype=complex)
    e0 = np.asarray(eps_ambient, dtype=complex)
    th = np.radians(check_angle_deg(angle_deg))
    n0 = np.sqrt(e0)
    c0 = np.cos(th)
    kz0 = n0 * c0
    kz1 = _forward_sqrt(e1 - e0 * np.sin(th) ** 2)
    rs = (kz0 - kz1) / (kz0 + kz1)
    rp = (e1 * kz0 - e0 * kz1) / (e1 * kz0 + e0 * kz1)
    return rp / rs


def _forward_sqrt(z):
    """Square root with Im ≥ 0 (and Re ≥ 0 when Im = 0): the forward-going wave for exp(−iωt)."""
    s = np.sqrt(np.asarray(z, dtype=complex))
    flip = (s.imag < 0) | ((s.imag == 0) & (s.real < 0))
    return np.where(flip, -s, s)


def uniaxial_bulk_rho(eps_ordinary, eps_extraordinary, angle_deg, orientation: str = "parallel", eps_ambient=1.0):
    """r_p / r_s of a uniaxial crystal with its optic axis in the surface.

    Parameters
    ----------
    eps_ordinary, eps_extraordinary : complex array_like
        ε_o and ε_e of the crystal (broadcast with ``angle_deg``).
    angle_deg : array_like
        Angle of incidence (degrees).
    orientation : {"parallel", "perpendicular"}
        Optic axis parallel to the plane of incidence (x) or perpendicular to it (y, along the
        s field). In both cases the principal axes coincide with x, y, z so that p and s do not
        mix and (Ψ, Δ) are defined.

    Notes
    -----
    With principal permittivities ε_x (in-plane, in the plane of incidence), ε_y (in-plane,
    along s) and ε_z (normal), and ambient ε_0 (Azzam & Bashara ch. 4; Lekner, *Theory of
    Reflection*, ch. 10):

        k_zs = sqrt(ε_y − ε_0 sin²θ),  k_zp = sqrt(ε_x (1 − ε_0 sin²θ / ε_z)),
        r_s = (N0 cosθ − k_zs)/(N0 cosθ + k_zs),
        r_p = (ε_x N0 cosθ − ε_0 k_zp)/(ε_x N0 cosθ + ε_0 k_zp).

    "parallel": ε_x = ε_e, ε_y = ε_z = ε_o. "perpendicular": ε_y = ε_e, ε_x = ε_z = ε_o.
    For ε_o = ε_e both reduce to :func:`bulk_rho`.
    """
    eo = np.asarray(eps_ordinary, dtype=complex)
    ee = np.asarray(eps_extraordinary, dtype=complex)
    e0 = np.asarray(eps_ambient, dtype=complex)
    if orientation == "parallel":
        ex, ey, ez = ee, eo, eo
    elif orientation == "perpendicular":
        ex, ey, ez = eo, ee, eo
    else:
        raise InvalidInputError(f"orientation must be 'parallel' or 'perpendicular', got {orientation!r}")
    th = np.radians(check_angle_deg(angle_deg))
    s2 = e0 * np.sin(th) ** 2
    kz0 = np.sqrt(e0) * np.cos(th)
    kzs = _forward_sqrt(ey - s2)
    kzp = _forward_sqrt(ex * (1 - s2 / ez))
    rs = (kz0 - kzs) / (kz0 + kzs)
    rp = (ex * kz0 - e0 * kzp) / (ex * kz0 + e0 * kzp)
    return rp / rs


def rho(stack, wavelength_nm, angle_deg):
    """r_p / r_s of ``stack`` (nmmm's exp(−iωt) convention: tan Ψ · exp(−iΔ)).

    ``wavelength_nm`` and ``angle_deg`` broadcast against each other (paired measurement
    points); the result has the broadcast shape (with any thickness-grid axes of the stack
    in front). The stack's own ``rt(..., grid=False)`` does the optics.
    """
    w = as_wavelength_nm(wavelength_nm)
    a = check_angle_deg(angle_deg)
    res = stack.rt(w, a, grid=False)
    if res.rs is None or res.rp is None:
        raise InvalidInputError(
            "Psi/Delta need the complex amplitudes r_p, r_s: the stack has incoherent layers "
            "(no phase, depolarizing); make every layer coherent for ellipsometry")
    return np.asarray(res.rp, dtype=complex) / np.asarray(res.rs, dtype=complex)


def psi_delta(stack, wavelength_nm, angle_deg):
    """Ψ and Δ (degrees) of a layer stack at each wavelength and angle of incidence.

    Parameters
    ----------
    stack : nmmm.layers.Stack
        Any object with ``rt(wavelength_nm, angle_deg)`` returning r_s and r_p (attributes
        ``rs``, ``rp``), such as :class:`nmmm.layers.Stack`.
    wavelength_nm, angle_deg : array_like
        Broadcast against each other (e.g. ``wavelength_nm[:, None]`` and ``angle_deg[None, :]``
        for a wavelength × angle table).

    Returns
    -------
    psi_deg, delta_deg : ndarray
        Ψ ∈ [0°, 90°] and Δ ∈ [0°, 360°), defined by r_p/r_s = tan Ψ · exp(−iΔ) in nmmm's
        exp(−iωt), n + ik convention — the textbook ρ = tan Ψ · exp(iΔ) of Fujiwara (2007)
        and Azzam & Bashara: Δ = 180° at normal incidence on a dielectric, 0° < Δ < 180° for
        a bulk absorber (see the module docstring).

    References
    ----------
    Fujiwara (2007), ch. 4.
    """
    return psi_delta_from_rho(rho(stack, wavelength_nm, angle_deg))
