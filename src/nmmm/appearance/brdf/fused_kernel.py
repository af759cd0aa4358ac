"""The fused Numba kernel of :class:`~nmmm.appearance.brdf.PaintBRDF`: one pass over
direction pairs × wavelengths, no temporaries; the same equations as the NumPy path of
:class:`~nmmm.appearance.brdf.tables._Tables` (``method="numpy"``).
"""

from __future__ import annotations

import numpy as np

try:  # pragma: no cover - numba is a dependency, the fallback only guards odd installs
    import numba as _nb

    _njit = _nb.njit(parallel=True, fastmath=True, cache=True)
    _prange = _nb.prange
except ImportError:  # pragma: no cover
    _nb = None


def _table_pos_py(c, step, n_nodes):
    """Node index and fraction of the angle arccos(c) (c clipped to [0, 1]) on a table of
    ``n_nodes`` nodes ``step`` degrees apart (the last interval is closed)."""
    x = min(np.arccos(min(max(c, 0.0), 1.0)) * (180.0 / np.pi) / step, n_nodes - 1.000001)
    i = int(x)
    return i, x - i


if _nb is not None:
    _table_pos = _nb.njit(inline="always", fastmath=True, cache=True)(_table_pos_py)
else:  # pragma: no cover
    _table_pos = _table_pos_py


def _kernel_py(wi, wo, out, Fs, Tc, Rf, a_tab, den, step, astep, dstep, n, alpha, tau, tau_e, kb, Dms, Kms,
               do_spec, do_flakes, do_base, do_ms, tau_e_const):
    P = wi.shape[0]
    L = out.shape[1]
    NT = Fs.shape[0]
    NA = Dms.shape[0]
    ND = den.shape[0]
    inv_n2 = 1.0 / (n * n)
    for p in _prange(P):
        ix, iy, iz = wi[p, 0], wi[p, 1], wi[p, 2]
        ox, oy, oz = wo[p, 0], wo[p, 1], wo[p, 2]
        if iz <= 0.0 or oz <= 0.0:
            for l in range(L):
                out[p, l] = 0.0
            continue
        # external angles -> table positions
        i0, fi = _table_pos(iz, step, NT)
        o0, fo = _table_pos(oz, step, NT)
        ai0, fai = _table_pos(iz, astep, NA)
        ao0, fao = _table_pos(oz, astep, NA)
        # coat specular lobe (GGX)
        spec_w = 0.0
        d0 = 0
        fd = 0.0
        if do_spec and alpha > 0.0:
            hx, hy, hz = ix + ox, iy + oy, iz + oz
            hn = np.sqrt(hx * hx + hy * hy + hz * hz)
            hx /= hn
            hy /= hn
            hz /= hn
            cd = ix * hx + iy * hy + iz * hz
            a2 = alpha * alpha
            dd = hz * hz * (a2 - 1.0) + 1.0
            D = a2 / (np.pi * dd * dd)
            ti2 = (1.0 - iz * iz) / (iz * iz)
            to2 = (1.0 - oz * oz) / (oz * oz)
            G = 4.0 / ((1.0 + np.sqrt(1.0 + a2 * ti2)) * (1.0 + np.sqrt(1.0 + a2 * to2)))
            spec_w = D * G / (4.0 * iz * oz)
            d0, fd = _table_pos(cd, step, NT)
        # internal directions (Snell)
        ipx, ipy = ix / n, iy / n
        ipz = np.sqrt(max(1.0 - ipx * ipx - ipy * ipy, 0.0))
        opx, opy = ox / n, oy / n
        opz = np.sqrt(max(1.0 - opx * opx - opy * opy, 0.0))
        S = 0.0
        g = 0.0
        c0 = 0
        fc = 0.0
        if tau > 0.0:
            k0, fa = _table_pos(ipz, step, NT)
            a_i = a_tab[k0] * (1.0 - fa) + a_tab[k0 + 1] * fa
            k0, fa = _table_pos(opz, step, NT)
            a_o = a_tab[k0] * (1.0 - fa) + a_tab[k0 + 1] * fa
            S = a_i / ipz + a_o / opz
            if do_flakes:
                hx, hy, hz = ipx + opx, ipy + opy, ipz + opz
                hn = np.sqrt(hx * hx + hy * hy + hz * hz)
                hz /= hn
                cdl = (ipx * hx + ipy * hy) / hn + ipz * hz
                t0, ft = _table_pos(hz, dstep, ND)
                pdf = den[t0] * (1.0 - ft) + den[t0 + 1] * ft
                g = tau * pdf / (4.0 * ipz * opz)
                c0, fc = _table_pos(cdl, step, NT)
        # flakes that block no light (tau_e = const over wavelength): one exp per pair
        x0 = tau_e[0] * S
        e0 = np.exp(-x0)
        ph0 = 1.0 - 0.5 * x0 if x0 < 1e-6 else (1.0 - e0) / x0
        for l in range(L):
            val = 0.0
            if spec_w > 0.0:
                val += spec_w * (Fs[d0, l] * (1.0 - fd) + Fs[d0 + 1, l] * fd)
            sub = 0.0
            if do_flakes or do_base:
                if tau_e_const:
                    x = x0
                    e = e0
                else:
                    x = tau_e[l] * S
                    e = np.exp(-x)
                if do_flakes and g > 0.0:
                    if tau_e_const:
                        ph = ph0
                    else:
                        ph = 1.0 - 0.5 * x if x < 1e-6 else (1.0 - e) / x
                    sub += g * ph * (Rf[c0, l] * (1.0 - fc) + Rf[c0 + 1, l] * fc)
                if do_base:
                    sub += e * kb[l]
                if sub != 0.0:
                    Ti = Tc[i0, l] * (1.0 - fi) + Tc[i0 + 1, l] * fi
                    To = Tc[o0, l] * (1.0 - fo) + Tc[o0 + 1, l] * fo
                    val += Ti * To * inv_n2 * sub
            if do_ms:
                val += ((Dms[ai0, l] * (1.0 - fai) + Dms[ai0 + 1, l] * fai)
                        * (Dms[ao0, l] * (1.0 - fao) + Dms[ao0 + 1, l] * fao) * Kms[l])
            out[p, l] = val


if _nb is not None:
    _kernel = _njit(_kernel_py)
else:  # pragma: no cover
    _prange = range
    _kernel = _kernel_py
