"""The fused Numba kernels of :class:`~nmmm.appearance.brdf.PaintBRDF`: one pass over
direction pairs × wavelengths; the same equations as the NumPy paths (``method="numpy"``).

- ``_kernel`` — paints without a coat medium (:class:`~nmmm.appearance.brdf.tables._Tables`),
  the multiple lobe's azimuth modes added by a second pass (``ms_azimuth.add_azimuth_modes``).
- ``evaluate_effect`` / ``_effect_kernel`` — paints whose basecoat is a pigmented medium
  (:class:`~nmmm.appearance.brdf.effect_tables._EffectTables`), all four terms and the lobe's
  modes in one pass.
"""

from __future__ import annotations

import numpy as np

from nmmm.appearance.brdf.interpolation import _angle_pos_nb

try:  # pragma: no cover - numba is a dependency, the fallback only guards odd installs
    import numba as _nb

    _njit = _nb.njit(parallel=True, fastmath=True, cache=True)
    _prange = _nb.prange
except ImportError:  # pragma: no cover
    _nb = None


def _table_pos_py(c, step, n_nodes):
    """Node index and fraction of the angle arccos(c) (c clipped to [0, 1]) on a table of
    ``n_nodes`` nodes ``step`` degrees apart (the last interval is closed)."""
    return _angle_pos_nb(np.arccos(min(max(c, 0.0), 1.0)) * (180.0 / np.pi) / step, n_nodes)


if _nb is not None:
    _table_pos = _nb.njit(inline="always", fastmath=True, cache=True)(_table_pos_py)
else:  # pragma: no cover
    _table_pos = _table_pos_py


def _ggx_weight_py(ix, iy, iz, ox, oy, oz, alpha, step, n_nodes):
    """The rough coat's specular lobe per pair: D G / (4 cos θi cos θo) (GGX, Smith's separable G)
    and the position of the microfacet angle θ_d on the ``step``° Fresnel table -> (w, d0, fd)."""
    hx, hy, hz = ix + ox, iy + oy, iz + oz
    hn = np.sqrt(hx * hx + hy * hy + hz * hz)
    hx /= hn
    hy /= hn
    hz /= hn
    a2 = alpha * alpha
    dd = hz * hz * (a2 - 1.0) + 1.0
    ti2 = (1.0 - iz * iz) / (iz * iz)
    to2 = (1.0 - oz * oz) / (oz * oz)
    G = 4.0 / ((1.0 + np.sqrt(1.0 + a2 * ti2)) * (1.0 + np.sqrt(1.0 + a2 * to2)))
    d0, fd = _table_pos(ix * hx + iy * hy + iz * hz, step, n_nodes)
    return a2 / (np.pi * dd * dd) * G / (4.0 * iz * oz), d0, fd


if _nb is not None:
    _ggx_weight = _nb.njit(inline="always", fastmath=True, cache=True)(_ggx_weight_py)
else:  # pragma: no cover
    _ggx_weight = _ggx_weight_py


def _kernel_py(wi, wo, out, Fs, Tc, Rf, a_tab, den, step, dstep, n, alpha, tau, tau_e, ext, eext, kb, Dms,
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
        # external angles -> positions on the 0.5° tables (the lobe's amount Dms included)
        thi = np.arccos(min(iz, 1.0)) * deg
        tho = np.arccos(min(oz, 1.0)) * deg
        i0, fi = _angle_pos_nb(thi / step, NT)
        o0, fo = _angle_pos_nb(tho / step, NT)
        # coat specular lobe (GGX)
        spec_w = 0.0
        d0 = 0
        fd = 0.0
        if do_spec and alpha > 0.0:
            spec_w, d0, fd = _ggx_weight(ix, iy, iz, ox, oy, oz, alpha, step, NT)
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
                             + w_ms * (Dms[i0, l] * gi + Dms[i0 + 1, l] * fi)
                             * (Dms[o0, l] * go + Dms[o0 + 1, l] * fo) * Kms[l])
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
                             + w_ms * (Dms[i0, l] * gi + Dms[i0 + 1, l] * fi)
                             * (Dms[o0, l] * go + Dms[o0 + 1, l] * fo) * Kms[l])


