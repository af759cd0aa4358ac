"""Lat-long environment maps on a plate: the non-Dirac BRDF terms integrated over cells of
the upper hemisphere (``_envmap_smooth``, a quadrature on a coarser grid of pixels,
interpolated back by ``_interp_axis``) and the smooth coat's mirror image of the map at
full resolution (``_mirror_env``, Numba).
"""

from __future__ import annotations

import numpy as np

from nmmm.errors import InvalidInputError

try:  # pragma: no cover - numba is a dependency, but keep a NumPy path
    import numba as _nb
except ImportError:  # pragma: no cover
    _nb = None


def _needs_numba(*args):  # pragma: no cover - only without numba
    raise InvalidInputError("discrete flakes (glints) need numba")


if _nb is not None:
    @_nb.njit(parallel=True, cache=True, fastmath=True)
    def _mirror_env(img, Fc, ri, rf, ci, cf, texel, on, env):
        """img += F(θo, λ) (bilinear from the coarse grid) × L_env(mirror direction)."""
        H = ri.size
        W = ci.size
        L = Fc.shape[2]
        for i in _nb.prange(H):
            r0 = ri[i]
            fr = rf[i]
            for j in range(W):
                if not on[i, j]:
                    continue
                c0 = ci[j]
                fc = cf[j]
                t = texel[i, j]
                for k in range(L):
                    F = ((1 - fr) * (1 - fc) * Fc[r0, c0, k] + fr * (1 - fc) * Fc[r0 + 1, c0, k]
                         + (1 - fr) * fc * Fc[r0, c0 + 1, k] + fr * fc * Fc[r0 + 1, c0 + 1, k])
                    img[i, j, k] += F * env[t, k]
else:  # pragma: no cover
    _mirror_env = _needs_numba


def _envmap_smooth(brdf, w, envmap, wo_grid, hit_grid, sub: int = 4, n_theta: int = 8, n_phi: int = 16):
    """Radiance reflected from a lat-long environment by the non-Dirac BRDF terms,
    ∑_k f(ω_k, ωo) cos θ_k ΔΩ_k L_k over n_theta × n_phi cells of the upper hemisphere,
    on every ``sub``-th node of the coarse grid, interpolated back onto it."""
    nr, nc = wo_grid.shape[:2]
    rs = np.unique(np.r_[np.arange(0, nr, sub), nr - 1])
    cs = np.unique(np.r_[np.arange(0, nc, sub), nc - 1])
    wo = wo_grid[np.ix_(rs, cs)].reshape(-1, 3)
    qd, qs, qr = envmap.upper_quadrature(w, n_theta, n_phi)
    out = np.zeros((wo.shape[0], w.size))
    comps = ("specular", "flakes", "base", "multiple")
    for k in range(qd.shape[0]):
        f = brdf.evaluate(w, np.broadcast_to(qd[k], wo.shape), wo, components=comps)
        out += f * (qd[k, 2] * qs[k] * qr[k])[None, :]
    out = out.reshape(rs.size, cs.size, w.size)
    # bilinear back onto the coarse grid (separable linear interpolation)
    res = _interp_axis(cs, _interp_axis(rs, out, nr, 0), nc, 1)
    return np.where(hit_grid[..., None], res, 0.0)


def _interp_axis(nodes, values, n, axis):
    """Linear interpolation of ``values`` given at integer ``nodes`` along ``axis`` onto 0..n-1."""
    if nodes.size == 1:
        return np.repeat(values, n, axis=axis)
    x = np.arange(n, dtype=float)
    i = np.clip(np.searchsorted(nodes, x, side="right") - 1, 0, nodes.size - 2)
    t = (x - nodes[i]) / (nodes[i + 1] - nodes[i])
    shape = [1] * values.ndim
    shape[axis] = n
    t = t.reshape(shape)
    return np.take(values, i, axis=axis) * (1 - t) + np.take(values, i + 1, axis=axis) * t
