"""Kramers–Kronig relations: causality links n and k (ε1 and ε2) of every material.

- :func:`eps1_from_eps2` — ε1(E) = ε∞ + (2/π) P∫ E'ε2(E') / (E'² − E²) dE'.
- :func:`eps2_from_eps1` — ε2(E) = −(2E/π) P∫ (ε1(E') − ε∞) / (E'² − E²) dE'.
- :func:`n_from_k` — n(E) = n∞ + (2/π) P∫ E'k(E') / (E'² − E²) dE' (same kernel for N = n + ik).
- :func:`kk_consistency` — how far a Material's n is from the n implied by its k over its range.

The principal-value integrals are computed **exactly for piecewise-linear data**: on each
segment [E_j, E_j+1] the integrand is split into partial fractions and integrated in
closed form (logarithms); the singular logarithms of the two segments meeting at E cancel
analytically. Grids may be non-uniform (e.g. uniform in wavelength). Accuracy is then set
by the sampling of the data (O(h²)) and by the truncation of the integral to the grid.

Energies in eV (E = 1239.84/λ[nm]); the public functions take wavelengths in nm or
energies in eV (``energy_ev=``).

References
----------
- H. A. Kramers, Atti Congr. Int. Fis. Como 2, 545 (1927); R. de L. Kronig, JOSA 12, 547 (1926).
- F. Wooten, Optical Properties of Solids (Academic Press 1972), §6.4.
- H. Fujiwara, Spectroscopic Ellipsometry (Wiley 2007), §5.2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike

from nmmm.errors import InvalidInputError
from nmmm.materials.material import HC_EV_NM, Material
from nmmm.spectra import as_wavelength_nm, check_finite


def _sorted_grid(energy_ev, values):
    E = check_finite(energy_ev, "energy_ev").astype(float)
    f = check_finite(values, "values").astype(float)
    if E.ndim != 1 or E.shape != f.shape[-1:] or E.size < 3:
        raise InvalidInputError("need a 1-D grid of at least 3 energies and values with that last axis")
    if np.any(E <= 0):
        raise InvalidInputError("energies must be > 0 eV")
    order = np.argsort(E)
    E, f = E[order], f[..., order]
    if np.any(np.diff(E) <= 0):
        raise InvalidInputError("grid energies (wavelengths) must be distinct")
    return E, f


@numba.njit(cache=True)
def _pv_kernel(E, alpha, beta, x, I1, I0):
    """Segment sums of :func:`_pv_integrals` for coefficient rows ``alpha[p], beta[p]`` at points ``x``.

    ln|E_n − x| and ln(E_n + x) are taken once per node: the logarithms of the segment ends
    telescope (ln|b − x| of one segment is ln|a − x| of the next), half the work of taking
    them per segment, with no (points × segments) temporaries.
    """
    P, S = alpha.shape
    lm = np.empty(S + 1)
    lp = np.empty(S + 1)
    for i in range(x.size):
        xi = x[i]
        for n in range(S + 1):
            d = abs(E[n] - xi)
            lm[n] = np.log(d) if d > 0 else 0.0  # x at a node: the singular parts cancel
            lp[n] = np.log(E[n] + xi)
        for p in range(P):
            s1 = 0.0
            s0 = 0.0
            for j in range(S):
                log_minus = lm[j + 1] - lm[j]  # ln|b−x| − ln|a−x|
                log_plus = lp[j + 1] - lp[j]  # ln((b+x)/(a+x))
                c_m = (alpha[p, j] + beta[p, j] * xi) / 2
                c_p = (alpha[p, j] - beta[p, j] * xi) / 2
                s1 += beta[p, j] * (E[j + 1] - E[j]) + c_m * log_minus + c_p * log_plus
                s0 += c_m * log_minus - c_p * log_plus
            I1[p, i] = s1
            I0[p, i] = s0 / xi


def _pv_integrals(E, f, E_eval):
    """Exact principal values for piecewise-linear f on nodes E:

    I1(x) = P∫ E' f(E') / (E'² − x²) dE',   I0(x) = P∫ f(E') / (E'² − x²) dE'.

    On a segment [a, b] with f = α + βE', the partial fractions give
    I1 = β(b − a) + c₋ ln|(b − x)/(a − x)| + c₊ ln((b + x)/(a + x)), c± = (α ∓ βx)/2,
    and I0 = (c₋ ln|…| − c₊ ln(…))/x. Returns arrays of shape ``f.shape[:-1] + E_eval.shape``.
    """
    a, b = E[:-1], E[1:]
    beta = np.diff(f, axis=-1) / (b - a)
    alpha = f[..., :-1] - beta * a
    x_all = np.asarray(E_eval, dtype=float)
    lead = f.shape[:-1]
    S = a.size
    I1 = np.empty((int(np.prod(lead)), x_all.size))
    I0 = np.empty_like(I1)
    _pv_kernel(np.ascontiguousarray(E, dtype=float), np.ascontiguousarray(alpha.reshape(-1, S), dtype=float),
               np.ascontiguousarray(beta.reshape(-1, S), dtype=float), np.ascontiguousarray(x_all.ravel()), I1, I0)
    return I1.reshape(lead + x_all.shape), I0.reshape(lead + x_all.shape)


def _energy(wavelength_nm=None, energy_ev=None):
    if (wavelength_nm is None) == (energy_ev is None):
        raise InvalidInputError("give exactly one of wavelength_nm or energy_ev")
    if energy_ev is not None:
        return check_finite(energy_ev, "energy_ev").astype(float)
    return HC_EV_NM / as_wavelength_nm(wavelength_nm)


def eps1_from_eps2(eps2: ArrayLike, wavelength_nm: ArrayLike | None = None, *, energy_ev: ArrayLike | None = None,
                   eps_inf: ArrayLike = 1.0, at_energy_ev: ArrayLike | None = None) -> np.ndarray:
    """ε1 from ε2 sampled on a grid: ε1(E) = ε∞ + (2/π) P∫ E'ε2(E')/(E'² − E²) dE'.

    Evaluated at the grid points, or at ``at_energy_ev`` if given.
    """
    E = _energy(wavelength_nm, energy_ev)
    Es, f = _sorted_grid(E, eps2)
    x = E if at_energy_ev is None else np.asarray(at_energy_ev, dtype=float)
    I1, _ = _pv_integrals(Es, f, x)
    return eps_inf + 2 / np.pi * I1


def eps2_from_eps1(eps1: ArrayLike, wavelength_nm: ArrayLike | None = None, *, energy_ev: ArrayLike | None = None,
                   eps_inf: ArrayLike = 1.0, at_energy_ev: ArrayLike | None = None) -> np.ndarray:
    """ε2 from ε1 sampled on a grid: ε2(E) = −(2E/π) P∫ (ε1(E') − ε∞)/(E'² − E²) dE'."""
    E = _energy(wavelength_nm, energy_ev)
    Es, f = _sorted_grid(E, np.asarray(eps1, dtype=float) - eps_inf)
    x = E if at_energy_ev is None else np.asarray(at_energy_ev, dtype=float)
    _, I0 = _pv_integrals(Es, f, x)
    return -2 * x / np.pi * I0


def n_from_k(k: ArrayLike, wavelength_nm: ArrayLike | None = None, *, energy_ev: ArrayLike | None = None,
             n_inf: ArrayLike = 1.0, at_energy_ev: ArrayLike | None = None) -> np.ndarray:
    """n from k on a grid (KK relation for the complex index N − 1, Wooten 1972 §6.4)."""
    return eps1_from_eps2(k, wavelength_nm, energy_ev=energy_ev, eps_inf=n_inf, at_energy_ev=at_energy_ev)


@dataclass(frozen=True)
class KKReport:
    """Result of :func:`kk_consistency`.

    ``n`` is the material's index, ``n_kk`` the index implied by its k through the KK
    integral over the material's range plus a smooth background fitted by least squares
    (c0 + c_uv·E² + c_ir/E²: absorption outside the range, which the data cannot give).
    ``rms`` and ``max_abs`` measure |n − n_kk| over the central part of the range
    (``trim`` of each end excluded, where truncation dominates).
    """

    material: str
    wavelength_nm: np.ndarray
    n: np.ndarray
    n_kk: np.ndarray
    background: tuple[float, float, float]
    rms: float
    max_abs: float

    def consistent(self, tolerance: float = 0.02) -> bool:
        """True when the largest deviation of n is below ``tolerance``."""
        return bool(self.max_abs <= tolerance)

    def __str__(self):
        return (f"Kramers–Kronig consistency of '{self.material}': |n − n_KK| rms {self.rms:.2e}, "
                f"max {self.max_abs:.2e} over {self.wavelength_nm.min():g}–{self.wavelength_nm.max():g} nm")


def kk_consistency(material: Material, wavelength_nm: ArrayLike | None = None, n_points: int = 2000,
                   trim: float = 0.1) -> KKReport:
    """Check that a Material's n and k are linked by causality over its own range.

    The KK integral of k is computed over ``wavelength_nm`` (default: ``n_points`` points
    uniform in energy across the material's whole range), a smooth background
    c0 + c_uv·E² + c_ir/E² accounts for absorption outside the range, and the deviation
    of n from the result is reported. A material whose k was changed without changing n
    (or the reverse) shows a large deviation.
    """
    if wavelength_nm is None:
        lo, hi = material.range_nm
        if not np.isfinite(hi):
            hi = max(lo * 50, 20000.0) if lo > 0 else 20000.0
        lo = max(lo, 1.0)
        E = np.linspace(HC_EV_NM / hi, HC_EV_NM / lo, n_points)
        w = HC_EV_NM / E
    else:
        w = as_wavelength_nm(wavelength_nm)
        E = HC_EV_NM / w
    nk = material.nk(w)
    Es, k = _sorted_grid(E, nk.imag)
    order = np.argsort(E)
    n = nk.real[order]
    I1, _ = _pv_integrals(Es, k, Es)
    n_int = 2 / np.pi * I1
    m = Es.size
    core = slice(int(trim * m), m - int(trim * m))
    basis = np.stack([np.ones_like(Es), Es**2, 1 / Es**2], axis=-1)
    coef, *_ = np.linalg.lstsq(basis[core], (n - n_int)[core], rcond=None)
    n_kk = n_int + basis @ coef
    dev = np.abs(n - n_kk)[core]
    return KKReport(material.name, (HC_EV_NM / Es), n, n_kk, tuple(map(float, coef)),
                    float(np.sqrt(np.mean(dev**2))), float(dev.max()))
