"""Radiative transfer in a pigmented basecoat holding a flake layer: the multiple-scattering
amount F_ms(λ) and the azimuthal modes of its lobe for a :class:`~nmmm.appearance.brdf.PaintBRDF`
with a :class:`~nmmm.appearance.brdf.CoatMedium`.

The basecoat (vertical optical thickness κ = (μa + μs) H, Henyey–Greenstein pigments of
asymmetry g) is cut into up to three homogeneous slabs — pigment above the flakes (0 … z0),
the flake band (z0 … z1: oriented mirrors of optical depth τ, as in
:mod:`~nmmm.appearance.brdf.multiple_scattering`, plus pigment), pigment below (z1 … 1) —
each obtained by doubling (van de Hulst 1980) and added from the bottom on the Lambertian
substrate ρ; the coat's underside mirrors the light outside the escape cone back down. The
scattering kernels are renormalised so that a lossless slab conserves photons exactly
(the white furnace holds by construction, as without pigments). Each azimuthal Fourier mode
is added separately (the substrate couples only the 0th); the multiply scattered part M is
the total minus what terms 2–3 already hold: one flake reached and left without pigment
scattering, and light that met neither flake nor pigment. F_ms is the same split of the same
transport, (e − s)/(e0 − s0) with s that light escaping under diffuse incidence
(:func:`_single_escape`): with the exact terms-2–3 albedo for s instead, the node quadrature's error
on the single light (0.45 % low for the Fe2O3/mica pearl's 8° tilt on 48 × 32 nodes) fell entirely on
the multiple term, 25× smaller: 0.80 / 0.89 / 0.97 of the tracer's at 450 / 550 / 650 nm (issue 18).

References
----------
- H. C. van de Hulst, *Multiple Light Scattering* (1980) — adding–doubling.
- L. G. Henyey, J. L. Greenstein, Astrophys. J. 93 (1941) 70 — the phase function.
- J. W. Hovenier, C. van der Mee, H. Domke, *Transfer of Polarized Light in Planetary
  Atmospheres* (2004) §6.3 — azimuthal modes in the adding method.
"""

from __future__ import annotations

import numpy as np

from nmmm.appearance.brdf.interpolation import _NA, _deg, _lerp1, _lerp_table
from nmmm.appearance.brdf.ms_azimuth import N_MODES, double, flake_kernels, gauss_nodes, in_chunks, lobe_tables

_N_MU = 96  # polar nodes (half in the escape cone)
_N_PHI = 96  # azimuths of the flake kernel over [0, π)
_MAX_STEP = 0.03  # largest extinction per doubling seed slab
_N_LOBE_NODES = 9  # wavelength nodes of the lobe's shape tables (twice as many where it bends: _lobe_nodes)
_NODE_TOL = 0.005  # largest error of the lobe's directional factor, linear in λ between the nodes


def pigment_kernels(g, mu, sn, dmu, n_modes, n_phi=48):
    """Henyey–Greenstein scattering per unit vertical optical depth of scatterers, Fourier
    modes 0 … n_modes: ``P[m, up/down, j, k, L]``, mode 0 renormalised so that each column
    scatters exactly 1/μ_k (photon conservation on the nodes). Each distinct asymmetry g is
    computed once (a constant g: one column for all wavelengths), the azimuth sums in one compiled
    pass (:func:`_hg_modes`; issue 18: table build time)."""
    g = np.asarray(g, float)
    gu, inv = np.unique(g, return_inverse=True)
    L, n = gu.size, mu.size
    ph = (np.arange(n_phi) + 0.5) * np.pi / n_phi
    cm = np.ascontiguousarray(np.cos(np.outer(np.arange(n_modes + 1), ph)))
    # cosine of the scattering angle, travel down along k (sn_k, 0, −μ_k) → along j (sn_j cos q, sn_j sin q,
    # sz μ_j), per azimuth q and up/down: (n_phi, 2, j, k)
    cth = np.stack([np.stack([sn[:, None] * sn[None, :] * np.cos(q) - sz * mu[:, None] * mu[None, :]
                              for sz in (1.0, -1.0)]) for q in ph])
    wjk = dmu[:, None] * 2 * np.pi / n_phi / mu[None, :]
    P = np.zeros((n_modes + 1, 2, n, n, L))
    _hg_modes(gu, np.ascontiguousarray(cth), np.ascontiguousarray(wjk), cm, P)
    col = P[0].sum(axis=(0, 1))  # (k, L)
    P *= np.where(col > 0, (1.0 / mu)[:, None] / np.where(col > 0, col, 1.0), 0.0)[None, None, None]
    return P[..., inv] if L < g.size or np.any(inv != np.arange(g.size)) else P


