"""Azimuth dependence of the multiple-scattering lobe of :class:`~nmmm.appearance.brdf.PaintBRDF`.

The lobe of term 4, f_ms⁰ = (1 − E⁰(θi))(1 − E⁰(θo)) / (π (1 − Ē⁰)) · F_ms, is the azimuthal
mean (0th Fourier mode) of the multiply scattered light. Multiply scattered light in a flake
layer keeps a memory of the incidence azimuth — two mirror reflections off nearly parallel
flakes send it on towards the specular side — so the lobe is completed by its Fourier modes

    f_ms(θi, θo, φ) = f_ms⁰(θi, θo) · [1 + 2 Σ_{m=1}^{M} c_m(θi, θo) cos(m φ)],

φ the azimuth between ωo and the mirror direction of ωi. The ratios c_m = M_m / M_0 are the
Fourier modes of the multiply scattered part M of the coat's internal reflection, from
adding–doubling per Fourier mode (van de Hulst 1980, ch. 5; Hovenier et al. 2004, §6.3: the
azimuthal modes of a plane-parallel medium decouple and each is added like the 0th): the
flake kernel expanded in cos(m φ), the Lambertian base coupling only m = 0, the coat's
underside mirroring all modes. M = (all orders) − (one flake, no coat reflection) − (no
flake at all) — exactly the light the terms 2–3 leave to term 4.

Since ∫ cos(m φ) dφ = 0 the modes add no energy: the albedo tables (E1, Dms, F_ms) and the
white-furnace property are untouched; c_m(θi, θo) = c_m(θo, θi) keeps reciprocity. The sum
is clipped at −1 (no negative radiance from the truncated series; it never bites for the
paints tested).

References
----------
- H. C. van de Hulst, *Multiple Light Scattering*, vol. 1, Academic Press (1980) — adding–
  doubling, Fourier decomposition in azimuth.
- J. W. Hovenier, C. van der Mee, H. Domke, *Transfer of Polarized Light in Planetary
  Atmospheres*, Kluwer (2004) §6.3 — azimuthal Fourier modes in the adding method.
"""

from __future__ import annotations

import numpy as np

from nmmm.appearance.brdf.interpolation import _NA, _deg, _lerp1, _lerp_table

try:  # pragma: no cover - numba is a dependency, the fallback only guards odd installs
    import numba as _nb
except ImportError:  # pragma: no cover
    _nb = None

#: Fourier modes m = 1 … N_MODES of the multiple-scattering lobe
N_MODES = 6


def gauss_nodes(n_mu: int = 48, n: float | None = None):
    """Internal polar nodes on [0, 90°], θ increasing: θ (rad), μ, sin θ, ∫dμ weights.

    Without ``n``: Gauss–Legendre in θ over [0, 90°]. With the coat index ``n`` the
    quadrature is split at the critical angle θc (Prahl 1995 puts the critical angle on
    the quadrature's edge for the same reason): half the nodes in the escape cone, Gauss in
    t with μ = μc + (1 − μc) t² (the coat transmission T ∝ √(μ − μc) at the cone's edge is
    then smooth in t), half outside it, Gauss in θ. The escape-cone integrals converge
    (internal diffuse reflectance r_i = 0.59635 for n = 1.5 from 24 nodes on; a single
    Gauss rule over [0, 90°] gives 0.5914 at 48 nodes, 0.5981 at 160) — and with them the
    light trapped under the coat, hence F_ms of absorbing paints (1–2 % too high before)."""
    if n is None or n <= 1.0:
        xg, wg = np.polynomial.legendre.leggauss(n_mu)
        th = 0.25 * np.pi * (xg + 1)
        mu, sn = np.cos(th), np.sin(th)
        return th, mu, sn, sn * 0.25 * np.pi * wg
    mu_c = np.sqrt(1.0 - 1.0 / (n * n))
    th_c = np.arccos(mu_c)
    n1 = n_mu // 2
    x, w = np.polynomial.legendre.leggauss(n1)
    t, wt = 0.5 * (x + 1), 0.5 * w
    mu1 = (mu_c + (1.0 - mu_c) * t * t)[::-1]  # θ increasing
    d1 = (2.0 * (1.0 - mu_c) * t * wt)[::-1]
    x, w = np.polynomial.legendre.leggauss(n_mu - n1)
    th2 = th_c + 0.5 * (0.5 * np.pi - th_c) * (x + 1)
    d2 = np.sin(th2) * 0.5 * (0.5 * np.pi - th_c) * w
    mu = np.concatenate([mu1, np.cos(th2)])
    th = np.arccos(mu)
    return th, mu, np.sin(th), np.concatenate([d1, d2])


