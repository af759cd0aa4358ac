"""Fresnel coefficients of a plane interface between two (possibly absorbing) media.

Public functions
----------------
- :func:`fresnel` — amplitude coefficients ``rs, rp, ts, tp`` (and the power ``Rs, Rp,
  Ts, Tp``, ``R``, ``T``) for light going from medium 1 into medium 2.
- :func:`n_cos_theta` — ``n cos(theta)`` in a layer from the conserved ``n0 sin(theta0)``
  (Snell), on the branch of the forward-going wave; complex angles in absorbing media.
- :func:`brewster_angle` — ``arctan(n2/n1)`` for real indices.
- :func:`critical_angle` — ``arcsin(n2/n1)`` for total internal reflection.
- :func:`medium_nk`, :func:`check_angle_deg` — input checks shared by :mod:`nmmm.layers`.

Conventions (the whole package)
-------------------------------
Refractive index ``n + ik`` with ``k >= 0`` absorbing; time dependence ``exp(-i omega t)``;
angles in degrees. The amplitude coefficients follow Born & Wolf §1.5.2 as written in
Byrnes (2016), eqs. (1)–(4), the convention of the ``tmm`` package:

    rs = (n1 cos θ1 − n2 cos θ2) / (n1 cos θ1 + n2 cos θ2)
    rp = (n2 cos θ1 − n1 cos θ2) / (n2 cos θ1 + n1 cos θ2)
    ts = 2 n1 cos θ1 / (n1 cos θ1 + n2 cos θ2)
    tp = 2 n1 cos θ1 / (n2 cos θ1 + n1 cos θ2)

so that at normal incidence ``rp = −rs`` (the ellipsometric convention in which
Δ = 180° at normal incidence for a bare substrate, Fujiwara 2007 §2.3.3). ``ts`` and
``tp`` are ratios of the full electric field amplitudes (not of their tangential parts).
Power coefficients are ``R = |r|²`` and the transmitted fraction of the incident
Poynting flux normal to the interface (Byrnes 2016, eqs. (21)–(22)):

    Ts = |ts|² Re(n2 cos θ2) / Re(n1 cos θ1)
    Tp = |tp|² Re(n2 cos θ2*) / Re(n1 cos θ1*)

With an absorbing medium 1 these define T against the incident wave's own flux; the
interference flux between incident and reflected waves in an absorbing medium is then
not counted, so ``R + T`` need not be 1 (Byrnes 2016, appendix; Macleod 2010 §2.6).

References
----------
- M. Born, E. Wolf, *Principles of Optics*, 7th ed., Cambridge University Press (1999),
  §1.5. doi:10.1017/CBO9781139644181
- S. J. Byrnes, "Multilayer optical calculations", arXiv:1603.02720 (2016).
- H. Fujiwara, *Spectroscopic Ellipsometry: Principles and Applications*, Wiley (2007),
  §2.3. doi:10.1002/9780470060193
- H. A. Macleod, *Thin-Film Optical Filters*, 4th ed., CRC Press (2010), ch. 2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from nmmm.errors import InvalidInputError
from nmmm.spectra import check_finite, check_nk

__all__ = [
    "FresnelCoefficients",
    "fresnel",
    "n_cos_theta",
    "brewster_angle",
    "critical_angle",
    "check_angle_deg",
    "medium_nk",
]

#: tolerance deciding whether Im(n cos θ) is "zero" when picking the forward branch
_BRANCH_TOL = 1e-12


def medium_nk(value, wavelength_nm, name: str = "nk") -> np.ndarray:
    """n + ik of a medium, validated (finite, ``k >= 0``).

    ``value`` is a nmmm Material (anything with ``.nk(wavelength_nm)``, evaluated at
    ``wavelength_nm``; the error then names the material) or complex values, returned as
    given (no broadcasting against the wavelengths).
    """
    if hasattr(value, "nk") and callable(value.nk):
        label = f"{name} ({getattr(value, 'name', type(value).__name__)})"
        return check_nk(value.nk(wavelength_nm), label)
    return check_nk(value, name)


def check_angle_deg(angle_deg, name: str = "angle_deg") -> np.ndarray:
    """Validate angles of incidence in degrees: real, finite, ``0 <= angle < 90``."""
    a = check_finite(angle_deg, name)
    if np.iscomplexobj(a):
        raise InvalidInputError(f"{name} must be real (degrees), got complex values")
    a = a.astype(float, copy=False)
    if np.any((a < 0) | (a >= 90)):
        raise InvalidInputError(
            f"{name} must lie in [0, 90) degrees (angle from the surface normal); "
            f"got values in [{a.min()!r}, {a.max()!r}]"
        )
    return a


def n_cos_theta(n: ArrayLike, n_sin_theta: ArrayLike) -> np.ndarray:
    """``n cos θ`` in a medium of index ``n`` for the conserved ``n0 sin θ0`` (Snell's law).

    ``n cos θ = sqrt(n² − (n0 sin θ0)²)``, on the branch of the wave travelling *forward*
    (away from the interface, into the medium): the one that decays, ``Im(n cos θ) > 0``,
    or, when it neither decays nor grows, the one carrying power forward,
    ``Re(n cos θ) > 0`` (Byrnes 2016, appendix D). In absorbing media and beyond the
    critical angle θ is complex; ``n cos θ`` is what the transfer matrices need, and
    ``cos θ = n cos θ / n``.

    Parameters
    ----------
    n : complex array_like
        Index of the medium, ``n + ik`` with ``k >= 0``.
    n_sin_theta : complex array_like
        ``n0 sin θ0`` in the incidence medium; broadcasts with ``n``.

    Examples
    --------
    Beyond the critical angle of glass→air the wave is evanescent,
    ``sqrt(1 − 1.5² sin²60°) = 0.829156i``:

    >>> complex(np.round(n_cos_theta(1.0, 1.5 * np.sin(np.radians(60))), 6))
    0.829156j
    """
    n = np.asarray(n, dtype=complex)
    beta = np.asarray(n_sin_theta, dtype=complex)
    q = np.sqrt(n * n - beta * beta)
    flip = (q.imag < -_BRANCH_TOL) | ((np.abs(q.imag) <= _BRANCH_TOL) & (q.real < 0))
    return np.where(flip, -q, q)


class UnpolarizedPower:
    """Unpolarized power of anything with ``Rs, Rp, Ts, Tp``: the mean of s and p."""

    @property
    def R(self) -> np.ndarray:
        """Unpolarized reflectance ``(Rs + Rp)/2``."""
        return 0.5 * (self.Rs + self.Rp)

    @property
    def T(self) -> np.ndarray:
        """Unpolarized transmittance ``(Ts + Tp)/2``."""
        return 0.5 * (self.Ts + self.Tp)


@dataclass(frozen=True)
class FresnelCoefficients(UnpolarizedPower):
    """Amplitude coefficients of one interface (see module docstring for conventions).

    Attributes
    ----------
    rs, rp, ts, tp : complex ndarray
        Reflection and transmission amplitude coefficients.
    n1, n2 : complex ndarray
        Indices of the incidence and transmission media (broadcast).
    cos_theta1, cos_theta2 : complex ndarray
        Cosines of the (possibly complex) angles in media 1 and 2.
    """

    rs: np.ndarray
    rp: np.ndarray
    ts: np.ndarray
    tp: np.ndarray
    n1: np.ndarray
    n2: np.ndarray
    cos_theta1: np.ndarray
    cos_theta2: np.ndarray

    @property
    def Rs(self) -> np.ndarray:
        """Power reflectance, s polarization: ``|rs|²``."""
        return np.abs(self.rs) ** 2

    @property
    def Rp(self) -> np.ndarray:
        """Power reflectance, p polarization: ``|rp|²``."""
        return np.abs(self.rp) ** 2

    @property
    def Ts(self) -> np.ndarray:
        """Power transmittance, s: ``|ts|² Re(n2 cos θ2)/Re(n1 cos θ1)``."""
        num = (self.n2 * self.cos_theta2).real
        den = (self.n1 * self.cos_theta1).real
        return np.abs(self.ts) ** 2 * num / den

    @property
    def Tp(self) -> np.ndarray:
        """Power transmittance, p: ``|tp|² Re(n2 cos θ2*)/Re(n1 cos θ1*)``."""
        num = (self.n2 * np.conj(self.cos_theta2)).real
        den = (self.n1 * np.conj(self.cos_theta1)).real
        return np.abs(self.tp) ** 2 * num / den


def fresnel(n1: ArrayLike, n2: ArrayLike, angle_deg: ArrayLike) -> FresnelCoefficients:
    """Fresnel amplitude coefficients for light incident from medium 1 onto medium 2.

    Parameters
    ----------
    n1, n2 : complex array_like
        Refractive indices ``n + ik`` (``k >= 0``) of the incidence and transmission
        media. Complex ``n1`` is allowed (see the module notes on T in that case).
    angle_deg : array_like
        Angle of incidence in medium 1, degrees in ``[0, 90)``. For absorbing ``n1``
        it is the (real) angle in the sense of the complex Snell invariant
        ``n1 sin θ1``.

    All three broadcast together (e.g. ``n2[:, None]`` against ``angle_deg[None, :]``).

    Returns
    -------
    FresnelCoefficients
        ``rs, rp, ts, tp`` and the power properties ``Rs, Rp, Ts, Tp, R, T``.

    Notes
    -----
    Born & Wolf (1999) eqs. 1.5(20)–(21) in the ``exp(−iωt)``, ``n + ik`` convention with
    ``rp = −rs`` at normal incidence (module docstring). The angle in medium 2 is
    complex when medium 2 absorbs or beyond the critical angle; :func:`n_cos_theta`
    picks the forward-decaying branch.

    References
    ----------
    Born & Wolf (1999) §1.5.2; Byrnes, arXiv:1603.02720 (2016), eqs. (1)–(4).

    Examples
    --------
    Air to glass at normal incidence, ``rs = (1 − 1.5)/(1 + 1.5) = −0.2``:

    >>> c = fresnel(1.0, 1.5, 0.0)
    >>> float(c.rs.real), float(c.rp.real), round(float(c.R), 6)
    (-0.2, 0.2, 0.04)
    """
    n1 = check_nk(n1, "n1")
    n2 = check_nk(n2, "n2")
    theta = np.radians(check_angle_deg(angle_deg))
    if np.any(n1 == 0) or np.any(n2 == 0):
        raise InvalidInputError("refractive indices must be non-zero")
    n1, n2, theta = np.broadcast_arrays(n1, n2, theta)
    beta = n1 * np.sin(theta)
    q1 = n1 * np.cos(theta)
    q2 = n_cos_theta(n2, beta)
    e1, e2 = n1 * n1, n2 * n2
    den_s = q1 + q2
    den_p = e2 * q1 + e1 * q2
    rs = (q1 - q2) / den_s
    rp = (e2 * q1 - e1 * q2) / den_p
    ts = 2 * q1 / den_s
    tp = 2 * q1 * n1 * n2 / den_p
    return FresnelCoefficients(rs, rp, ts, tp, n1, n2, np.cos(theta).astype(complex), q2 / n2)


def brewster_angle(n1: ArrayLike, n2: ArrayLike) -> np.ndarray:
    """Brewster's angle in degrees, ``θ_B = arctan(n2/n1)`` (Born & Wolf §1.5.3), where
    ``rp = 0`` for real indices.

    >>> round(float(brewster_angle(1.0, 1.5)), 4)
    56.3099
    """
    n1 = check_finite(n1, "n1")
    n2 = check_finite(n2, "n2")
    if np.iscomplexobj(n1) or np.iscomplexobj(n2):
        raise InvalidInputError("brewster_angle needs real indices; for absorbing media find the minimum of Rp")
    return np.degrees(np.arctan2(n2, n1))


def critical_angle(n1: ArrayLike, n2: ArrayLike) -> np.ndarray:
    """Critical angle in degrees, ``arcsin(n2/n1)``, for real ``n1 > n2`` (total internal
    reflection beyond it; Born & Wolf §1.5.4).

    >>> round(float(critical_angle(1.5, 1.0)), 4)
    41.8103
    """
    n1 = np.asarray(check_finite(n1, "n1"), dtype=float)
    n2 = np.asarray(check_finite(n2, "n2"), dtype=float)
    if np.any(n2 >= n1):
        raise InvalidInputError("a critical angle exists only for n1 > n2 (from the denser medium)")
    return np.degrees(np.arcsin(n2 / n1))