def _hg_modes_py(g, cth, wjk, cm, P):
    """P[m, s, j, k, l] = Σ_q cm[m, q] wjk[j, k] p_HG(cth[q, s, j, k]; g[l]), the azimuths summed in order
    (as the loop over q it replaced); (1 + g² − 2 g c)^1.5 as x √x."""
    n_phi, M1, L = cth.shape[0], cm.shape[0], g.size
    g2 = g * g
    a = 1 - g2
    b = 1 + g2
    g2x = 2 * g
    v = np.empty(L)
    for s in range(2):
        for j in range(cth.shape[2]):
            for k in range(cth.shape[3]):
                w = wjk[j, k]
                for q in range(n_phi):
                    c = cth[q, s, j, k]
                    for l in range(L):
                        x = b[l] - g2x[l] * c
                        v[l] = w * (a[l] / (4 * np.pi * (x * np.sqrt(x))))
                    for m in range(M1):
                        cq = cm[m, q]
                        acc = P[m, s, j, k]
                        for l in range(L):
                            acc[l] += cq * v[l]


try:  # pragma: no cover - numba is a dependency, the fallback only guards odd installs
    import numba as _nb

    _hg_modes = _nb.njit(cache=True)(_hg_modes_py)
except ImportError:  # pragma: no cover
    _hg_modes = _hg_modes_py


def _slab(Ku, Kd, ext, thickness):
    """(R, T) of a homogeneous slab, (L, j, k), from kernels per unit thickness (L, j, k) and
    the extinction ext (L, k) per unit thickness, by doubling a thin seed slab. The number of
    doublings is set by the largest extinction over all wavelengths; each wavelength's matrices are
    then doubled on their own, in chunks of wavelengths run side by side
    (:func:`~nmmm.appearance.brdf.ms_azimuth.in_chunks`: the same operations on each matrix, the same numbers)."""
    eye = np.eye(Ku.shape[-1])
    emax = float(np.max(ext)) * thickness
    nd = int(np.clip(np.ceil(np.log2(max(emax, 1e-12) / _MAX_STEP)), 4, 40))
    d = thickness / 2.0 ** nd
    R, T = d * Ku, d * Kd + eye[None] * (1.0 - d * ext)[:, None, :]
    return in_chunks(lambda r, t: double(r, t, nd), R, T)


def _on_top(R, T, Rbelow):
    eye = np.eye(R.shape[-1])
    return R + T @ np.linalg.solve(eye[None] - Rbelow @ R, Rbelow @ T)


def _single_escape(tab, G_mirror, fext, v, Tint, D, d0, lamb, inv_mu, z0, dz):
    """The transport's own terms 2–3 under diffuse incidence (L,): light that met one flake mirror and
    no pigment scattering, or the substrate without any scattering (with the coat's underside), escaping.
    ``multiply_scattered`` in :func:`coat_transport` removes the same from M_m."""
    L, n_mu = Tint.shape
    eye = np.eye(n_mu)
    kap = (tab.kappa if v == 0 else tab.kappa0)[:, None]
    rho = tab.rho if v == 0 else np.ones(L)
    Rb = rho[:, None, None] * np.broadcast_to(lamb[:, None], (n_mu, n_mu))[None]
    tdir = np.exp(-fext - kap * inv_mu)
    X = tdir[:, :, None] * Rb * tdir[:, None, :]
    S = np.linalg.solve(eye[None] - X * D[:, None, :], X)
    if G_mirror is not None:
        s2 = inv_mu.T + inv_mu
        x = fext[:, :, None] + fext[:, None, :] + kap[:, :, None] * dz * s2[None]
        S = S + (np.moveaxis(G_mirror[0, v], -1, 0) * tab.tau * np.exp(-kap[:, :, None] * z0 * s2[None])
                 * -np.expm1(-x) / np.where(x > 0, x, 1.0))
    return np.sum(Tint * np.einsum("ljk,lk->lj", S, d0), axis=1)