def flake_kernels(tab, mu, sn, dmu, n_modes: int = 0, n_phi: int = 32, lossless: bool = True):
    """Oriented-mirror scattering per unit flake optical depth, Fourier modes m = 0 … n_modes
    in the azimuth difference: ``G[m, up/down, actual/lossless, j, k, L]`` = ∫ kernel ·
    cos(m φ) dφ · dμ_j (photons from node k travelling down into node j travelling up/down)."""
    L, n_mu = tab.L, mu.size
    ph = (np.arange(n_phi) + 0.5) * np.pi / n_phi  # [0, π), the kernel is even in φ
    uk = np.stack([sn, 0 * sn, -mu], -1)
    nv = 2 if lossless else 1
    G = np.zeros((n_modes + 1, 2, nv, n_mu, n_mu, L))
    cm = np.cos(np.outer(np.arange(n_modes + 1), ph))  # (M+1, n_phi)
    for iq, q in enumerate(ph):
        for s_out, sz in enumerate((1.0, -1.0)):
            uj = np.stack([sn * np.cos(q), sn * np.sin(q), sz * mu], -1)
            hv = uj[:, None, :] - uk[None, :, :]
            hn = np.linalg.norm(hv, axis=-1)
            hn = np.where(hn > 1e-12, hn, 1.0)
            c = np.abs(np.sum(hv * uk[None, :, :], axis=-1)) / hn
            wgt = tab.tilt.pdf(np.abs(hv[..., 2]) / hn) / (4 * mu[None, :]) * (dmu[:, None] * 2 * np.pi / n_phi)
            dc = _deg(c.ravel())
            tabs = (tab.Rf, tab.Rf0)[:nv]
            for v, Rt in enumerate(tabs):
                contrib = wgt[..., None] * _lerp_table(Rt, dc, tab.step).reshape(wgt.shape + (L,))
                G[:, s_out, v] += cm[:, iq, None, None, None] * contrib[None]
    return G


def double(R, T, n_doublings):
    """Adding–doubling of a homogeneous (symmetric) layer: (R, T) of δ → of 2ⁿ δ; (L, j, k)."""
    eye = np.eye(R.shape[-1])
    for _ in range(n_doublings):
        M = np.linalg.solve(eye[None] - R @ R, T)
        R, T = R + T @ R @ M, T @ M
    return R, T


