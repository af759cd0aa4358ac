"""Size-corrected Maxwell Garnett: the sphere's polarizability from the first Mie coefficient.

- :func:`size_parameter` — x = 2π n_m r / λ of a sphere of radius r in the host.
- :func:`mie_a1` — the electric dipole Mie coefficient a1(m, x), closed form with
  order-1 Riccati–Bessel functions (Bohren & Huffman 1983, eq. 4.88).
- :func:`dipole_polarizability_mie` — polarizability per unit volume relative to the host,
  ``alpha = 9 i a1 / (2 x³)`` (tends to 3 (eps_i − eps_m)/(eps_i + 2 eps_m) as x → 0).
- :func:`maxwell_garnett_mie` — Maxwell Garnett with that polarizability (Doyle 1989),
  warning (:class:`SizeValidityWarning`) when x leaves the range of the dipole theory.
- :func:`check_quasi_static` — warn when particles are too large for the quasi-static formulas.
- :func:`mie_low_orders`, :func:`neglected_multipole_fraction`, :func:`check_dipole_validity` —
  what the dipole theory leaves out (b1, a2, b2), and the warning built on it.

Notes
-----
Quasi-static effective media (eq. 2, Bruggeman, ...) ignore retardation across the
particle: their error on the dipole grows as x² (x = 2π n_m r/λ) — about 1 % at x = 0.1,
10 % at x ≈ 0.3 — and they miss radiative damping and the red shift of the resonance.
Doyle's extended Maxwell Garnett theory keeps the Clausius–Mossotti structure and takes
the dipole polarizability from the exact Mie coefficient a1, which includes both. It still
neglects the magnetic dipole b1 and the electric quadrupole a2, which grow as x² relative
to a1; Ruppin (2000) found it the most accurate of the extended MG theories. nmmm computes
what it neglects — the share of the sphere's extinction carried by b1, a2 and b2
(:func:`neglected_multipole_fraction`, closed forms of order ≤ 2) — and issues
:class:`SizeValidityWarning` when it exceeds 5 % or when x > 1 (use full Mie scattering with
radiative transfer in :mod:`nmmm.layers` there). For gold in silica this allows radii up to
about 30 nm across the visible. Im ε of the result describes the *extinction* of the coherent
beam (absorption and scattering out of it), the quantity for transmission through a
non-turbid layer.

Convention: exp(−iωt), m = n + ik with k >= 0; a1 then has Re a1 >= 0 (its real part
is the dipole extinction), as in Bohren & Huffman.

References
----------
- W. T. Doyle, "Optical properties of a suspension of metal spheres",
  Phys. Rev. B 39, 9852 (1989), doi:10.1103/PhysRevB.39.9852.
- R. Ruppin, "Evaluation of extended Maxwell-Garnett theories",
  Opt. Commun. 182, 273 (2000), doi:10.1016/S0030-4018(00)00825-7.
- C. F. Bohren, D. R. Huffman, Absorption and Scattering of Light by Small Particles
  (Wiley 1983), §4.4 (eqs. 4.53, 4.88) and §5.2.
"""

from __future__ import annotations

import warnings

import numpy as np
from numpy.typing import ArrayLike

from nmmm.ema._validation import as_eps, as_fraction
from nmmm.errors import InvalidInputError
from nmmm.spectra import as_wavelength_nm, check_finite, check_positive

#: Default largest size parameter for the dipole (a1) theory.
MAX_SIZE_PARAMETER_DIPOLE = 1.0
#: Default largest size parameter for the quasi-static formulas (≈ 3 % error on the dipole).
MAX_SIZE_PARAMETER_QUASI_STATIC = 0.2
#: Default largest share of extinction the dipole theory may neglect (b1, a2, b2).
MAX_NEGLECTED_MULTIPOLE_FRACTION = 0.05
#: Below this x, a1 is computed from its series (the closed form cancels).
_X_SERIES = 1e-3


class SizeValidityWarning(UserWarning):
    """Particles too large for the effective-medium formula in use."""