def coat_transport(tab, n_modes: int = N_MODES, n_mu: int = _N_MU):
    """F_ms(λ) of a paint with a coat medium (see the module docstring); the azimuthal modes
    c_m(θi, θo) of its lobe at 9 (or 17: :func:`_lobe_nodes`) wavelength nodes (indices
    ``tab._ms_nodes``) are stored on ``tab._ms_modes_spectral`` ``(NA, NA, K, n_modes)``, linear in λ
    between nodes. F_ms subtracts the transport's own single light, not the exact terms-2–3 albedo
    (module docstring). Mode 0 is solved at every wavelength, the modes m ≥ 1 (flake and pigment
    kernels included) at the nodes only."""
    L, n = tab.L, tab.n
    th, mu, sn, dmu = gauss_nodes(n_mu, tab.n)
    eye = np.eye(n_mu)
    z0, dz = tab.z0, tab.dz
    flakes = tab.has_flakes
    li = np.arange(L)
    # mode 0 at every wavelength (F_ms, and the lobe's polar shape that places the wavelength nodes);
    # the modes m ≥ 1 only at the nodes (below)
    scatters = bool(np.any(np.asarray(tab.kap_s) > 0))  # without pigment scattering its kernels are zeros

    def pigment_part(n_m, idx):
        if scatters:
            return pigment_kernels(np.asarray(tab.g_pig, float)[idx], mu, sn, dmu, n_m)
        return np.zeros((n_m + 1, 2, n_mu, n_mu, li[idx].size))

    P0 = pigment_part(0, li)
    if flakes:
        eps = _lerp1(tab.a_tab, np.degrees(th), tab.step) / mu
        target = eps[:, None] * tab.extinction_ratio(np.degrees(th))  # (k, L) per unit τ

        def flake_part(n_m, idx):
            """The flake kernel, modes 0 … n_m, wavelengths idx: (G, G_mirror), G (M+1, up/down,
            actual/lossless, j, k, K), renormalised to the extinction, rims added to mode 0."""
            G = flake_kernels(tab, mu, sn, dmu, n_m, n_phi=_N_PHI, wl=idx)
            tg = target[:, idx]
            col0 = G[0, :, 1].sum(axis=(0, 1))
            G *= np.where(col0 > 0, tg / np.where(col0 > 0, col0, 1.0), 0.0)[None, None, None, None]
            fe = getattr(tab, "edge", 0.0)
            if fe > 0:  # rims: a fraction fe of the flake interactions scattered diffusely
                G *= 1.0 - fe
            G_mirror = G[:, 0].copy() if fe > 0 else G[:, 0]  # (M+1, variant, j, k, K) upward, mirrors only
            if fe > 0:
                # a rim takes light in proportion to the flakes' projected area a(μ_k) and sends it, up or
                # down, in proportion to a(μ_j): reciprocal (isotropic emission would not be: it gives
                # f ∝ a(μi)/μi/μo for a thin layer, not symmetric); no azimuth memory (mode 0 only)
                em = eps * mu * dmu  # a(μ_j) dμ_j
                em = em / (2.0 * em.sum())  # columns sum to 1 over up and down
                for v, alb in enumerate((tab.edge_albedo[idx], np.ones(tg.shape[1]))):
                    G[0, :, v] += em[None, :, None, None] * (fe * tg * alb[None, :])[None, None]
            return G, G_mirror

        G0, G0_mirror = flake_part(0, li)
        fext = np.moveaxis(target, -1, 0) * tab.tau  # (L, k) through the whole band
    else:
        G0 = G0_mirror = None
        fext = np.zeros((L, n_mu))
    mu_c = np.sqrt(1 - 1 / (n * n))
    mu_ext = np.sqrt(np.clip(1 - n * n * (1 - mu * mu), 0, 1))
    Tint = np.where(mu[:, None] > mu_c, _lerp_table(tab.Tc, _deg(mu_ext), tab.step), 0.0).T  # (L, K)
    D = 1.0 - Tint
    lamb = 2 * mu * dmu
    lamb = lamb / lamb.sum()
    d0 = Tint * (mu * dmu)[None, :]
    d0 = d0 / d0.sum(axis=1, keepdims=True)
    ks = np.asarray(tab.kap_s, float)[:, None, None]
    inv_mu = (1.0 / mu)[None, :]

    def system(m, v, idx, P, G):
        """Internal reflection of the whole coat (with the substrate for m = 0), mode m,
        variant v (0 actual, 1 lossless), wavelengths ``idx`` (P and G hold only those)."""
        kap = (tab.kappa if v == 0 else tab.kappa0)[idx][:, None]
        rho = (tab.rho if v == 0 else np.ones(L))[idx]
        Pu = np.moveaxis(P[m, 0], -1, 0) * ks[idx]
        Pd = np.moveaxis(P[m, 1], -1, 0) * ks[idx]
        Rbelow = rho[:, None, None] * np.broadcast_to(lamb[:, None], (n_mu, n_mu))[None] if m == 0 else 0 * Pu
        if flakes:  # bottom first: pigment below the band, the band, pigment above it
            Fu = np.moveaxis(G[m, 0, v], -1, 0) * (tab.tau / dz)
            Fd = np.moveaxis(G[m, 1, v], -1, 0) * (tab.tau / dz)
            layers = [(Pu, Pd, kap * inv_mu, 1.0 - z0 - dz), (Fu + Pu, Fd + Pd, fext[idx] / dz + kap * inv_mu, dz),
                      (Pu, Pd, kap * inv_mu, z0)]
        else:
            layers = [(Pu, Pd, kap * inv_mu, 1.0)]
        for Ku, Kd, ext, t in layers:
            if t > 1e-12:
                R, T = _slab(Ku, Kd, ext, t)
                Rbelow = _on_top(R, T, Rbelow)
        return Rbelow

    escaped, Rtot0 = [], []
    for v in (0, 1):
        Rtot = system(0, v, li, P0, G0)
        Rtot0.append(Rtot)
        u = np.linalg.solve(eye[None] - Rtot * D[:, None, :], np.einsum("ljk,lk->lj", Rtot, d0)[..., None])[..., 0]
        escaped.append(np.sum(Tint * u, axis=1))
    e, e0 = escaped
    # what terms 2–3 hold, from the same node transport (one flake mirror and no pigment scattering;
    # the substrate seen without any scattering, the coat's underside included), escaping under diffuse
    # incidence: F_ms = (e − s) / (e0 − s0) with this s, not the exact terms-2–3 albedo
    s, s0 = (_single_escape(tab, G0_mirror, fext, v, Tint, D, d0, lamb, inv_mu, z0, dz) for v in (0, 1))
    with np.errstate(divide="ignore", invalid="ignore"):
        F = np.clip(np.where(e0 - s0 > 1e-12, (e - s) / (e0 - s0), 0.0), 0.0, 1.0)
    s2 = inv_mu.T + inv_mu  # (j, k) 1/μ_j + 1/μ_k

    def multiply_scattered(m, v, idx, Rt, G_mirror):
        """M_m: the coat's internal reflection Rt (mode m, variant v, wavelengths idx) with its underside,
        less what terms 2–3 hold (one flake mirror and no pigment scattering; the substrate seen without
        any scattering). A rim's light, scattered once, stays in M as it does in F_ms."""
        Ds = D[idx][:, None, :]
        with_coat = lambda X: np.linalg.solve(eye[None] - X * Ds, X)  # noqa: E731
        kapv = (tab.kappa if v == 0 else tab.kappa0)[idx][:, None]
        Mm = with_coat(Rt)
        if flakes:
            Ku = np.moveaxis(G_mirror[m, v], -1, 0)
            fs = fext[idx][:, :, None] + fext[idx][:, None, :]
            x = fs + kapv[:, :, None] * dz * s2[None]
            Mm = Mm - Ku * tab.tau * np.exp(-kapv[:, :, None] * z0 * s2[None]) * -np.expm1(-x) / np.where(x > 0, x, 1.0)
        if m == 0:
            tdir = np.exp(-fext[idx] - kapv * inv_mu)
            rhov = (tab.rho if v == 0 else np.ones(L))[idx]
            Rb = rhov[:, None, None] * np.broadcast_to(lamb[:, None], (n_mu, n_mu))[None]
            Mm = Mm - with_coat(tdir[:, :, None] * Rb * tdir[:, None, :])
        return Mm

    # --- azimuthal modes of the multiply scattered part at a few wavelengths (one shape, linear in λ between
    # them): mode 0 from the systems solved above, the modes m ≥ 1 (their flake and pigment kernels too) at
    # the nodes only; 9 evenly spaced nodes, 17 where the shape is not linear between 9 (_lobe_nodes)
    ms0 = multiply_scattered(0, 0, li, Rtot0[0], G0_mirror)
    ms0_lossless = multiply_scattered(0, 1, li, Rtot0[1], G0_mirror)
    sel, node_error = _lobe_nodes(tab, F, ms0, ms0_lossless, th, mu, dmu)
    ms = [ms0[sel]]
    if n_modes > 0:
        Pm = pigment_part(n_modes, sel)
        Gm, Gm_mirror = flake_part(n_modes, sel) if flakes else (None, None)
        ms += [multiply_scattered(m, 0, sel, system(m, 0, sel, Pm, Gm), Gm_mirror) for m in range(1, n_modes + 1)]
    lobe_tables(tab, F, sel, ms, ms0_lossless[sel], th, mu, dmu)
    tab.ms_node_error = node_error
    return F