def azimuth_modes(tab, n_modes: int = N_MODES, n_mu: int = 48, n_doublings: int = 16):
    """c_m(θi, θo) on the external albedo grid (2° steps): ``(NA, NA, n_modes)``; one shape for
    all wavelengths: Σ_λ M_m / Σ_λ M_0 (the flakes' spectral contrast hardly moves it)."""
    n = tab.n
    th, mu, sn, dmu = gauss_nodes(n_mu, n)
    G = flake_kernels(tab, mu, sn, dmu, n_modes, lossless=False)[:, :, 0]  # (M+1, up/down, j, k, L)
    eps = _lerp1(tab.a_tab, np.degrees(th), tab.step) / mu  # (k,) extinction per unit τ, × τ_e/τ
    target = eps[:, None] * (tab.tau_e / tab.tau)[None, :]  # (k, L)
    # the kernel is renormalised as in multiple_scattering_factor (lossless column = target)
    G0 = flake_kernels(tab, mu, sn, dmu, 0)[0, :, 1]  # (up/down, j, k, L) lossless
    col0 = G0.sum(axis=(0, 1))
    scale = np.where(col0 > 0, target / np.where(col0 > 0, col0, 1.0), 0.0)  # (k, L)
    eye = np.eye(n_mu)
    delta = tab.tau / 2.0 ** n_doublings
    mu_c = np.sqrt(1 - 1 / (n * n))
    mu_ext = np.sqrt(np.clip(1 - n * n * (1 - mu * mu), 0, 1))
    Tint = np.where(mu[:, None] > mu_c, _lerp_table(tab.Tc, _deg(mu_ext), tab.step), 0.0).T  # (L, K)
    D = 1.0 - Tint  # the coat's underside mirrors this fraction back down, every mode
    lamb = 2 * mu * dmu
    lamb = lamb / lamb.sum()
    Rb = tab.rho[:, None, None] * np.broadcast_to(lamb[:, None], (n_mu, n_mu))[None]

    def with_coat(Rtot):
        return np.linalg.solve(eye[None] - Rtot * D[:, None, :], Rtot)

    tT = np.moveaxis(target, -1, 0)  # (L, k)
    Tdir = np.exp(-tab.tau * tT)
    ms = []
    for m in range(n_modes + 1):
        Ku = np.moveaxis(G[m, 0] * scale[None], -1, 0)  # (L, j, k) per unit τ
        Kd = np.moveaxis(G[m, 1] * scale[None], -1, 0)
        R, T = double(delta * Ku, delta * Kd + eye[None] * (1 - delta * tT)[:, None, :], n_doublings)
        Rtot = R + T @ np.linalg.solve(eye[None] - Rb @ R, Rb @ T) if m == 0 else R
        s = tT[:, :, None] + tT[:, None, :]  # ε_j + ε_k
        R1 = Ku * -np.expm1(-tab.tau * s) / np.where(s > 0, s, 1.0)
        Mm = with_coat(Rtot) - R1
        if m == 0:
            Mm = Mm - with_coat(Tdir[:, :, None] * Rb * Tdir[:, None, :])
        ms.append(Mm)
    # one azimuthal shape for all wavelengths (the ratio of the wavelength sums): the modes then
    # cost one multiply per pair and wavelength
    M0 = ms[0].sum(axis=0)
    ok = M0 > 1e-12 * np.max(np.abs(M0))
    c = np.stack([np.where(ok, Mm.sum(axis=0) / np.where(ok, M0, 1.0), 0.0) for Mm in ms[1:]])  # (M, j, k)
    c = 0.5 * (c + np.swapaxes(c, -1, -2))  # reciprocity (f = P/(μ dω) is symmetric)
    # external incidence grid -> internal angle -> linear weights on the Gauss nodes
    tha = np.radians(np.linspace(0.0, 90.0, _NA))
    thp = np.arcsin(np.clip(np.sin(tha) / n, 0, 1))
    W = np.zeros((_NA, n_mu))
    x = np.clip(np.interp(thp, th, np.arange(n_mu)), 0, n_mu - 1.000001)
    i0 = x.astype(int)
    f = x - i0
    W[np.arange(_NA), i0] = 1 - f
    W[np.arange(_NA), i0 + 1] += f
    return np.ascontiguousarray(np.einsum("aj,mjk,bk->abm", W, c, W, optimize=True))