if _nb is not None:
    _kernel = _njit(_kernel_py)
else:  # pragma: no cover
    _prange = range
    _kernel = _kernel_py


# -- paints with a coat medium ------------------------------------------------------------------

_Q_BLOCK = 64  # rows of the fine factor of the attenuation tables (_attenuation_factors)


def _attenuation_factors(c, s2_step, n_rows):
    """exp(−S' c) (c (L,)) at S' = 2 + j Δ, j < ``n_rows``, as ``hi[j // 64] · lo[j % 64]``:
    ``hi`` exp(−(2 + 64 k Δ) c) and ``lo`` exp(−i Δ c), i ≤ 64 (``lo[i + 1]`` is read at i = 63).
    The effect tables' ``_Qd``, ``_Qz``, ``_Qb`` (2048 × L, 1.3 MB each at 81 λ, a random row
    per pair) to within 3e-16 relative in 97 rows that stay in cache."""
    k = np.arange((n_rows + _Q_BLOCK - 1) // _Q_BLOCK)
    hi = np.exp(-np.outer(2.0 + s2_step * (_Q_BLOCK * k), c))
    lo = np.exp(-np.outer(s2_step * np.arange(_Q_BLOCK + 1), c))
    return np.ascontiguousarray(hi), np.ascontiguousarray(lo)


def _lobe_sums_py(C2, NA, a0, fa, b0, fb, cphi, K, M1, seg, lw, cm, sk, sl):
    """sl[l] = 1 + s(λ_l), s = c_0 + 2 Σ_m c_m cos(m φ) (≥ −1) linear in λ between the K node
    sums (``ms_azimuth._lobe_at_wavelengths``, same numbers): ``C2`` the shape tables mode-major,
    (NA·NA, M1·K) (:func:`_mode_major`), bilinear in θi, θo; cos(m φ) by the Chebyshev recursion
    (``cm``; cphi > 1: no azimuth); each mode added to the node sums ``sk`` in a loop over the
    nodes (it vectorises: a dot product per node did not); then the wavelength runs ``seg``.
    Arrays are indexed, not sliced: a view per pair cost more than the sums."""
    w00 = (1.0 - fa) * (1.0 - fb)
    w01 = (1.0 - fa) * fb
    w10 = fa * (1.0 - fb)
    w11 = fa * fb
    r = a0 * NA + b0
    for k in range(K):
        sk[k] = C2[r, k] * w00 + C2[r + 1, k] * w01 + C2[r + NA, k] * w10 + C2[r + NA + 1, k] * w11
    if cphi <= 1.0:
        c_prev, c_cur = 1.0, cphi
        for m in range(1, M1):
            cm[m] = 2.0 * c_cur
            c_prev, c_cur = c_cur, 2.0 * cphi * c_cur - c_prev
        for m in range(1, M1):
            c = cm[m]
            j0 = m * K
            for k in range(K):
                j = j0 + k
                sk[k] += c * (C2[r, j] * w00 + C2[r + 1, j] * w01 + C2[r + NA, j] * w10 + C2[r + NA + 1, j] * w11)
    for k in range(K):
        sk[k] = max(sk[k], -1.0)
    for q in range(seg.shape[0] - 1):
        s_lo = sk[q]
        ds = (sk[q + 1] if q + 1 < K else s_lo) - s_lo
        for l in range(seg[q], seg[q + 1]):
            sl[l] = 1.0 + (s_lo + ds * lw[l])


def _mode_major(C):
    """The lobe's shape tables (NA, NA, K, 1 + M) as (NA·NA, (1 + M)·K), mode-major, for
    :func:`_lobe_sums_py`; a (1, 1) zero table when there are none."""
    if C.shape[-1] == 0:
        return np.zeros((1, 1))
    return np.ascontiguousarray(np.swapaxes(C, 2, 3)).reshape(C.shape[0] * C.shape[1], C.shape[2] * C.shape[3])


if _nb is not None:
    _lobe_sums = _nb.njit(inline="always", fastmath=True, cache=True)(_lobe_sums_py)
else:  # pragma: no cover
    _lobe_sums = _lobe_sums_py


def _effect_kernel_py(wi, wo, out, Fs, Tc, Rf, a_tab, den, step, astep, dstep, n, alpha, tau, tau_e, ext, eext, kd,
                      Qd_hi, Qd_lo, Qz_hi, Qz_lo, Qb_hi, Qb_lo, s2_step, ns2, tau_e_const, has_z0, has_below, kb,
                      Dms, Kms, C2, K, seg, lw, do_spec, do_flakes, do_ms, chunk):
    """The terms of :mod:`~nmmm.appearance.brdf.effect_tables` per pair: the geometry, the
    lobe's node sums (:func:`_lobe_sums_py`), then a few short loops over wavelengths, each
    with few arrays so that it vectorises (``eb`` = e^−X, ``xb`` = X, ``acc`` = flakes +
    substrate under the coat, then the sum of the four terms). The flake layer's extinction
    τ_e S for opaque flakes (``tau_e_const``), else ``ext`` (NT, L) = τ a(μ) (1 − T̄(μ, λ)) per
    internal direction and ``eext`` = exp(−ext/μ) on the same nodes (``_Tables._ext_exp``); the
    pigments' attenuation exp(−c S') from :func:`_attenuation_factors`."""
    P = wi.shape[0]
    L = out.shape[1]
    NT = Fs.shape[0]
    NA = int(90.0 / astep + 0.5) + 1  # nodes of the lobe's shape tables (C2: NA·NA rows); Dms is on the 0.5° ones
    ND = den.shape[0]
    M1 = C2.shape[1] // K
    inv_n2 = 1.0 / (n * n)
    deg = 180.0 / np.pi
    n_chunks = (P + chunk - 1) // chunk
    for ch in _prange(n_chunks):  # chunks of pairs: per-chunk buffers
        sk = np.empty(K)
        cm = np.empty(M1)
        sl = np.ones(L)
        eb = np.empty(L)
        xb = np.empty(L)
        acc = np.empty(L)
        for p in range(ch * chunk, min(P, (ch + 1) * chunk)):
            ix, iy, iz = wi[p, 0], wi[p, 1], wi[p, 2]
            ox, oy, oz = wo[p, 0], wo[p, 1], wo[p, 2]
            if iz <= 0.0 or oz <= 0.0:
                for l in range(L):
                    out[p, l] = 0.0
                continue
            thi = np.arccos(min(iz, 1.0)) * deg
            tho = np.arccos(min(oz, 1.0)) * deg
            i0, fi = _angle_pos_nb(thi / step, NT)
            o0, fo = _angle_pos_nb(tho / step, NT)
            ai0, fai = _angle_pos_nb(thi / astep, NA)
            ao0, fao = _angle_pos_nb(tho / astep, NA)
            spec_w = 0.0
            d0 = 0
            fd = 0.0
            if do_spec and alpha > 0.0:
                spec_w, d0, fd = _ggx_weight(ix, iy, iz, ox, oy, oz, alpha, step, NT)
            ipx, ipy = ix / n, iy / n
            ipz = np.sqrt(max(1.0 - ipx * ipx - ipy * ipy, 0.0))
            opx, opy = ox / n, oy / n
            opz = np.sqrt(max(1.0 - opx * opx - opy * opy, 0.0))
            S2 = 1.0 / ipz + 1.0 / opz
            S = 0.0
            g = 0.0
            c0 = 0
            fc = 0.0
            ki, fki, ko, fko = 0, 0.0, 0, 0.0
            inv_i, inv_o = 0.0, 0.0
            if tau > 0.0:
                ki, fki = _table_pos(ipz, step, NT)
                a_i = a_tab[ki] * (1.0 - fki) + a_tab[ki + 1] * fki
                ko, fko = _table_pos(opz, step, NT)
                a_o = a_tab[ko] * (1.0 - fko) + a_tab[ko + 1] * fko
                S = a_i / ipz + a_o / opz
                inv_i, inv_o = 1.0 / ipz, 1.0 / opz
                if do_flakes:
                    hx, hy, hz = ipx + opx, ipy + opy, ipz + opz
                    hn = np.sqrt(hx * hx + hy * hy + hz * hz)
                    hz /= hn
                    t0, ft = _table_pos(hz, dstep, ND)
                    g = tau * (den[t0] * (1.0 - ft) + den[t0 + 1] * ft) / (4.0 * ipz * opz)
                    c0, fc = _table_pos((ipx * hx + ipy * hy) / hn + ipz * hz, step, NT)
            if do_ms:  # the lobe's polar shape and azimuth modes: sl = 1 + s(λ)
                cphi = 2.0  # > 1: no azimuth (a direction along the normal)
                if M1 > 1:
                    ri = np.sqrt(ix * ix + iy * iy)
                    ro = np.sqrt(ox * ox + oy * oy)
                    if ri > 1e-9 and ro > 1e-9:
                        cphi = min(max(-(ix * ox + iy * oy) / (ri * ro), -1.0), 1.0)
                _lobe_sums(C2, NA, ai0, fai, ao0, fao, cphi, K, M1, seg, lw, cm, sk, sl)
            # the pigments' attenuation at S': row js of the tables, as hi[js // 64] lo[js % 64] (_attenuation_factors)
            xs = min(max((S2 - 2.0) / s2_step, 0.0), ns2 - 1.000001)
            js = int(xs)
            fs = xs - js
            gs = 1.0 - fs
            jh = js // _Q_BLOCK
            jl = js - _Q_BLOCK * jh
            # e^−X (eb) and X (xb): the flake layer and the pigments of the flake band
            if tau_e_const:
                e_t0 = np.exp(-tau_e[0] * S)
                for l in range(L):
                    eb[l] = Qd_hi[jh, l] * (Qd_lo[jl, l] * gs + Qd_lo[jl + 1, l] * fs) * e_t0
                for l in range(L):
                    xb[l] = tau_e[l] * S + kd[l] * S2
            else:
                gki = 1.0 - fki
                gko = 1.0 - fko
                for l in range(L):
                    eb[l] = (Qd_hi[jh, l] * (Qd_lo[jl, l] * gs + Qd_lo[jl + 1, l] * fs)
                             * ((eext[ki, l] * gki + eext[ki + 1, l] * fki) * (eext[ko, l] * gko + eext[ko + 1, l] * fko)))
                for l in range(L):
                    xb[l] = ((ext[ki, l] * gki + ext[ki + 1, l] * fki) * inv_i
                             + (ext[ko, l] * gko + ext[ko + 1, l] * fko) * inv_o + kd[l] * S2)
            # flakes: g (1 − e^−X)/X R, under the pigments above the band
            gc = 1.0 - fc
            for l in range(L):
                acc[l] = g * (1.0 - eb[l]) / (xb[l] + 1e-300) * (Rf[c0, l] * gc + Rf[c0 + 1, l] * fc)
            if has_z0:
                for l in range(L):
                    acc[l] *= Qz_hi[jh, l] * (Qz_lo[jl, l] * gs + Qz_lo[jl + 1, l] * fs)
            # substrate: e^−X kb, under the pigments below the band
            if has_below:
                for l in range(L):
                    acc[l] += eb[l] * kb[l] * (Qb_hi[jh, l] * (Qb_lo[jl, l] * gs + Qb_lo[jl + 1, l] * fs))
            else:
                for l in range(L):
                    acc[l] += eb[l] * kb[l]
            # the coat in and out, the specular lobe, the multiple lobe
            gi = 1.0 - fi
            go = 1.0 - fo
            gd = 1.0 - fd
            for l in range(L):
                out[p, l] = ((Tc[i0, l] * gi + Tc[i0 + 1, l] * fi) * (Tc[o0, l] * go + Tc[o0 + 1, l] * fo) * inv_n2
                             * acc[l]
                             + spec_w * (Fs[d0, l] * gd + Fs[d0 + 1, l] * fd)
                             + (Dms[i0, l] * gi + Dms[i0 + 1, l] * fi) * (Dms[o0, l] * go + Dms[o0 + 1, l] * fo)
                             * Kms[l] * sl[l])


if _nb is not None:
    _effect_kernel = _nb.njit(parallel=True, fastmath=True, cache=True)(_effect_kernel_py)
else:  # pragma: no cover
    _effect_kernel = _effect_kernel_py


def evaluate_effect(tab, wi, wo, comps, out):
    """f (P, L) of a paint with a coat medium (``_EffectTables``) for the pairs wi, wo (P, 3)
    into ``out``, by :func:`_effect_kernel_py`; ``comps`` the terms (``paint_brdf.COMPONENTS``)."""
    from nmmm.appearance.brdf.ms_azimuth import _CHUNK_PAIRS, _node_runs, _node_weights

    L = tab.L
    Rf = tab.Rf if tab.has_flakes else np.zeros((2, L))
    a_tab = tab.a_tab if tab.has_flakes else np.zeros(2)
    den = tab.tilt.density if tab.has_flakes else np.zeros(2)
    dstep = (tab.tilt.tilt_deg[1] - tab.tilt.tilt_deg[0]) if tab.has_flakes else 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        kb = np.where(tab.rho > 0, tab.rho / (np.pi * (1 - tab.rho * tab.r_t)), 0.0)
    if "base" not in comps:
        kb = np.zeros(L)
    C = tab._ms_modes_spectral
    do_ms = "multiple" in comps and bool(np.any(tab.Kms > 0)) and C.shape[-1] > 0
    K = C.shape[2]
    c2 = getattr(tab, "_ms_mode_major", None)
    if c2 is None or c2[0] is not C:  # once per shape tables
        c2 = tab._ms_mode_major = (C, _mode_major(C))
    lk, lw = _node_weights(tab)
    kap = np.asarray(tab.kappa, float)
    Kms = np.asarray(tab.Kms, float) if "multiple" in comps else np.zeros(L)
    ns2 = tab._Qd.shape[0]
    q = getattr(tab, "_q_factors", None)
    if q is None or q[0] is not tab._Qd:  # once per tables: the factors of _Qd, _Qz, _Qb
        q = tab._q_factors = (tab._Qd,) + tuple(t for f in (tab.dz, tab.z0, 1.0 - tab.dz)
                                                for t in _attenuation_factors(kap * f, tab._s2_step, ns2))
    _effect_kernel(np.ascontiguousarray(wi), np.ascontiguousarray(wo), out, tab.Fs, tab.Tc, Rf, a_tab, den,
                   tab.step, tab.astep, dstep, tab.n, tab.alpha, tab.tau if tab.has_flakes else 0.0,
                   np.ascontiguousarray(tab.tau_e, float), tab.ext_tab, tab._ext_exp(), kap * tab.dz, *q[1:],
                   tab._s2_step, ns2, bool(tab.tau_e_const), tab.z0 > 0.0, tab.dz < 1.0,
                   np.ascontiguousarray(kb, float), np.ascontiguousarray(tab.Dms_fine), Kms, c2[1], K,
                   _node_runs(lk, K), lw.astype(float), "specular" in comps, "flakes" in comps and tab.has_flakes,
                   do_ms, _CHUNK_PAIRS)