def _lobe_nodes(tab, F, ms0, ms0_lossless, th, mu, dmu, tol: float = _NODE_TOL):
    """The lobe's wavelength nodes: ``_N_LOBE_NODES`` evenly spaced, or twice as dense where the lobe's
    directional factor ``ms_albedo_factor`` (from its polar shape c_0, solved at every wavelength), linear
    between those nodes, is more than ``tol`` off at some wavelength and angle -> (nodes, that error at the
    nodes kept). The Fe2O3/mica pearl's factor at θi = 0 runs 0.80 … 0.94 over 480–630 nm, not
    linearly: 9 nodes missed it by 0.015 (0.007 at 550 nm, its multiple term there 1.2 % above the tracer's at
    θi = 0, 5.7 SE at 2·10^6 photons), 17 by 0.004 (0.6 %, 2.7 SE; 0.4 % with all 41). Placing 9 nodes where
    the factor bends instead doubled the modes' error for TiO2/mica (a far bin 4.4 SE off at 450 nm)."""
    L = F.size
    li = np.arange(L)
    K = min(L, _N_LOBE_NODES)
    even = np.unique(np.linspace(0, L - 1, K).round().astype(int))
    if K >= L or K < 2:
        return even, 0.0
    lobe_tables(tab, F, li, [ms0], ms0_lossless, th, mu, dmu)
    fac = tab.ms_albedo_factor  # (NA, L), c_0 at every wavelength
    for K in (K, 2 * K - 1):
        sel = np.unique(np.linspace(0, L - 1, min(L, K)).round().astype(int))
        err = float(np.max(np.abs(np.stack([np.interp(li, sel, f[sel]) for f in fac]) - fac)))
        if err <= tol or sel.size >= L:
            break
    return sel, err
