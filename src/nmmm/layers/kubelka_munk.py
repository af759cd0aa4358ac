"""Kubelka–Munk two-flux theory with Saunderson's surface correction — the fast path for
the reflectance of a pigmented film.

Public functions
----------------
- :func:`km_coefficients` — K and S from the transport coefficients μ_a, μ_s, g
  (registry :data:`KM_COEFFICIENT_METHODS`: ``"gate"`` K = 2μ_a, S = ¾μ_s(1−g);
  ``"star"`` K = 2μ_a, S = ¾μ_s(1−g) − ¼μ_a).
- :func:`km_r_infinity` — R∞ = 1 + K/S − √((K/S)² + 2K/S) of an opaque layer.
- :func:`km_reflectance`, :func:`km_transmittance` — a layer of thickness X over a
  background of reflectance R_g (Kubelka 1948, hyperbolic solution).
- :func:`saunderson_k1` — external specular reflectance for the measurement geometry (Fresnel).
- :func:`saunderson_k2` — internal reflectance of the surface for diffuse light,
  k2 = 1 − (1 − r_e)/n² with r_e the external diffuse (hemispherical) Fresnel reflectance.
- :func:`saunderson` — R = k1 + (1 − k1)(1 − k2) R_b / (1 − k2 R_b) (specular included).
- :func:`hiding_thickness` — the thickness whose contrast ratio R_black/R_white reaches a target.

All K, S, μ are per unit length in the same unit as the thickness (here nm⁻¹ and nm).

Assumptions (and where they break): KM treats two diffuse fluxes. It is good for optically
thick, strongly scattering films with moderate absorption; it is off for collimated light
in weakly scattering or strongly forward-scattering films and for thin layers.
:mod:`nmmm.layers.adding_doubling_method` solves the radiative transfer equation with Fresnel
boundaries as the reference; :func:`nmmm.layers.paint.compare_km_ad` reports the difference.

References
----------
- P. Kubelka, F. Munk, "Ein Beitrag zur Optik der Farbanstriche", Z. Tech. Phys. 12, 593
  (1931).
- P. Kubelka, "New contributions to the optics of intensely light-scattering materials.
  Part I", J. Opt. Soc. Am. 38, 448 (1948). doi:10.1364/JOSA.38.000448
- J. L. Saunderson, "Calculation of the color of pigmented plastics", J. Opt. Soc. Am. 32,
  727 (1942). doi:10.1364/JOSA.32.000727
- D. B. Judd, "Fresnel reflection of diffusely incident light", J. Res. Natl. Bur. Stand.
  29, 329 (1942) (k2 for n = 1.5: 0.596).
- L. F. Gate, "Comparison of the photon diffusion model and Kubelka–Munk equation with the
  exact solution of the radiative transport equation", Appl. Opt. 13, 236 (1974).
  doi:10.1364/AO.13.000236
- S. N. Thennadil, "Relationship between the Kubelka–Munk scattering and radiative transfer
  coefficients", J. Opt. Soc. Am. A 25, 1480 (2008). doi:10.1364/JOSAA.25.001480
- L. O. Star, J. P. A. Marijnissen, M. J. C. van Gemert, "Light dosimetry in optical
  phantoms and in tissues: I. Multiple flux and transport theory", Phys. Med. Biol. 33,
  437 (1988). doi:10.1088/0031-9155/33/4/004
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from nmmm.errors import InvalidInputError
from nmmm.layers.fresnel_equations import fresnel
from nmmm.spectra import check_finite

__all__ = [
    "KM_COEFFICIENT_METHODS",
    "km_coefficients",
    "km_r_infinity",
    "km_reflectance",
    "km_transmittance",
    "saunderson_k1",
    "saunderson_k2",
    "saunderson",
    "hiding_thickness",
]


def _nonneg(x, name):
    a = check_finite(x, name)
    if np.iscomplexobj(a):
        raise InvalidInputError(f"{name} must be real")
    a = a.astype(float, copy=False)
    if np.any(a < 0):
        raise InvalidInputError(f"{name} must be >= 0, got min {a.min()!r}")
    return a


def _unit(x, name):
    a = _nonneg(x, name)
    if np.any(a > 1):
        raise InvalidInputError(f"{name} must lie in [0, 1] (a reflectance), got max {a.max()!r}")
    return a


# --------------------------------------------------------------------------------------
# K and S from transport coefficients
# --------------------------------------------------------------------------------------
def km_coefficients_gate(mu_a, mu_s, g):
    """K = 2μ_a, S = ¾ μ_s (1 − g) (Gate 1974; Thennadil 2008 for diffuse incidence)."""
    return 2 * mu_a, 0.75 * mu_s * (1 - g)


def km_coefficients_star(mu_a, mu_s, g):
    """K = 2μ_a, S = ¾ μ_s (1 − g) − ¼ μ_a (Star, Marijnissen & van Gemert 1988), clipped at 0."""
    return 2 * mu_a, np.maximum(0.75 * mu_s * (1 - g) - 0.25 * mu_a, 0.0)


#: Mappings from radiative-transfer coefficients to Kubelka–Munk K, S.
KM_COEFFICIENT_METHODS = {"gate": km_coefficients_gate, "star": km_coefficients_star}


def km_coefficients(mu_a: ArrayLike, mu_s: ArrayLike, g: ArrayLike,
                    method: str = "gate") -> tuple[np.ndarray | float, np.ndarray | float]:
    """Kubelka–Munk (K, S) from absorption μ_a, scattering μ_s (same length unit) and g.

    Examples
    --------
    >>> [round(v, 12) for v in km_coefficients(0.01, 1.0, 0.6)]
    [0.02, 0.3]
    """
    try:
        f = KM_COEFFICIENT_METHODS[method]
    except KeyError:
        raise InvalidInputError(f"unknown method {method!r}; choose from {sorted(KM_COEFFICIENT_METHODS)}") from None
    mu_a = _nonneg(mu_a, "mu_a")
    mu_s = _nonneg(mu_s, "mu_s")
    g = check_finite(g, "g").astype(float)
    if np.any((g <= -1) | (g >= 1)):
        raise InvalidInputError("g must lie in (-1, 1)")
    K, S = f(mu_a, mu_s, g)
    if np.ndim(K) == 0:
        return float(K), float(S)
    return K, S


# --------------------------------------------------------------------------------------
# two-flux solutions
# --------------------------------------------------------------------------------------
def km_r_infinity(k_over_s: ArrayLike) -> np.ndarray:
    """Reflectance of an opaque layer, R∞ = 1 + K/S − √((K/S)² + 2K/S) (Kubelka 1948, eq. 6)."""
    q = np.asarray(k_over_s, dtype=float)
    if np.any(np.isnan(q)) or np.any(q < 0):
        raise InvalidInputError("k_over_s must be >= 0 (np.inf, no scattering, gives R = 0)")
    # the same expression rationalised, 1 / (1 + q + √(q² + 2q)): no cancellation for large q
    with np.errstate(invalid="ignore", over="ignore"):
        r = 1.0 / (1 + q + np.sqrt(q * q + 2 * q))
    return np.where(np.isinf(q), 0.0, r)[()]


def _b_coth(b, SX):
    """b·coth(b·SX), with its limit 1/SX + b² SX / 3 for small b·SX."""
    bsx = b * SX
    small = bsx < 1e-6
    safe = np.where(small, 1.0, bsx)
    with np.errstate(divide="ignore", invalid="ignore"):
        big = b / np.tanh(safe)
        lim = 1.0 / np.where(SX > 0, SX, 1.0) + b * b * SX / 3
    return np.where(small, lim, big)


def km_reflectance(K: ArrayLike, S: ArrayLike, thickness: ArrayLike,
                   background_reflectance: ArrayLike = 0.0) -> np.ndarray:
    """Diffuse reflectance of a KM layer of thickness X over a background R_g (Kubelka 1948):

        R = [1 − R_g (a − b coth(bSX))] / [a − R_g + b coth(bSX)],  a = 1 + K/S, b = √(a² − 1)

    with the limits S → 0 (R = R_g e^{−2KX}) and K → 0. K, S per unit length, X in the same
    unit; all broadcast.

    Examples
    --------
    Thick enough, the background no longer matters and R → R∞:

    >>> bool(np.isclose(km_reflectance(0.1, 1.0, 100.0, 0.0), km_r_infinity(0.1), rtol=1e-12))
    True
    """
    K = _nonneg(K, "K")
    S = _nonneg(S, "S")
    X = _nonneg(thickness, "thickness")
    Rg = _unit(background_reflectance, "background_reflectance")
    K, S, X, Rg = np.broadcast_arrays(K, S, X, Rg)
    noscat = S == 0
    Ss = np.where(noscat, 1.0, S)
    a = 1 + K / Ss
    b = np.sqrt(np.maximum(a * a - 1, 0.0))
    SX = Ss * X
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        bc = _b_coth(b, SX)
        R = (1 - Rg * (a - bc)) / (a - Rg + bc)
        # X = 0: the background itself
        R = np.where(X == 0, Rg, R)
    R = np.where(noscat, Rg * np.exp(-2 * K * X), R)
    return R[()] if R.ndim == 0 else R


def km_transmittance(K: ArrayLike, S: ArrayLike, thickness: ArrayLike) -> np.ndarray:
    """Diffuse transmittance of a free KM layer, T = b / (a sinh(bSX) + b cosh(bSX))
    (Kubelka 1948), with the limits S → 0 (T = e^{−KX}) and K → 0 (T = 1/(1 + SX))."""
    K = _nonneg(K, "K")
    S = _nonneg(S, "S")
    X = _nonneg(thickness, "thickness")
    K, S, X = np.broadcast_arrays(K, S, X)
    noscat = S == 0
    Ss = np.where(noscat, 1.0, S)
    a = 1 + K / Ss
    b = np.sqrt(np.maximum(a * a - 1, 0.0))
    SX = Ss * X
    bsx = b * SX
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        # T = b / (a sinh(bSX) + b cosh(bSX)) = 1 / (a sinh(bSX)/b + cosh(bSX))
        sinhc = np.where(bsx < 1e-6, SX * (1 + bsx**2 / 6), np.sinh(bsx) / np.where(b > 0, b, 1.0))
        T = 1.0 / (a * sinhc + np.cosh(bsx))
    T = np.where(noscat, np.exp(-K * X), np.nan_to_num(T, nan=0.0))
    return T[()] if T.ndim == 0 else T


# --------------------------------------------------------------------------------------
# Saunderson surface correction
# --------------------------------------------------------------------------------------
def saunderson_k1(n_binder: ArrayLike, angle_deg: ArrayLike = 0.0, n_ambient: ArrayLike = 1.0) -> np.ndarray:
    """External specular reflectance k1 of the air/binder surface for light incident at
    ``angle_deg`` (unpolarized Fresnel, :func:`nmmm.layers.fresnel_equations.fresnel`)."""
    return fresnel(n_ambient, n_binder, angle_deg).R


def saunderson_k2(n_binder: ArrayLike, n_ambient: ArrayLike = 1.0, n_nodes: int = 96) -> np.ndarray:
    """Internal reflectance k2 of the surface for diffuse (Lambertian) light from inside.

    k2 = 1 − (1 − r_e)/m², m = n_binder/n_ambient, where r_e = ∫₀¹ R(μ) 2μ dμ is the
    external hemispherical Fresnel reflectance (Judd 1942; Stokes reciprocity). For
    n = 1.5 in air k2 = 0.596 (Judd 1942).

    >>> round(float(saunderson_k2(1.5)), 3)
    0.596
    """
    n = np.real(check_finite(n_binder, "n_binder")).astype(float)
    x, w = np.polynomial.legendre.leggauss(int(n_nodes))
    mu = 0.5 * (x + 1)
    wq = 0.5 * w
    ang = np.degrees(np.arccos(np.clip(mu, 0, 1 - 1e-15)))
    R = fresnel(n_ambient, n[..., None], ang).R
    r_e = np.sum(R * 2 * mu * wq, axis=-1)
    return 1 - (1 - r_e) * (n_ambient / n) ** 2


def saunderson(body_reflectance: ArrayLike, k1: ArrayLike, k2: ArrayLike, specular: str = "included") -> np.ndarray:
    """Saunderson's (1942) correction of a diffuse body reflectance R_b for the surface:

        R = k1 + (1 − k1)(1 − k2) R_b / (1 − k2 R_b)

    ``specular="excluded"`` drops the k1 term (SCE geometry).

    0.04 + 0.96 · 0.4 · 0.5 / (1 − 0.3) = 0.3143:

    >>> round(float(saunderson(0.5, 0.04, 0.6)), 4)
    0.3143
    """
    Rb = _unit(body_reflectance, "body_reflectance")
    k1 = _unit(k1, "k1")
    k2 = _unit(k2, "k2")
    body = (1 - k1) * (1 - k2) * Rb / (1 - k2 * Rb)
    if specular == "included":
        return k1 + body
    if specular == "excluded":
        return body
    raise InvalidInputError("specular must be 'included' or 'excluded'")


def hiding_thickness(K: ArrayLike, S: ArrayLike, contrast_ratio: float = 0.98, white_reflectance: float = 0.8,
                     max_thickness: float | None = None) -> np.ndarray | float:
    """Thickness at which the contrast ratio R(black)/R(white) of a KM film reaches
    ``contrast_ratio`` (black background 0, white ``white_reflectance``), by bisection in
    log thickness. Same length unit as 1/K, 1/S; inf where it is never reached below
    ``max_thickness`` (default 1e4/S).
    """
    K = _nonneg(K, "K")
    S = _nonneg(S, "S")
    K, S = np.broadcast_arrays(K, S)
    if not 0 < contrast_ratio < 1:
        raise InvalidInputError("contrast_ratio must lie in (0, 1)")
    hi = np.full(K.shape, 1e4) / np.where(S > 0, S, 1.0) if max_thickness is None else np.full(K.shape, float(max_thickness))
    lo = hi * 1e-12

    def cr(X):
        return km_reflectance(K, S, X, 0.0) / np.maximum(km_reflectance(K, S, X, white_reflectance), 1e-300)

    ok = cr(hi) >= contrast_ratio
    for _ in range(80):
        mid = np.sqrt(lo * hi)
        up = cr(mid) >= contrast_ratio
        hi = np.where(up, mid, hi)
        lo = np.where(up, lo, mid)
    out = np.where(ok & (S > 0), hi, np.inf)
    return out[()] if out.ndim == 0 else out