def size_parameter(radius_nm: ArrayLike, wavelength_nm: ArrayLike, eps_host: ArrayLike) -> np.ndarray:
    """``x = 2π n_m r / λ``: radius ``radius_nm`` and wavelength ``wavelength_nm`` in nm,
    n_m = Re sqrt(eps_host). Broadcasts.

    >>> round(float(size_parameter(50.0, 500.0, 2.25)), 6)   # 2π·1.5·50/500
    0.942478
    """
    r = check_positive(radius_nm, "radius_nm")
    w = as_wavelength_nm(wavelength_nm)
    em = as_eps(eps_host, "eps_host")
    n_m = np.sqrt(em).real
    if np.any(n_m <= 0):
        raise InvalidInputError("the host must have a positive refractive index for a size parameter")
    return 2 * np.pi * n_m * r / w


def _psi(z, n):
    """Riccati–Bessel ψ_0, ψ_1 (z j_n(z))."""
    return np.sin(z) if n == 0 else np.sin(z) / z - np.cos(z)


def _xi(z, n):
    """Riccati–Bessel ξ_n = z h_n^(1)(z) = ψ_n − i χ_n, for n = 0, 1 (exp(−iωt))."""
    if n == 0:
        return -1j * np.exp(1j * z)
    return np.exp(1j * z) * (-1j / z - 1)


def _log_derivative_1(z):
    """D_1(z) = ψ_1'(z)/ψ_1(z) = −1/z + 1/(1/z − cot z); tan avoids overflow of sin, cos
    for large Im z."""
    cot = 1 / np.tan(z)
    return -1 / z + 1 / (1 / z - cot)


def _psi2(z):
    return (3 / z**2 - 1) * np.sin(z) - 3 * np.cos(z) / z


def _xi2(z):
    """ξ_2 = z h_2^(1)(z) = ψ_2 − i χ_2 with χ_2 = (3/z² − 1) cos z + 3 sin z / z."""
    return _psi2(z) - 1j * ((3 / z**2 - 1) * np.cos(z) + 3 * np.sin(z) / z)


