"""Angle tables of the paint BRDF: uniform grids over 0–90° and their linear interpolation.

The BRDF's per-wavelength tables (Fresnel, coat transmission, flake reflectance, albedos)
are sampled on uniform angle grids and read back by linear interpolation; these helpers
are shared by the table builder, the NumPy path and the discrete-flake code.

- ``_NT``, ``_NA`` — nodes of the 1-D angle tables (0.5°) and of the albedo tables (2°).
- ``_refine_deficit`` — the multiple lobe's amount 1 − E⁰(θ) from the 2° albedo nodes onto the
  0.5° nodes of the 1-D tables, as T(θ) G(θ) with G = (1 − E⁰)/T interpolated (see there).
- ``_lerp_table`` — (NT, L) table at angles (P,) → (P, L) (Numba loop for large inputs).
- ``_lerp1`` — the same for a 1-D table; ``_deg`` — arccos in degrees.
- ``_angle_pos_nb`` — node index and fraction of an angle on such a grid, inside the Numba kernels.
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


def _refine_deficit(D, T, astep, Tc, step, R=None, Rc=None):
    """The lobe's amount D = 1 − E⁰ (NA, L) on the albedo nodes (``astep``) -> on the nodes of the
    coat's transmission table ``Tc`` (NT, L; ``step``), the grid the kernels read T(θ) on.

    E⁰ = R(θ) + T(θ) g(θ'), with g the single terms under the coat, so D = T(θ) G(θ), G = 1 − g
    for a clear coat (T = 1 − R): the Fresnel curvature of T near grazing is in T, and G is smooth.
    Interpolating D itself linearly on 2° nodes missed that curvature: a lossless effect coat's
    white furnace was 3–5e-3 off between nodes at 85–89° (tests/appearance/test_brdf_furnace_grazing.py).
    So G = D / T is interpolated and multiplied by T on the fine nodes; at 90° (T ≈ 0, where the
    tables set E⁰ = R) G is extrapolated from the two nodes before. On the albedo nodes (a subset of the fine ones) the
    result is D itself.

    The single terms' albedo E = R + T g is refined the same way with the coat's reflectance
    ``R`` (NA, L) on the albedo nodes and ``Rc`` (NT, L) on the fine ones: E = Rc + Tc G."""
    D = np.asarray(D, float) - (0.0 if R is None else np.asarray(R, float))
    T = np.asarray(T, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        G = np.where(T > 1e-12, D / np.where(T > 1e-12, T, 1.0), 0.0)
    if G.shape[0] >= 3:  # at 90° T ≈ 0 and the tables set E⁰ = R there (G = 1): its limit instead
        G[-1] = 2.0 * G[-2] - G[-3]
    th = np.arange(Tc.shape[0]) * step
    if R is not None:
        return Rc + Tc * _lerp_table(G, th, astep)
    return np.clip(Tc * _lerp_table(G, th, astep), 0.0, 1.0)


def _angle_pos(x, n_nodes):
    """Node index and fraction of position ``x`` (angle / step) on ``n_nodes`` nodes (last interval closed)."""
    x = min(max(x, 0.0), n_nodes - 1.000001)
    i = int(x)
    return i, x - i


if _nb is not None:
    _angle_pos_nb = _nb.njit(inline="always", fastmath=True, cache=True)(_angle_pos)
else:  # pragma: no cover
    _angle_pos_nb = _angle_pos
