"""A smooth, Kramers–Kronig-consistent correction of a compound's k(λ) (calibration, issue 17).

- :func:`k_correction_factor` — the factor f(λ) = s · exp(Σ_j c_j P_j(x)) that multiplies k(λ):
  s the overall k scale, P_j the Legendre polynomials (j = 1 … 3) of the wavelength mapped onto
  x ∈ [−1, 1] over the calibration window (held at the window's ends beyond it): a correction of
  ln k that is a scale (s), a tilt (c_1), a bow (c_2) and an S-shape (c_3) — smooth by
  construction, with as few unknowns as a ladder can fix.
- :func:`kk_delta_n` — Δn(λ) = (2/π) P∫ E'Δk(E')/(E'² − E²) dE', the index change that a change Δk
  of the absorption implies by causality (:func:`nmmm.materials.kramers_kronig.n_from_k`).
- :func:`corrected_nk` — n + Δn + i·f·k: the corrected compound; n and k stay linked by
  Kramers–Kronig (the change of n is the transform of the change of k over the grid given, held
  at its end values 50 % beyond it; absorption farther out is unchanged).
- :func:`corrected_material_nk` — the same for a Material, the KK integral taken on a fine grid
  (``step_nm``) of the material itself, so a coarse measurement grid and a finer file agree.

The KK integral runs over the sampling grid extended by 50 % on each side with Δk held at its end
values (a window wider than the data, so the transform is not truncated at the ends of the visible;
the tails beyond are a modelling choice stated here, and their effect is smooth and small inside:
for hematite on 400–700 nm, against the transform of f·k over the database's whole 210–5000 nm
with f held beyond the window, Δn differs by 0.01–0.05 (largest Δn 0.18–0.46; three corrections),
all but 0.0004–0.003 of it a smooth background c0 + c_uv E² + c_ir/E²).

References
----------
- F. Wooten, *Optical Properties of Solids*, Academic Press (1972), §6.4 (KK for N − 1).
- D. Y. Smith, "Dispersion theory, sum rules, and their application to the analysis of optical
  data", in E. D. Palik (ed.), *Handbook of Optical Constants of Solids*, Academic Press (1985),
  ch. 3 (KK corrections of partial data).
"""

from __future__ import annotations

import numpy as np
from numpy.polynomial import legendre

__all__ = ["K_LEGENDRE_TERMS", "k_correction_factor", "kk_delta_n", "corrected_nk", "corrected_material_nk"]

#: Names of the Legendre coefficients of the ln k correction (calibration parameters).
K_LEGENDRE_TERMS = ("k_legendre_1", "k_legendre_2", "k_legendre_3")


def _x(wavelength_nm, window_nm):
    lo, hi = float(window_nm[0]), float(window_nm[1])
    if hi <= lo:
        return np.zeros_like(np.asarray(wavelength_nm, float))
    return np.clip(2 * (np.asarray(wavelength_nm, float) - lo) / (hi - lo) - 1, -1.0, 1.0)


def k_correction_factor(wavelength_nm, window_nm, k_scale: float = 1.0, coefficients=()) -> np.ndarray:
    """f(λ) = k_scale · exp(Σ_j c_j P_j(x)), x the wavelength mapped onto [−1, 1] over ``window_nm``
    (module docstring); ``coefficients`` are c_1, c_2, … (at most three).

    Examples
    --------
    >>> k_correction_factor([400.0, 550.0, 700.0], (400, 700), 1.2, (0.1,)).round(4).tolist()
    [1.0858, 1.2, 1.3262]
    """
    x = _x(wavelength_nm, window_nm)
    c = np.concatenate([[0.0], np.asarray(coefficients, float)])
    return float(k_scale) * np.exp(legendre.legval(x, c))


def kk_delta_n(wavelength_nm, delta_k) -> np.ndarray:
    """The KK transform of ``delta_k`` on ``wavelength_nm`` (n∞ contribution 0), over the grid
    extended by 50 % on each side with ``delta_k`` held at its end values (module docstring)."""
    from nmmm.materials.kramers_kronig import n_from_k

    w = np.asarray(wavelength_nm, float)
    dk = np.asarray(delta_k, float)
    order = np.argsort(w)
    ws, dks = w[order], dk[order]
    span = max(ws[-1] - ws[0], 1.0)
    fine = np.linspace(max(ws[0] - 0.5 * span, 50.0), ws[-1] + 0.5 * span, 600)
    kf = np.interp(fine, ws, dks)
    return np.interp(w, fine, np.asarray(n_from_k(kf, fine, n_inf=1.0)) - 1.0)


def corrected_nk(wavelength_nm, nk0, window_nm=None, k_scale: float = 1.0, coefficients=()) -> np.ndarray:
    """The compound ``nk0`` (complex n + ik on ``wavelength_nm``) with k multiplied by
    :func:`k_correction_factor` and n changed by :func:`kk_delta_n` of the change of k.

    Examples
    --------
    No correction leaves the compound as it is:

    >>> w = np.array([400.0, 500.0, 600.0, 700.0])
    >>> bool(np.allclose(corrected_nk(w, 2.5 + 0.1j * np.ones(4)), 2.5 + 0.1j))
    True
    """
    w = np.asarray(wavelength_nm, float)
    nk0 = np.asarray(nk0, complex)
    window = (w.min(), w.max()) if window_nm is None else window_nm
    k0 = nk0.imag
    dk = (k_correction_factor(w, window, k_scale, coefficients) - 1.0) * k0
    return (nk0.real + kk_delta_n(w, dk)) + 1j * (k0 + dk)


def corrected_material_nk(material, wavelength_nm, window_nm, k_scale: float = 1.0, coefficients=(),
                          step_nm: float = 5.0) -> np.ndarray:
    """:func:`corrected_nk` of ``material`` at ``wavelength_nm``, Δn computed from Δk sampled at
    ``step_nm`` over the window and the requested wavelengths (then interpolated): inside the window
    the result at a wavelength does not depend on which other wavelengths are asked for, unless some
    lie outside it (they extend the grid of the KK integral, and so change Δn everywhere)."""
    w = np.asarray(wavelength_nm, float)
    lo, hi = min(float(window_nm[0]), w.min()), max(float(window_nm[1]), w.max())
    fine = np.unique(np.concatenate([np.arange(lo, hi, float(step_nm)), [hi]]))
    k0f = np.asarray(material.nk(fine)).imag
    dkf = (k_correction_factor(fine, window_nm, k_scale, coefficients) - 1.0) * k0f
    nk0 = np.asarray(material.nk(w), complex)
    dn = np.interp(w, fine, kk_delta_n(fine, dkf))
    return (nk0.real + dn) + 1j * nk0.imag * k_correction_factor(w, window_nm, k_scale, coefficients)