def mie_low_orders(m: ArrayLike, x: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Mie coefficients a1, b1, a2, b2 of a sphere (closed forms, Bohren & Huffman eq. 4.88):

    ``a_n = [(D_n(mx)/m + n/x) ψ_n(x) − ψ_{n−1}(x)] / [(D_n(mx)/m + n/x) ξ_n(x) − ξ_{n−1}(x)]``,
    ``b_n = [(m D_n(mx) + n/x) ψ_n(x) − ψ_{n−1}(x)] / [(m D_n(mx) + n/x) ξ_n(x) − ξ_{n−1}(x)]``,
    with D_2(z) = −2/z + 1/(2/z − D_1(z)). Used to measure what the dipole theory neglects.
    Returns four arrays of the broadcast shape of ``m`` and ``x`` (x not too small: > 1e-3).
    """
    m = check_finite(m, "m").astype(complex)
    x = check_positive(x, "x")
    m, x = np.broadcast_arrays(m, x)
    z = m * x
    D1 = _log_derivative_1(z)
    D2 = -2 / z + 1 / (2 / z - D1)
    psi0, psi1, psi2 = _psi(x, 0), _psi(x, 1), _psi2(x)
    xi0, xi1, xi2 = _xi(x, 0), _xi(x, 1), _xi2(x)
    out = []
    for D, n, psi_n, psi_m, xi_n, xi_m in ((D1, 1, psi1, psi0, xi1, xi0), (D2, 2, psi2, psi1, xi2, xi1)):
        ga = D / m + n / x
        gb = m * D + n / x
        out.append(((ga * psi_n - psi_m) / (ga * xi_n - xi_m), (gb * psi_n - psi_m) / (gb * xi_n - xi_m)))
    (a1, b1), (a2, b2) = out
    return a1, b1, a2, b2


def neglected_multipole_fraction(eps_inclusion: ArrayLike, eps_host: ArrayLike, radius_nm: ArrayLike,
                                 wavelength_nm: ArrayLike) -> np.ndarray:
    """Share of the sphere's extinction (through order 2) that the electric-dipole theory
    leaves out: ``(3 Re b1 + 5 Re(a2 + b2)) / (3 Re(a1 + b1) + 5 Re(a2 + b2))``
    (extinction efficiency ∝ Σ (2n+1) Re(a_n + b_n), Bohren & Huffman eq. 4.62)."""
    ei = as_eps(eps_inclusion, "eps_inclusion")
    em = as_eps(eps_host, "eps_host")
    x = size_parameter(radius_nm, wavelength_nm, em)
    m = np.sqrt(ei) / np.sqrt(em)
    m = np.where(m.imag < 0, m.real + 0j, m)
    x = np.maximum(x, _X_SERIES)  # below, the neglected share is ~x² and immaterial
    a1, b1, a2, b2 = mie_low_orders(m, x)
    neglected = 3 * b1.real + 5 * (a2.real + b2.real)
    total = 3 * (a1.real + b1.real) + 5 * (a2.real + b2.real)
    return np.abs(neglected) / np.maximum(np.abs(total), 1e-300)


def mie_a1(m: ArrayLike, x: ArrayLike) -> np.ndarray:
    """First electric Mie coefficient of a sphere (relative index m, size parameter x).

    ``a1 = [(D1(mx)/m + 1/x) ψ1(x) − ψ0(x)] / [(D1(mx)/m + 1/x) ξ1(x) − ξ0(x)]``
    (Bohren & Huffman eq. 4.88, n = 1) with ψ0 = sin x, ψ1 = sin x/x − cos x,
    ξ0 = −i e^{ix}, ξ1 = e^{ix}(−i/x − 1). For x < 1e-3 the series
    ``a1 = −(2i/3) x³ (m²−1)/(m²+2) − (2i/5) x⁵ (m²−2)(m²−1)/(m²+2)² + (4/9) x⁶ ((m²−1)/(m²+2))²``
    (Bohren & Huffman §5.2) replaces it. ``m = n + ik`` (k >= 0), ``x > 0``; broadcasts.
    """
    m = check_finite(m, "m").astype(complex)
    if np.any(m.imag < 0):
        raise InvalidInputError("m must have Im m >= 0 (n + ik, exp(-i omega t))")
    x = check_positive(x, "x")
    m, x = np.broadcast_arrays(m, x)
    out = np.empty(m.shape, dtype=complex)
    small = x < _X_SERIES
    if np.any(~small):
        mm, xx = m[~small], x[~small]
        g = _log_derivative_1(mm * xx) / mm + 1 / xx
        out[~small] = (g * _psi(xx, 1) - _psi(xx, 0)) / (g * _xi(xx, 1) - _xi(xx, 0))
    if np.any(small):
        mm, xx = m[small], x[small]
        m2 = mm * mm
        beta = (m2 - 1) / (m2 + 2)
        out[small] = (-2j / 3 * xx**3 * beta - 2j / 5 * xx**5 * (m2 - 2) * (m2 - 1) / (m2 + 2) ** 2
                      + 4 / 9 * xx**6 * beta**2)
    return out


def dipole_polarizability_mie(eps_inclusion: ArrayLike, eps_host: ArrayLike, radius_nm: ArrayLike,
                              wavelength_nm: ArrayLike) -> np.ndarray:
    """Polarizability per unit volume relative to the host from a1: ``9 i a1 / (2 x³)``.

    (With α = 6π i a1 / k³ the dipole polarizability in volume units and V = 4π r³/3;
    Doyle 1989.) Tends to the quasi-static ``3 (eps_i − eps_m)/(eps_i + 2 eps_m)``.
    """
    ei = as_eps(eps_inclusion, "eps_inclusion")
    em = as_eps(eps_host, "eps_host")
    x = size_parameter(radius_nm, wavelength_nm, em)
    m = np.sqrt(ei) / np.sqrt(em)
    m = np.where(m.imag < 0, m.real + 0j, m)  # lossy host: keep the passive branch
    return 9j * mie_a1(m, x) / (2 * x**3)


def _warn_size(x, limit, what, stacklevel=3):
    xmax = float(np.max(x))
    if xmax > limit:
        warnings.warn(
            f"size parameter x = 2 pi n_m r / lambda reaches {xmax:.3g} > {limit:g}, the validity limit "
            f"of {what}; results lose accuracy — use smaller particles, a longer wavelength, or full "
            "Mie scattering with radiative transfer (nmmm.layers)", SizeValidityWarning, stacklevel=stacklevel)


def check_quasi_static(radius_nm: ArrayLike, wavelength_nm: ArrayLike, eps_host: ArrayLike,
                       max_size_parameter: float = MAX_SIZE_PARAMETER_QUASI_STATIC) -> np.ndarray:
    """Warn (:class:`SizeValidityWarning`) if particles of ``radius_nm`` are too large for
    the quasi-static formulas at ``wavelength_nm``; returns the size parameters."""
    x = size_parameter(radius_nm, wavelength_nm, eps_host)
    _warn_size(x, max_size_parameter, "the quasi-static formulas (try maxwell_garnett_mie)")
    return x


def check_dipole_validity(eps_inclusion: ArrayLike, eps_host: ArrayLike, radius_nm: ArrayLike, wavelength_nm: ArrayLike,
                          max_size_parameter: float = MAX_SIZE_PARAMETER_DIPOLE,
                          max_neglected: float = MAX_NEGLECTED_MULTIPOLE_FRACTION, stacklevel: int = 3) -> np.ndarray:
    """Warn (:class:`SizeValidityWarning`) where the dipole (a1) theory is out of its range:
    size parameter above ``max_size_parameter`` or neglected multipoles (b1, a2, b2) carrying
    more than ``max_neglected`` of the extinction (:func:`neglected_multipole_fraction`)."""
    x = size_parameter(radius_nm, wavelength_nm, eps_host)
    _warn_size(x, max_size_parameter, "the dipole (a1) size-corrected Maxwell Garnett theory", stacklevel + 1)
    share = neglected_multipole_fraction(eps_inclusion, eps_host, radius_nm, wavelength_nm)
    worst = float(np.max(share)) if np.size(share) else 0.0
    if worst > max_neglected:
        warnings.warn(
            f"the magnetic dipole and electric/magnetic quadrupole terms carry up to {100 * worst:.0f} % of the "
            f"extinction (limit {100 * max_neglected:g} %), which the dipole (a1) size-corrected Maxwell Garnett "
            "theory neglects; use smaller particles or full Mie scattering with radiative transfer (nmmm.layers)",
            SizeValidityWarning, stacklevel=stacklevel)
    return share


def maxwell_garnett_mie(eps_inclusion: ArrayLike, eps_host: ArrayLike, fraction: ArrayLike, radius_nm: ArrayLike,
                        wavelength_nm: ArrayLike,
                        max_size_parameter: float = MAX_SIZE_PARAMETER_DIPOLE,
                        max_neglected: float = MAX_NEGLECTED_MULTIPOLE_FRACTION) -> np.ndarray:
    """Size-corrected Maxwell Garnett (Doyle 1989) for spheres of radius ``radius_nm``:

    ``eps = eps_m (1 + 2 p alpha/3) / (1 − p alpha/3)``, ``alpha = 9 i a1 / (2 x³)``,
    with a1 the first electric Mie coefficient (:func:`mie_a1`) at size parameter
    x = 2π n_m r / λ. Equals eq. (2) as r → 0. Warns with :class:`SizeValidityWarning`
    when x exceeds ``max_size_parameter`` or the neglected multipoles exceed ``max_neglected``
    of the extinction (:func:`check_dipole_validity`). All arguments broadcast.
    """
    from nmmm.ema.maxwell_garnett_rule import maxwell_garnett_polarizability

    p = as_fraction(fraction)
    alpha = dipole_polarizability_mie(eps_inclusion, eps_host, radius_nm, wavelength_nm)
    check_dipole_validity(eps_inclusion, eps_host, radius_nm, wavelength_nm, max_size_parameter, max_neglected)
    return maxwell_garnett_polarizability(eps_host, p, alpha)


__all__ = [
    "MAX_NEGLECTED_MULTIPOLE_FRACTION",
    "check_dipole_validity",
    "mie_low_orders",
    "neglected_multipole_fraction",
    "MAX_SIZE_PARAMETER_DIPOLE",
    "MAX_SIZE_PARAMETER_QUASI_STATIC",
    "SizeValidityWarning",
    "check_quasi_static",
    "dipole_polarizability_mie",
    "maxwell_garnett_mie",
    "mie_a1",
    "size_parameter",
]
