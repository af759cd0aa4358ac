"""The smooth part of a plate image (every BRDF term but the glints) is evaluated on a
coarse grid of pixels and interpolated bilinearly onto the full image: ``_bilinear``
(Numba, parallel over rows; ``_bilinear_py`` the NumPy equivalent). ``accumulate_light`` and
``add_environment`` fill the coarse grid in one pass each, in float32, without the
(pixels × wavelengths) float64 temporaries of the NumPy expressions.
"""

from __future__ import annotations

import numpy as np

try:  # pragma: no cover - numba is a dependency, but keep a NumPy path
    import numba as _nb
except ImportError:  # pragma: no cover
    _nb = None


def _bilinear_py(coarse, ri, rf, ci, cf, out):
    a = coarse[ri][:, ci]
    b = coarse[ri + 1][:, ci]
    c = coarse[ri][:, ci + 1]
    d = coarse[ri + 1][:, ci + 1]
    fr = rf[:, None, None]
    fc = cf[None, :, None]
    out[:] = (a * (1 - fr) * (1 - fc) + b * fr * (1 - fc) + c * (1 - fr) * fc + d * fr * fc)


if _nb is not None:
    @_nb.njit(parallel=True, cache=True, fastmath=True)
    def _bilinear(coarse, ri, rf, ci, cf, out):
        H = ri.size
        W = ci.size
        L = coarse.shape[2]
        for i in _nb.prange(H):
            r0 = ri[i]
            fr = rf[i]
            for j in range(W):
                c0 = ci[j]
                fc = cf[j]
                w00 = (1 - fr) * (1 - fc)
                w10 = fr * (1 - fc)
                w01 = (1 - fr) * fc
                w11 = fr * fc
                for k in range(L):
                    out[i, j, k] = (w00 * coarse[r0, c0, k] + w10 * coarse[r0 + 1, c0, k]
                                    + w01 * coarse[r0, c0 + 1, k] + w11 * coarse[r0 + 1, c0 + 1, k])
else:  # pragma: no cover
    _bilinear = _bilinear_py


if _nb is not None:
    @_nb.njit(parallel=True, cache=True)
    def _accumulate_light_nb(out, f, s, sp, first):
        N, L = f.shape
        for p in _nb.prange(N):
            sc = s[p]
            for k in range(L):
                v = f[p, k] * sc * sp[k]
                out[p, k] = v if first else out[p, k] + v

    @_nb.njit(parallel=True, cache=True)
    def _add_albedo_nb(out, A, th, step, env, first):
        N, L = out.shape
        n = A.shape[0]
        for p in _nb.prange(N):
            x = min(max(th[p] / step, 0.0), n - 1.000001)  # as brdf.interpolation._lerp_table
            i = int(x)
            fr = x - i
            for k in range(L):
                v = (A[i, k] * (1.0 - fr) + A[i + 1, k] * fr) * env[k]
                out[p, k] = v if first else out[p, k] + v


def accumulate_light(out, f, s, sp, first: bool):
    """``out (N, L) float32 (+)= f (N, L) · s (N,) · sp (L,)`` (one light's BRDF × irradiance)."""
    s = np.ascontiguousarray(s, dtype=float).ravel()
    sp = np.ascontiguousarray(sp, dtype=float).ravel()
    if _nb is None:  # pragma: no cover
        v = f * s[:, None] * sp[None, :]
        out[...] = v if first else out + v
        return
    _accumulate_light_nb(out, np.ascontiguousarray(f), s, sp, first)


def add_environment(out, brdf, w, wo, env, first: bool):
    """``out (+)= albedo(wo) · env`` for a uniform environment. A :class:`PaintBRDF`'s albedo is
    piecewise linear in θ on its table's uniform grid, so it is evaluated once on that grid's
    nodes and interpolated per pixel in the same pass (the same values as ``brdf.albedo``);
    other BRDFs go through ``brdf.albedo``."""
    from nmmm.appearance.brdf import PaintBRDF

    env = np.ascontiguousarray(env, dtype=float)
    tab = brdf.prepare(w) if isinstance(brdf, PaintBRDF) and type(brdf).albedo is PaintBRDF.albedo else None
    step = getattr(tab, "step", None)
    if _nb is None or step is None:
        v = brdf.albedo(w, wo) * env[None, :]
        out[...] = v if first else out + v
        return
    n = tab.Tc.shape[0]  # the albedo is linear between the nodes of its 0.5° table (albedo_nodes)
    th_nodes = np.radians(np.arange(n) * step)
    nodes = np.stack([np.sin(th_nodes), np.zeros(n), np.cos(th_nodes)], axis=-1)
    nodes[-1] = (1.0, 0.0, 0.0)
    A = np.ascontiguousarray(brdf.albedo(w, nodes), dtype=float)
    th = np.degrees(np.arccos(np.clip(wo[:, 2], 0.0, 1.0)))
    _add_albedo_nb(out, A, np.ascontiguousarray(th), float(step), env, first)
