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


def _angle_pos(x, n_nodes):
    """Node index and fraction of position ``x`` (angle / step) on ``n_nodes`` nodes (last interval closed)."""
    x = min(max(x, 0.0), n_nodes - 1.000001)
    i = int(x)
    return i, x - i


if _nb is not None:
    _angle_pos_nb = _nb.njit(inline="always", fastmath=True, cache=True)(_angle_pos)
else:  # pragma: no cover
    _angle_pos_nb = _angle_pos


def _kernel_py(wi, wo, out, Fs, Tc, Rf, a_tab, den, step, astep, dstep, n, alpha, tau, tau_e, ext, eext, kb, Dms,
               Kms, do_spec, do_flakes, do_base, do_ms, tau_e_const):
    """Per pair the geometry (table positions and per-pair weights) first, then one branch-free
    loop over wavelengths (the terms a paint lacks enter with weight 0, ``Rf`` then a (2, L)
    table of zeros), so that the wavelength loop vectorises. Opaque flakes (``tau_e_const``):
    extinction τ_e S; flakes that transmit: ``ext`` (NT, L) = τ a(μ) (1 − T̄(μ, λ)) along each
    internal direction (``_Tables.optical_path``) and ``eext`` = exp(−ext/μ) on the same nodes
    (``_Tables._ext_exp``: the transmission in and out interpolated, no exp per wavelength)."""
    P = wi.shape[0]
    L = out.shape[1]
    NT = Fs.shape[0]
    NA = Dms.shape[0]
    ND = den.shape[0]
    NR = Rf.shape[0]
    inv_n2 = 1.0 / (n * n)
    deg = 180.0 / np.pi
    w_ms = 1.0 if do_ms else 0.0
    w_base = 1.0 if do_base else 0.0
    for p in _prange(P):
        ix, iy, iz = wi[p, 0], wi[p, 1], wi[p, 2]
        ox, oy, oz = wo[p, 0], wo[p, 1], wo[p, 2]
        if iz <= 0.0 or oz <= 0.0:
            for l in range(L):
                out[p, l] = 0.0
            continue
        # external angles -> positions on the 0.5° tables and the 2° albedo tables
        thi = np.arccos(min(iz, 1.0)) * deg
        tho = np.arccos(min(oz, 1.0)) * deg
        i0, fi = _angle_pos_nb(thi / step, NT)
        o0, fo = _angle_pos_nb(tho / step, NT)
        ai0, fai = _angle_pos_nb(thi / astep, NA)
        ao0, fao = _angle_pos_nb(tho / astep, NA)
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
        ki, fki, ko, fko = 0, 0.0, 0, 0.0
        if tau > 0.0:
            ki, fki = _table_pos(ipz, step, NT)
            a_i = a_tab[ki] * (1.0 - fki) + a_tab[ki + 1] * fki
            ko, fko = _table_pos(opz, step, NT)
            a_o = a_tab[ko] * (1.0 - fko) + a_tab[ko + 1] * fko
            S = a_i / ipz + a_o / opz
            if do_flakes:
                hx, hy, hz = ipx + opx, ipy + opy, ipz + opz
                hn = np.sqrt(hx * hx + hy * hy + hz * hz)
                hz /= hn
                cdl = (ipx * hx + ipy * hy) / hn + ipz * hz
                t0, ft = _table_pos(hz, dstep, ND)
                pdf = den[t0] * (1.0 - ft) + den[t0 + 1] * ft
                g = tau * pdf / (4.0 * ipz * opz)
                c0, fc = _table_pos(cdl, step, NR)
        gi = 1.0 - fi
        go = 1.0 - fo
        gai = 1.0 - fai
        gao = 1.0 - fao
        gd = 1.0 - fd
        gc = 1.0 - fc
        if tau_e_const:
            # flakes that block no light (tau_e the same at every wavelength): one exp per pair
            x0 = tau_e[0] * S
            e0 = np.exp(-x0)
            ph0 = 1.0 - 0.5 * x0 if x0 < 1e-6 else (1.0 - e0) / x0
            w_fl = g * ph0 * inv_n2
            w_b = e0 * w_base * inv_n2
            for l in range(L):
                tt = (Tc[i0, l] * gi + Tc[i0 + 1, l] * fi) * (Tc[o0, l] * go + Tc[o0 + 1, l] * fo)
                out[p, l] = (spec_w * (Fs[d0, l] * gd + Fs[d0 + 1, l] * fd)
                             + tt * (w_fl * (Rf[c0, l] * gc + Rf[c0 + 1, l] * fc) + w_b * kb[l])
                             + w_ms * (Dms[ai0, l] * gai + Dms[ai0 + 1, l] * fai)
                             * (Dms[ao0, l] * gao + Dms[ao0 + 1, l] * fao) * Kms[l])
        else:
            inv_i = 1.0 / ipz if tau > 0.0 else 0.0
            inv_o = 1.0 / opz if tau > 0.0 else 0.0
            for l in range(L):
                x = ((ext[ki, l] * (1.0 - fki) + ext[ki + 1, l] * fki) * inv_i
                     + (ext[ko, l] * (1.0 - fko) + ext[ko + 1, l] * fko) * inv_o)
                e = ((eext[ki, l] * (1.0 - fki) + eext[ki + 1, l] * fki)
                     * (eext[ko, l] * (1.0 - fko) + eext[ko + 1, l] * fko))
                ph = 1.0 - 0.5 * x if x < 1e-6 else (1.0 - e) / x
                tt = (Tc[i0, l] * gi + Tc[i0 + 1, l] * fi) * (Tc[o0, l] * go + Tc[o0 + 1, l] * fo) * inv_n2
                out[p, l] = (spec_w * (Fs[d0, l] * gd + Fs[d0 + 1, l] * fd)
                             + tt * (g * ph * (Rf[c0, l] * gc + Rf[c0 + 1, l] * fc) + e * w_base * kb[l])
                             + w_ms * (Dms[ai0, l] * gai + Dms[ai0 + 1, l] * fai)
                             * (Dms[ao0, l] * gao + Dms[ao0 + 1, l] * fao) * Kms[l])


if _nb is not None:
    _kernel = _njit(_kernel_py)
else:  # pragma: no cover
    _prange = range
    _kernel = _kernel_py
