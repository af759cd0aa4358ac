"""Bilinear lookup in a spectral latitude-longitude environment map: the four texel centres
around a direction and their weights (``_env_taps``, Numba, inlined into the plate renderer's
passes) and :func:`envmap_lookup_bilinear` (what
:meth:`~nmmm.appearance.render.LatLongEnvironment.lookup` returns). φ wraps around; the
horizon is a seam (a direction above it reads rows above it only), since the maps of a plate
scene change abruptly there (sky or booth walls above, ground or floor below).
"""

from __future__ import annotations

import math

import numpy as np

try:  # pragma: no cover - numba is a dependency, but keep a NumPy path
    import numba as _nb
except ImportError:  # pragma: no cover
    _nb = None


def _env_taps_py(dx, dy, dz, h, wd):
    """The four texels around a unit direction on an (h, wd) lat-long map and their bilinear
    weights: texel centres at θ = (i + ½) π / h, φ = (j + ½) 2π / wd; φ wraps around.
    The horizon is a seam: a direction above it (z ≥ 0) is interpolated between rows whose
    centres are above it only, one below between rows below (the sky or the booth's walls
    seen from the plate are not blended with the ground or floor across the horizon); θ is
    clamped to the outermost row centres (constant towards the poles and the seam)."""
    th = math.acos(min(max(dz, -1.0), 1.0))
    ph = math.atan2(dy, dx)
    if ph < 0.0:
        ph += 2.0 * math.pi
    y = th / math.pi * h - 0.5
    x = ph / (2.0 * math.pi) * wd - 0.5
    if dz >= 0.0:
        lo, hi = 0, (h - 1) // 2  # rows with centres at θ ≤ 90°
    else:
        lo, hi = h // 2, h - 1  # rows with centres at θ ≥ 90°
    if y <= lo:
        i0, i1, fy = lo, lo, 0.0
    elif y >= hi:
        i0, i1, fy = hi, hi, 0.0
    else:
        i0 = int(y)
        i1 = i0 + 1
        fy = y - i0
    xf = math.floor(x)
    fx = x - xf
    j0 = int(xf) % wd
    j1 = (j0 + 1) % wd
    return (i0 * wd + j0, i0 * wd + j1, i1 * wd + j0, i1 * wd + j1,
            (1.0 - fy) * (1.0 - fx), (1.0 - fy) * fx, fy * (1.0 - fx), fy * fx)


def _env_lookup_py(dirs, h, wd, env, out):
    """out (N, L) = the map ``env`` (h·wd, L) bilinearly interpolated along ``dirs`` (N, 3)."""
    L = env.shape[1]
    for p in _prange(dirs.shape[0]):
        t0, t1, t2, t3, a0, a1, a2, a3 = _env_taps(dirs[p, 0], dirs[p, 1], dirs[p, 2], h, wd)
        for k in range(L):
            out[p, k] = a0 * env[t0, k] + a1 * env[t1, k] + a2 * env[t2, k] + a3 * env[t3, k]


if _nb is not None:
    _prange = _nb.prange
    _env_taps = _nb.njit(inline="always", cache=True)(_env_taps_py)
    _env_lookup = _nb.njit(parallel=True, cache=True)(_env_lookup_py)
else:  # pragma: no cover
    _prange = range
    _env_taps = _env_taps_py
    _env_lookup = _env_lookup_py


def envmap_lookup_bilinear(envmap, wavelength_nm, directions) -> np.ndarray:
    """Radiance (..., L) of a :class:`~nmmm.appearance.render.LatLongEnvironment` seen along unit
    ``directions`` (..., 3), bilinear between the four nearest texel centres (φ periodic, θ
    clamped at the first/last row) instead of the nearest texel: no staircase where a
    smooth coat mirrors the booth's walls."""
    r = envmap._on(wavelength_nm)  # (h, wd, L) on the grid
    h, wd, L = r.shape
    d = np.asarray(directions, float)
    flat = np.ascontiguousarray(d.reshape(-1, 3))
    out = np.empty((flat.shape[0], L))
    _env_lookup(flat, h, wd, np.ascontiguousarray(r.reshape(-1, L), float), out)
    return out.reshape(d.shape[:-1] + (L,))
