"""The smooth part of a plate image (every BRDF term but the glints) is evaluated on a
coarse grid of pixels and interpolated bilinearly onto the full image: ``_bilinear``
(Numba, parallel over rows; ``_bilinear_py`` the NumPy equivalent).
"""

from __future__ import annotations

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
