"""Angle tables of the paint BRDF: uniform grids over 0–90° and their linear interpolation.

The BRDF's per-wavelength tables (Fresnel, coat transmission, flake reflectance, albedos)
are sampled on uniform angle grids and read back by linear interpolation; these helpers
are shared by the table builder, the NumPy path and the discrete-flake code.

- ``_NT``, ``_NA`` — nodes of the 1-D angle tables (0.5°) and of the albedo tables (2°).
- ``_lerp_table`` — (NT, L) table at angles (P,) → (P, L) (Numba loop for large inputs).
- ``_lerp1`` — the same for a 1-D table; ``_deg`` — arccos in degrees.
- ``_phi_mean`` — (1 − e⁻ˣ)/x, the mean attenuation through a slab.
- ``_hemi_mean`` — cosine-weighted hemispherical mean 2∫ v(μ) μ dμ.
"""

from __future__ import annotations

import numpy as np

try:  # pragma: no cover - numba is a dependency, the fallback only guards odd installs
    import numba as _nb
except ImportError:  # pragma: no cover
    _nb = None

_NT = 181  # angle nodes of the 1-D tables (0.5 deg)
_NA = 46  # incidence nodes of the albedo tables (2 deg)


def _lerp_table_np(table, theta_deg, step_deg):
    x = np.clip(theta_deg / step_deg, 0.0, table.shape[0] - 1.000001)
    i = x.astype(np.intp)
    f = (x - i)[:, None]
    return table[i] * (1.0 - f) + table[i + 1] * f


def _lerp_table_loop(table, theta_deg, step_deg, out):
    n = table.shape[0]
    for p in range(theta_deg.shape[0]):
        x = min(max(theta_deg[p] / step_deg, 0.0), n - 1.000001)
        i = int(x)
        f = x - i
        for l in range(table.shape[1]):
            out[p, l] = table[i, l] * (1.0 - f) + table[i + 1, l] * f


def _lerp_table(table, theta_deg, step_deg):
    """Linear interpolation of ``table`` (NT, L) at angles ``theta_deg`` (P,) on a uniform
    grid of step ``step_deg`` -> (P, L)."""
    theta_deg = np.ascontiguousarray(theta_deg, dtype=float).ravel()
    if _lerp_nb is None or theta_deg.size * table.shape[1] < 4096:
        return _lerp_table_np(table, theta_deg, step_deg)
    out = np.empty((theta_deg.size, table.shape[1]))
    _lerp_nb(np.ascontiguousarray(table, dtype=float), theta_deg, float(step_deg), out)
    return out


def _lerp1(table, theta_deg, step_deg):
    x = np.clip(theta_deg / step_deg, 0.0, table.shape[0] - 1.000001)
    i = x.astype(np.intp)
    f = x - i
    return table[i] * (1.0 - f) + table[i + 1] * f


def _deg(mu):
    return np.degrees(np.arccos(np.clip(mu, 0.0, 1.0)))


def _phi_mean(x):
    """(1 − exp(−x))/x, 1 at x = 0."""
    x = np.asarray(x, float)
    small = x < 1e-8
    xs = np.where(small, 1.0, x)
    return np.where(small, 1.0 - 0.5 * x, -np.expm1(-xs) / xs)


def _hemi_mean(values, mu):
    """2 ∫ v(μ) μ dμ over a table given at the (decreasing) cosines ``mu``."""
    order = np.argsort(mu)
    return 2 * np.trapezoid(values[order] * mu[order][:, None], mu[order], axis=0)


if _nb is not None:
    _lerp_nb = _nb.njit(cache=True)(_lerp_table_loop)
else:  # pragma: no cover
    _lerp_nb = None