def _add_modes_py(wi, wo, out, Dms, Kms, C, astep):
    P = wi.shape[0]
    L = out.shape[1]
    NA = Dms.shape[0]
    M = C.shape[2]
    for p in _prange(P):
        ix, iy, iz = wi[p, 0], wi[p, 1], wi[p, 2]
        ox, oy, oz = wo[p, 0], wo[p, 1], wo[p, 2]
        if iz <= 0.0 or oz <= 0.0:
            continue
        ri = np.sqrt(ix * ix + iy * iy)
        ro = np.sqrt(ox * ox + oy * oy)
        if ri < 1e-9 or ro < 1e-9:
            continue
        cphi = -(ix * ox + iy * oy) / (ri * ro)
        cphi = min(max(cphi, -1.0), 1.0)
        xi = min(np.arccos(min(iz, 1.0)) * (180.0 / np.pi) / astep, NA - 1.000001)
        a0 = int(xi)
        fa = xi - a0
        xo = min(np.arccos(min(oz, 1.0)) * (180.0 / np.pi) / astep, NA - 1.000001)
        b0 = int(xo)
        fb = xo - b0
        w00 = (1.0 - fa) * (1.0 - fb)
        w01 = (1.0 - fa) * fb
        w10 = fa * (1.0 - fb)
        w11 = fa * fb
        s = 0.0
        c_prev, c_cur = 1.0, cphi
        for m in range(M):  # cos(m φ) by the Chebyshev recursion
            s += c_cur * (C[a0, b0, m] * w00 + C[a0, b0 + 1, m] * w01 + C[a0 + 1, b0, m] * w10
                          + C[a0 + 1, b0 + 1, m] * w11)
            c_prev, c_cur = c_cur, 2.0 * cphi * c_cur - c_prev
        s *= 2.0
        if s < -1.0:
            s = -1.0
        if s == 0.0:
            continue
        for l in range(L):
            out[p, l] += s * ((Dms[a0, l] * (1.0 - fa) + Dms[a0 + 1, l] * fa)
                              * (Dms[b0, l] * (1.0 - fb) + Dms[b0 + 1, l] * fb) * Kms[l])


if _nb is not None:
    _prange = _nb.prange
    _add_modes = _nb.njit(parallel=True, fastmath=True, cache=True)(_add_modes_py)
else:  # pragma: no cover
    _prange = range
    _add_modes = _add_modes_py


def mode_table(tab) -> np.ndarray:
    """c_m(θi, θo) of a table set, computed once and cached on it: ``(NA, NA, M)`` (M = 0 when
    the paint has no flakes or no multiple-scattering lobe)."""
    C = getattr(tab, "_ms_modes", None)
    if C is None:
        C = azimuth_modes(tab) if tab.has_flakes and np.any(tab.Kms > 0) else np.zeros((1, 1, 0))
        tab._ms_modes = C
    return C


def azimuth_factor(tab, wi, wo) -> np.ndarray:
    """s = 2 Σ_m c_m cos(m φ) (clipped at −1) for the pairs (P, 3): the lobe is f_ms⁰ (1 + s)."""
    C = mode_table(tab)
    wi = np.asarray(wi, float).reshape(-1, 3)
    wo = np.asarray(wo, float).reshape(-1, 3)
    if C.shape[2] == 0:
        return np.zeros(wi.shape[0])
    ri = np.hypot(wi[:, 0], wi[:, 1])
    ro = np.hypot(wo[:, 0], wo[:, 1])
    ok = (ri > 1e-9) & (ro > 1e-9) & (wi[:, 2] > 0) & (wo[:, 2] > 0)
    cphi = np.clip(-(wi[:, 0] * wo[:, 0] + wi[:, 1] * wo[:, 1]) / np.where(ok, ri * ro, 1.0), -1.0, 1.0)
    NA = C.shape[0]
    xi = np.clip(_deg(wi[:, 2]) / tab.astep, 0, NA - 1.000001)
    xo = np.clip(_deg(wo[:, 2]) / tab.astep, 0, NA - 1.000001)
    a0, b0 = xi.astype(int), xo.astype(int)
    fa, fb = (xi - a0)[:, None], (xo - b0)[:, None]
    c = (C[a0, b0] * (1 - fa) * (1 - fb) + C[a0, b0 + 1] * (1 - fa) * fb + C[a0 + 1, b0] * fa * (1 - fb)
         + C[a0 + 1, b0 + 1] * fa * fb)  # (P, M)
    phi = np.arccos(cphi)
    s = 2 * np.sum(c * np.cos(np.outer(phi, np.arange(1, C.shape[2] + 1))), axis=1)
    return np.where(ok, np.maximum(s, -1.0), 0.0)


def add_azimuth_modes(tab, wi, wo, out):
    """out (P, L) += the azimuthal modes of the multiple-scattering lobe for the pairs (P, 3)."""
    C = mode_table(tab)
    if C.shape[2] == 0:
        return
    _add_modes(np.ascontiguousarray(wi, float), np.ascontiguousarray(wo, float), out, tab.Dms,
               np.asarray(tab.Kms, float), C, float(tab.astep))
