"""Shape of the multiple-scattering lobe of :class:`~nmmm.appearance.brdf.PaintBRDF`: its
polar shape and its azimuth dependence, from the transport of the multiply scattered light.

The separable lobe of term 4, f_KC = (1 − E⁰(θi))(1 − E⁰(θo)) / (π (1 − Ē⁰)) · F_ms, has the
right diffuse-incidence amount F_ms but neither the polar shape of the multiply scattered light
(rims' and pigments' light is not separable) nor its azimuth dependence: multiply scattered
light in a flake layer keeps a memory of the incidence azimuth — two mirror reflections off
nearly parallel flakes send it on towards the specular side. The lobe is

    f_ms(θi, θo, φ) = f_KC(θi, θo) · [1 + c_0(θi, θo) + 2 Σ_{m=1}^{M} c_m(θi, θo) cos(m φ)],

φ the azimuth between ωo and the mirror direction of ωi; c_0 and c_m come from the Fourier
modes M_m of the multiply scattered part M of the coat's internal reflection
(:func:`lobe_tables`), by adding–doubling per Fourier mode (van de Hulst 1980, ch. 5;
Hovenier et al. 2004, §6.3: the azimuthal modes of a plane-parallel medium decouple and each
is added like the 0th): the flake kernel expanded in cos(m φ), the Lambertian base coupling
only m = 0, the coat's underside mirroring all modes. M = (all orders) − (one flake, no coat
reflection) − (no flake at all) — exactly the light the terms 2–3 leave to term 4. The polar
quadrature is split at the coat's critical angle (:func:`gauss_nodes`).

Since ∫ cos(m φ) dφ = 0 the modes m ≥ 1 add no energy; c_0 has a zero diffuse-incidence mean
and, lossless, a zero mean over θo at every θi (white furnace); its directional albedo is
``ms_albedo_factor``. c_m(θi, θo) = c_m(θo, θi) keeps reciprocity. The sum is clipped at −1
(no negative radiance from the truncated series).

References
----------
- H. C. van de Hulst, *Multiple Light Scattering*, vol. 1, Academic Press (1980) — adding–
  doubling, Fourier decomposition in azimuth.
- J. W. Hovenier, C. van der Mee, H. Domke, *Transfer of Polarized Light in Planetary
  Atmospheres*, Kluwer (2004) §6.3 — azimuthal Fourier modes in the adding method.
- S. A. Prahl, "The adding-doubling method", in A. J. Welch, M. J. C. van Gemert (eds.),
  *Optical-Thermal Response of Laser-Irradiated Tissue*, Plenum (1995) 101–129,
  doi:10.1007/978-1-4757-6092-7_5 — the polar quadrature split at the critical angle
  (:func:`gauss_nodes`).
- C. Kulla, A. Conty, "Revisiting physically based shading at Imageworks", SIGGRAPH 2017
  course *Physically Based Shading in Theory and Practice* — the separable lobe f_KC.
"""

from __future__ import annotations

import numpy as np

from nmmm.appearance.brdf.interpolation import _NA, _angle_pos_nb, _deg, _lerp1, _lerp_table

try:  # pragma: no cover - numba is a dependency, the fallback only guards odd installs
    import numba as _nb
except ImportError:  # pragma: no cover
    _nb = None

#: Fourier modes m = 1 … N_MODES of the multiple-scattering lobe
N_MODES = 6
#: pairs per parallel chunk of the kernels (per-chunk buffers of the lobe sums)
_CHUNK_PAIRS = 256
#: private override of the lobe-shape rule of :func:`lobe_tables`, for the Monte-Carlo comparison
#: (tests/appearance/test_brdf_montecarlo.py): None (the rule), "transport" or "separable" for every paint
#: built while it is set (tables are cached per paint: build a fresh paint after setting it)
_LOBE_SHAPE_OVERRIDE: str | None = None
#: flakes tilted less than this (deg; cosine taper between the two) enter the transport's kernel by a
#: quadrature over their normals (:func:`_core_kernel`), not on the outgoing nodes
_CORE_DEG = (3.0, 9.0)


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


def flake_kernels(tab, mu, sn, dmu, n_modes: int = 0, n_phi: int = 32, lossless: bool = True,
                  core_deg: tuple[float, float] | None = _CORE_DEG, wl=None):
    """Oriented-mirror scattering per unit flake optical depth, Fourier modes m = 0 … n_modes
    in the azimuth difference: ``G[m, up/down, actual/lossless, j, k, L]`` = ∫ kernel ·
    cos(m φ) dφ · dμ_j (photons from node k travelling down into node j travelling up/down).

    The kernel p(h) R / (4 μ_k) is sampled on the outgoing nodes (μ_j, φ) for the flakes tilted
    beyond ``core_deg`` (a cosine taper from 1 at the first angle to 0 at the second); the nearly
    flat ones are integrated over their normals instead (:func:`_core_kernel`). A tilt law with a
    finite density per unit tilt at 0 — the deposit's half-normal law — has p(h) ∝ 1/θ_h per sr: on
    the outgoing nodes this is a 1/r peak at the mirror direction of node k, which the node j = k
    meets at an azimuth ∝ sin θ_k. The point quadrature over-integrated it by up to 9 % near the
    normal (96 × 96 nodes, the Fe2O3/mica pearl), undone by the renormalisation of the columns but
    not in the kernel's shape: the multiple term at θi = 0 was 1.5–3.3 % (8–13 SE) above the tracer's
    (issue 18). ``core_deg=None``: the point quadrature everywhere. ``wl``: only these wavelength
    indices (the last axis of G), e.g. the lobe's nodes for the modes m ≥ 1.

    The reflectance R(|u·h|) enters linearly, read from its angle table by linear interpolation, so
    the kernel is a weight matrix over the table's angle nodes — geometry, tilt law and quadrature,
    the same at every wavelength (:func:`_kernel_weights`) — times the table: G_m = A_m · R, one
    matrix product for all wavelengths and both variants (issue 18: table build time; the same sums
    as a per-wavelength evaluation, in another order)."""
    wl = slice(None) if wl is None else np.asarray(wl)
    nv = 2 if lossless else 1
    Rts = (tab.Rf[:, wl], tab.Rf0[:, wl])[:nv]
    L, n_mu, NT = Rts[0].shape[1], mu.size, Rts[0].shape[0]
    R = np.concatenate(Rts, axis=1)  # (NT, nv L)
    G = np.empty((n_modes + 1, 2, nv, n_mu, n_mu, L))
    for m, A in enumerate(_kernel_weights(tab, mu, sn, dmu, n_modes, n_phi, core_deg, NT)):
        G[m] = (A @ R).reshape(2, n_mu, n_mu, nv, L).transpose(0, 3, 1, 2, 4)
    return G


def _lerp_entries(theta_deg, step, n):
    """Node index i and weight f of the linear interpolation on a uniform angle table of n nodes
    (as :func:`~nmmm.appearance.brdf.interpolation._lerp_table`): value = (1 − f) T[i] + f T[i + 1]."""
    x = np.clip(theta_deg / step, 0.0, n - 1.000001)
    i = x.astype(np.intp)
    return i, x - i


def _kernel_weights(tab, mu, sn, dmu, n_modes, n_phi, core_deg, NT):
    """The flake kernel's weights over the reflectance table's angle nodes, mode by mode: yields
    A_m (2 n_mu², NT), rows (up/down, j, k), with G_m = A_m · R_table (:func:`flake_kernels`). The
    entries depend on the nodes, the tilt law, the coat index and the quadrature, not on the wavelengths
    or the flakes' optics: they are kept for the last few such geometries (:func:`_kernel_entries`)."""
    n_mu = mu.size
    S, ph, core_idx, core_w, core_phi = _kernel_entries(tab, mu, sn, dmu, n_phi, core_deg, NT)
    for m in range(n_modes + 1):
        # the point part: Σ_q cos(m q) (its azimuths' columns); the core: cos(m φ) of each mirror ray
        A = S @ np.cos(m * ph)
        if core_idx.size:
            A += np.bincount(core_idx, core_w * np.cos(m * core_phi), minlength=A.size)
        yield A.reshape(2 * n_mu * n_mu, NT)


_ENTRIES_CACHE: dict = {}
_ENTRIES_CACHE_SIZE = 2


def _kernel_entries(tab, mu, sn, dmu, n_phi, core_deg, NT):
    """The flake kernel's weight matrix (:func:`_kernel_weights`) before its azimuth sum: the point part as a
    sparse matrix S (flat index (up/down, j, k) · NT + table node, azimuth q) and its azimuths q, the
    core's entries (flat index, weight, azimuth φ of the mirror ray). Cached
    (the last ``_ENTRIES_CACHE_SIZE``, ~45 MB each at 96 × 96 nodes) by what they depend on: the tilt
    law (its nodes and density), the coat index, the polar nodes, the azimuths, the core's tilts and the
    table step — a change of concentration, pigment or flake optics reuses them."""
    tilt = tab.tilt
    key = (np.asarray(tilt.tilt_deg, float).tobytes(), np.asarray(tilt.density, float).tobytes(),
           float(getattr(tab, "n", 1.0)), mu.tobytes(), sn.tobytes(), dmu.tobytes(), int(n_phi),
           None if core_deg is None else tuple(map(float, core_deg)), float(tab.step), int(NT))
    hit = _ENTRIES_CACHE.pop(key, None)
    if hit is None:
        hit = _build_kernel_entries(tab, mu, sn, dmu, n_phi, core_deg, NT)
        while len(_ENTRIES_CACHE) >= _ENTRIES_CACHE_SIZE:
            _ENTRIES_CACHE.pop(next(iter(_ENTRIES_CACHE)))
    _ENTRIES_CACHE[key] = hit  # most recently used last
    return hit


def _build_kernel_entries(tab, mu, sn, dmu, n_phi, core_deg, NT):
    from scipy import sparse

    ph = (np.arange(n_phi) + 0.5) * np.pi / n_phi  # [0, π), the kernel is even in φ
    uk = np.stack([sn, 0 * sn, -mu], -1)
    n_mu = mu.size
    nn = n_mu * n_mu
    rows = np.arange(nn)
    idx, wgt = [], []
    for q in ph:
        for s_out, sz in enumerate((1.0, -1.0)):
            uj = np.stack([sn * np.cos(q), sn * np.sin(q), sz * mu], -1)
            hv = uj[:, None, :] - uk[None, :, :]
            hn = np.linalg.norm(hv, axis=-1)
            hn = np.where(hn > 1e-12, hn, 1.0)
            c = np.abs(np.sum(hv * uk[None, :, :], axis=-1)) / hn
            hz = np.abs(hv[..., 2]) / hn
            pdf = tab.tilt.pdf(hz)
            if core_deg is not None:
                pdf = pdf * (1.0 - _core_weight(np.degrees(np.arccos(np.clip(hz, -1.0, 1.0))), core_deg))
            w = (pdf / (4 * mu[None, :]) * (dmu[:, None] * 2 * np.pi / n_phi)).ravel()
            i, f = _lerp_entries(_deg(c.ravel()), tab.step, NT)
            r = (s_out * nn + rows) * NT + i
            idx += [r, r + 1]
            wgt += [w * (1.0 - f), w * f]
    q = np.repeat(np.arange(n_phi), 4 * nn)  # entries per azimuth: up/down, two table nodes
    S = sparse.csr_matrix((np.concatenate(wgt), (np.concatenate(idx), q)), shape=(2 * nn * NT, n_phi))
    if core_deg is None:
        return S, ph, np.zeros(0, np.intp), np.zeros(0), np.zeros(0)
    return (S, ph) + _core_entries(tab, mu, dmu, core_deg, NT)


def _core_weight(theta_deg, core_deg):
    """χ(θ): 1 below core_deg[0], a cosine taper to 0 at core_deg[1]."""
    a, b = core_deg
    x = np.clip((np.asarray(theta_deg, float) - a) / (b - a), 0.0, 1.0)
    return 0.5 * (1.0 + np.cos(np.pi * x))


def _node_cells(mu, dmu, mu_c):
    """Edges in μ of the cells of the polar nodes (θ increasing): cell j spans dμ_j, laid end to end from
    μ = 1 inside the escape cone and from μ_c outside it, so no cell straddles the critical angle."""
    inside = mu > mu_c
    top = np.where(inside, 1.0, mu_c)
    first = np.concatenate([[True], inside[1:] != inside[:-1]])
    hi = np.empty_like(mu)
    for j in range(mu.size):
        hi[j] = top[j] if first[j] else hi[j - 1] - dmu[j - 1]
    return hi, hi - dmu


def _core_entries(tab, mu, dmu, core_deg, NT, n_theta: int = 16, n_phi: int = 48, n_sub: int = 4):
    """The nearly flat flakes' part of :func:`flake_kernels`, χ(θ_h) p(h), as a transfer between the nodes'
    cells (:func:`_node_cells`): photons spread evenly over node k's cell (``n_sub`` incidences), each
    normal from a Gauss–Legendre rule in the tilt over [0, core_deg[1]] (the measure p(θ) sin θ dθ is
    finite where p per sr is not) and uniform in its azimuth, the mirror direction counted in the cell
    it falls in, its azimuth φ giving cos(m φ) exactly. Read along a row (the radiance of a node) or a
    column (where a node's photons go) it is the same cell average: the point kernel's 1/r peak at the
    mirror direction is right in neither. Returns the entries of the weight matrix of
    :func:`_kernel_weights` (flat index (up/down, j, k) · NT + table node, weight, φ), the mode m's
    weight being weight · cos(m φ)."""
    n_mu = mu.size
    n = getattr(tab, "n", 1.0)
    mu_c = np.sqrt(1.0 - 1.0 / (n * n)) if n > 1.0 else -1.0
    hi, lo = _node_cells(mu, dmu, mu_c)
    edges = np.concatenate([hi[:1], lo])  # decreasing in μ
    x, wx = np.polynomial.legendre.leggauss(n_theta)
    tmax = np.radians(core_deg[1])
    t = 0.5 * (x + 1) * tmax
    wt = 0.5 * tmax * wx * np.sin(t) * tab.tilt.pdf(np.cos(t)) * _core_weight(np.degrees(t), core_deg)
    p = (np.arange(n_phi) + 0.5) * np.pi / n_phi  # [0, π), weights × 2: cos(m φ) is even in φ
    T, P = np.meshgrid(t, p, indexing="ij")
    h = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1).reshape(-1, 3)
    wh = np.broadcast_to((wt * 2 * np.pi / n_phi)[:, None], T.shape).reshape(-1)
    kk = np.broadcast_to(np.arange(n_mu)[:, None], (n_mu, h.shape[0]))
    idx, wgt, phi = [], [], []
    for i in range(n_sub):  # incidences spread evenly over each node's cell
        mu_in = hi - (i + 0.5) / n_sub * dmu
        uk = np.stack([np.sqrt(np.clip(1 - mu_in * mu_in, 0, 1)), 0 * mu_in, -mu_in], -1)  # travelling down
        c = uk @ h.T  # (k, S)
        out = uk[:, None, :] - 2.0 * c[..., None] * h[None]  # mirror directions
        w = (wh[None] * np.abs(c) / mu[:, None] / n_sub).ravel()  # photons per unit τ per sample (the node's rate)
        mu_o = np.abs(out[..., 2])
        phi_o = np.arctan2(out[..., 1], out[..., 0]).ravel()
        j = np.clip(np.searchsorted(-edges, -mu_o, side="right") - 1, 0, n_mu - 1)  # the cell it falls in
        row = ((np.where(out[..., 2] > 0, 0, 1) * n_mu + j) * n_mu + kk).ravel()  # (up/down, j, k)
        it, f = _lerp_entries(_deg(np.abs(c).ravel()), tab.step, NT)
        r = row * NT + it
        idx += [r, r + 1]
        wgt += [w * (1.0 - f), w * f]
        phi += [phi_o, phi_o]
    return np.concatenate(idx), np.concatenate(wgt), np.concatenate(phi)


def _workers(L):
    """Threads for the wavelength chunks of :func:`in_chunks`: Numba's thread count
    (``NUMBA_NUM_THREADS``, ``numba.set_num_threads``; the kernels use the same), ≥ 8 wavelengths each."""
    n = _nb.get_num_threads() if _nb is not None else 1
    return max(1, min(n, L // 8))


def in_chunks(fn, *arrays):
    """fn over chunks of the leading (wavelength) axis of ``arrays`` in threads (NumPy's linear algebra
    releases the GIL), its tuple of results concatenated: for per-wavelength work such as :func:`double`,
    each wavelength's matrices see the same operations as in one call, so the numbers are the same at any
    thread count (issue 18: table build time)."""
    L = arrays[0].shape[0]
    nw = _workers(L)
    if nw == 1:
        return fn(*arrays)
    from concurrent.futures import ThreadPoolExecutor

    cuts = np.linspace(0, L, nw + 1).round().astype(int)
    parts = [tuple(a[i:j] for a in arrays) for i, j in zip(cuts[:-1], cuts[1:])]
    with ThreadPoolExecutor(nw) as ex:
        res = list(ex.map(lambda p: fn(*p), parts))
    return tuple(np.concatenate(r) for r in zip(*res))


def double(R, T, n_doublings):
    """Adding–doubling of a homogeneous (symmetric) layer: (R, T) of δ → of 2ⁿ δ; (L, j, k)."""
    eye = np.eye(R.shape[-1])
    for _ in range(n_doublings):
        M = np.linalg.solve(eye[None] - R @ R, T)
        R, T = R + T @ R @ M, T @ M
    return R, T


def azimuth_modes(tab, n_modes: int = N_MODES, n_mu: int = 48, n_doublings: int = 16, n_nodes: int = 3,
                  n_probe: int = 9, node_tol: float = 0.02):
    """The lobe's shape tables of a paint without coat medium (flakes over a Lambertian base):
    the multiply scattered part M_m of the flake layer's transport, modes 0 … n_modes, handed
    to :func:`lobe_tables` (c_0, c_m, ``ms_albedo_factor``).

    The transport is solved at ``n_probe`` wavelength nodes; the kernel keeps only ``n_nodes``
    of them (the ends and the middle; each node costs it 4 (1 + M) reads per pair) where the
    tables interpolated linearly from those reproduce the ``n_probe``-node tables within
    ``node_tol`` (bound |Δc_0| + 2 Σ |Δc_m| at the worst grid point): Al flakes (c_0, c_m vary by
    ≤ 0.02 over 380–780 nm, nearly linearly: bound 0.011–0.013, the lobe ≤ 0.3 % of its maximum
    off). Coloured metals and interference flakes are not linear in λ (bound Cu 0.42, Au 1.04,
    TiO2/mica 2.8; at 3 nodes the Cu and Au lobes were 9 % and 3 % of their maximum off): they
    keep the ``n_probe`` nodes. ``tab.ms_node_error`` records the bound."""
    n, L = tab.n, tab.L
    sel = np.unique(np.linspace(0, L - 1, min(L, max(n_probe, n_nodes))).round().astype(int))
    th, mu, sn, dmu = gauss_nodes(n_mu, n)
    G = flake_kernels(tab, mu, sn, dmu, n_modes, wl=sel)  # (M+1, up/down, actual/lossless, j, k, K)
    eps = _lerp1(tab.a_tab, np.degrees(th), tab.step) / mu  # (k,) a(μ)/μ, opaque flakes' extinction per unit τ
    # × (1 − T̄(μ, λ)) per direction (extinction_ratio; 1 for opaque flakes): the extinction per unit τ
    target = eps[:, None] * tab.extinction_ratio(np.degrees(th))[:, sel]  # (k, K)
    # the kernel is renormalised as in multiple_scattering_factor (lossless column = target)
    col0 = G[0, :, 1].sum(axis=(0, 1))
    scale = np.where(col0 > 0, target / np.where(col0 > 0, col0, 1.0), 0.0)  # (k, K)
    eye = np.eye(n_mu)
    delta = tab.tau / 2.0 ** n_doublings
    mu_c = np.sqrt(1 - 1 / (n * n))
    mu_ext = np.sqrt(np.clip(1 - n * n * (1 - mu * mu), 0, 1))
    Tint = np.where(mu[:, None] > mu_c, _lerp_table(tab.Tc, _deg(mu_ext), tab.step), 0.0).T[sel]  # (K, n_mu)
    D = 1.0 - Tint  # the coat's underside mirrors this fraction back down, every mode
    lamb = 2 * mu * dmu
    lamb = lamb / lamb.sum()

    def with_coat(Rtot):
        return np.linalg.solve(eye[None] - Rtot * D[:, None, :], Rtot)

    tT = np.moveaxis(target, -1, 0)  # (K, k)
    Tdir = np.exp(-tab.tau * tT)

    def multiply_scattered(m, v):
        rho = tab.rho[sel] if v == 0 else np.ones(sel.size)
        Rb = rho[:, None, None] * np.broadcast_to(lamb[:, None], (n_mu, n_mu))[None]
        Ku = np.moveaxis(G[m, 0, v] * scale[None], -1, 0)  # (K, j, k) per unit τ
        Kd = np.moveaxis(G[m, 1, v] * scale[None], -1, 0)
        R, T = in_chunks(lambda r, t: double(r, t, n_doublings), delta * Ku,
                         delta * Kd + eye[None] * (1 - delta * tT)[:, None, :])
        Rtot = R + T @ np.linalg.solve(eye[None] - Rb @ R, Rb @ T) if m == 0 else R
        s = tT[:, :, None] + tT[:, None, :]  # ε_j + ε_k
        Mm = with_coat(Rtot) - Ku * -np.expm1(-tab.tau * s) / np.where(s > 0, s, 1.0)
        if m == 0:
            Mm = Mm - with_coat(Tdir[:, :, None] * Rb * Tdir[:, None, :])
        return Mm

    ms = [multiply_scattered(m, 0) for m in range(n_modes + 1)]
    ms_lossless = multiply_scattered(0, 1)
    lobe_tables(tab, tab.Fms, sel, ms, ms_lossless, th, mu, dmu)
    K = sel.size
    sub = np.unique(np.linspace(0, K - 1, min(K, n_nodes)).round().astype(int))
    tab.ms_node_error = 0.0
    if sub.size < K:
        full = (tab._ms_modes_spectral, tab.ms_albedo_factor, tab._ms_nodes, tab.ms_lobe_shape, tab.ms_shape_mean)
        lobe_tables(tab, tab.Fms, sel[sub], [Mm[sub] for Mm in ms], ms_lossless[sub], th, mu, dmu)
        C, Cf = tab._ms_modes_spectral, full[0]
        if C.shape[-1] == 0 or Cf.shape[-1] == 0:
            return
        # the node-subset tables, linear in λ, against the full ones at every probe node
        k = np.clip(np.searchsorted(sel[sub], sel, side="right") - 1, 0, sub.size - 2)
        t = ((sel - sel[sub][k]) / (sel[sub][k + 1] - sel[sub][k]))[None, None, :, None]
        d = np.abs(C[:, :, k] * (1.0 - t) + C[:, :, k + 1] * t - Cf)  # (NA, NA, K, 1 + M)
        tab.ms_node_error = float(np.max(d[..., 0] + 2.0 * d[..., 1:].sum(axis=-1)))
        if tab.ms_node_error > node_tol or tab.ms_lobe_shape != full[3]:
            tab._ms_modes_spectral, tab.ms_albedo_factor, tab._ms_nodes, tab.ms_lobe_shape, tab.ms_shape_mean = full


def lobe_tables(tab, F, sel, ms, ms_lossless, th, mu, dmu):
    """The multiple lobe's shape from the transport, on the external albedo grid (2°) at the
    wavelength nodes ``sel``: ``tab._ms_modes_spectral`` (NA, NA, K, 1 + M) holds c_0 and
    the modes c_m of f_ms = f_KC (1 + c_0 + 2 Σ c_m cos m φ), f_KC = (1 − E⁰(θi))(1 − E⁰(θo))
    F_ms / (π (1 − Ē⁰)) the separable lobe; ``tab.ms_albedo_factor`` (NA, L) its directional
    albedo relative to f_KC's, (1 − E⁰(θi)) F_ms.

    The transport's radiance M_m / (2π μ' dμ') on the escape-cone nodes, × T(θi) T(θo) / n²
    (the coat both ways, the n² of the solid angles), is the lobe: c_0 = M_0 / f_KC − 1.
    The separable f_KC keeps the right diffuse-incidence amount but not the directional one
    nor the polar shape (the rims' light is not separable). Lossless, the node
    quadrature's single scattering differs slightly from terms 2–3's exact integrals, so the
    relative defect δ(θi) = ⟨c_0⁰(θi, ·)⟩ of the lossless lobe is removed by the symmetric
    δ(θi) + δ(θo) − ⟨δ⟩ (⟨·⟩: mean over θo weighted by (1 − E⁰) cos θ): the lossless lobe then
    keeps exactly f_KC's directional albedo (white furnace) and c_0 stays symmetric
    (reciprocity). c_0 is then scaled to a zero diffuse-incidence mean (F_ms keeps the amount).

    Checked against the photon tracer of tests/appearance/test_brdf_montecarlo.py (6·10^5
    photons, θi = 45°): the separable lobe alone was 2–5 % off in the bins (rims: limb
    brightening), this lobe is within 2.6 SE in every bin of every case."""
    L, n = tab.L, tab.n
    K = sel.size
    mu_c = np.sqrt(1 - 1 / (n * n))
    nc = int(np.sum(mu > mu_c))  # the escape-cone nodes (θ increasing: the first nc)
    tha = np.linspace(0.0, 90.0, _NA)
    thp = np.arcsin(np.clip(np.sin(np.radians(tha)) / n, 0, 1))
    W = np.zeros((_NA, nc))
    x = np.clip(np.interp(thp, th[:nc], np.arange(nc)), 0, nc - 1.000001)
    i0 = x.astype(int)
    W[np.arange(_NA), i0] = 1 - (x - i0)
    W[np.arange(_NA), i0 + 1] += x - i0
    Tg = _lerp_table(tab.Tc, tha, tab.step)[:, sel]  # (NA, K)
    rad = (2 * np.pi * mu * dmu)[:nc]

    def on_grid(Mm):  # (K, j, k) transport -> (NA, NA, K) external BRDF
        R = Mm[:, :nc, :nc] / rad[None, :, None]
        A = np.einsum("aj,wjk,bk->abw", W, R, W, optimize=True) * Tg[:, None, :] * Tg[None, :, :] / (n * n)
        return 0.5 * (A + np.swapaxes(A, 0, 1))

    # (1 − E⁰)-weighted means over θo as the kernel integrates: the 128-node Gauss rule of the
    # albedo tables, the shape on the linear interpolants of the 2° tables, 1 − E⁰ on the 0.5° ones
    xg, wg = np.polynomial.legendre.leggauss(128)
    mu_e = 0.5 * (xg + 1)
    te = _deg(mu_e) / tab.astep
    j0 = np.minimum(te.astype(int), _NA - 2)
    Wg = np.zeros((mu_e.size, _NA))
    Wg[np.arange(mu_e.size), j0] = 1 - (te - j0)
    Wg[np.arange(mu_e.size), j0 + 1] += te - j0
    Dg = _lerp_table(tab.Dms_fine, _deg(mu_e), tab.step)[:, sel]  # (G, K)
    wgt = (wg * mu_e)[:, None] * Dg
    wgt = wgt / np.where(wgt.sum(axis=0) > 0, wgt.sum(axis=0), 1.0)

    def mean_o(X):  # (NA, NA, K) -> (NA, K)
        return np.einsum("gb,abk,gk->ak", Wg, X, wgt, optimize=True)

    Dm = tab.Dms[:, sel]
    KC = Dm[:, None, :] * Dm[None, :, :]
    ok = KC > 1e-9
    k_lossless = 1.0 / (np.pi * np.maximum(1.0 - tab.E0_bar[sel], 1e-12))
    X0 = np.where(ok, on_grid(ms_lossless) / np.where(ok, KC * k_lossless, 1.0) - 1.0, 0.0)
    delta = mean_o(X0)  # (NA, K)
    dbar = np.sum(wgt * (Wg @ delta), axis=0)  # (K,)
    Y = delta[:, None, :] + delta[None, :, :] - dbar[None, None, :]
    Fk = F[sel] * k_lossless
    okF = ok & (Fk > 0)[None, None, :]
    A0 = on_grid(ms[0])
    c0 = np.where(okF, A0 / np.where(okF, KC * Fk, 1.0) - 1.0 - Y, 0.0)
    # F_ms carries the diffuse-incidence amount, c_0 the shape: its diffuse mean c̄_0 is removed
    # (≤ 3e-4 for the shipped recipes since F_ms comes from the transport's own single/multiple split,
    # issue 18; it was 0.05–0.30 for the Fe2O3/mica pearl when F_ms subtracted the exact terms 2–3).
    # The transport's shape is used for flakes that transmit too: against the Monte-Carlo tracer
    # (tests/appearance/test_brdf_montecarlo.py, θi = 45°) it left 1/36 (pearl) and 0/36 (TiO2/mica)
    # bins beyond 4 SE + 0.1 %, the separable lobe 10/36 and 3/36. The separable lobe (c_0 = 0) remains
    # only where 1 + c̄_0 ≤ 0.1 would make the renormalised c_0 meaningless — for the whole paint, as a
    # per-node choice switched c_0 on and off along λ.
    # ``tab.ms_lobe_shape`` says which lobe a paint has, ``tab.ms_shape_mean`` the c̄_0
    cbar = np.sum(wgt * (Wg @ mean_o(c0)), axis=0)  # (K,)
    good = bool(np.all(cbar > -0.9))
    if _LOBE_SHAPE_OVERRIDE is not None:
        good = _LOBE_SHAPE_OVERRIDE == "transport"
    c0 = (1.0 + c0) / (1.0 + cbar)[None, None, :] - 1.0 if good else np.zeros_like(c0)
    tab.ms_lobe_shape = "transport" if good else "separable"
    tab.ms_shape_mean = cbar
    c0 = np.where(okF, c0, 0.0)
    okA = okF & (A0 > 0)
    modes = [np.where(okA, on_grid(Mm) / np.where(okA, A0, 1.0), 0.0) * (1.0 + c0) for Mm in ms[1:]]
    if np.any(F > 0):
        tab._ms_modes_spectral = np.ascontiguousarray(np.stack([c0] + modes, axis=-1))  # (NA, NA, K, 1 + M)
    else:
        tab._ms_modes_spectral = np.zeros((1, 1, 1, 0))
    fac = 1.0 + mean_o(c0)  # (NA, K), linear in λ between the nodes as in the kernel
    li = np.arange(L)
    tab.ms_albedo_factor = np.stack([np.interp(li, sel, fac[a]) for a in range(_NA)]) if K > 1 else np.repeat(fac, L, 1)
    tab._ms_nodes = sel.astype(np.int64)


def _lobe_at_wavelengths(C, ai0, fai, ao0, fao, cphi, seg, lw, sk, sl):
    """sl[l] = s = c_0 + 2 Σ c_m cos(m φ) (≥ −1) at each wavelength, linear in λ between the
    node sums sk[k] (bilinear in θi, θo; cphi > 1: no azimuth). Per pair: cos(m φ) once by the
    Chebyshev recursion, each node's sum once (sk: K node sums, then M cosines), then the
    wavelengths between nodes k and k + 1, ``seg[k] … seg[k + 1]`` (:func:`_node_runs`), in one
    branch-free loop per run. The kernels' wavelength loops that use sl have no branch either and
    vectorise: the pass was 2× slower with the node sums inside the wavelength loop."""
    K = C.shape[2]
    M1 = C.shape[3]
    w00 = (1.0 - fai) * (1.0 - fao)
    w01 = (1.0 - fai) * fao
    w10 = fai * (1.0 - fao)
    w11 = fai * fao
    c00 = C[ai0, ao0]
    c01 = C[ai0, ao0 + 1]
    c10 = C[ai0 + 1, ao0]
    c11 = C[ai0 + 1, ao0 + 1]
    cm = sk[K:]  # cos(m φ), m = 1 … M, by the Chebyshev recursion, once for all nodes
    c_prev, c_cur = 1.0, cphi
    for m in range(1, M1):
        cm[m - 1] = c_cur
        c_prev, c_cur = c_cur, 2.0 * cphi * c_cur - c_prev
    for k in range(K):  # bilinear in θi, θo, node k; clipped at −1
        s = c00[k, 0] * w00 + c01[k, 0] * w01 + c10[k, 0] * w10 + c11[k, 0] * w11
        if cphi <= 1.0:
            for m in range(1, M1):
                s += 2.0 * cm[m - 1] * (c00[k, m] * w00 + c01[k, m] * w01 + c10[k, m] * w10 + c11[k, m] * w11)
        sk[k] = max(s, -1.0)
    for r in range(seg.shape[0] - 1):
        s_lo = sk[r]
        ds = (sk[r + 1] if r + 1 < K else s_lo) - s_lo
        l0, l1 = seg[r], seg[r + 1]
        sl_r = sl[l0:l1]  # on views the loop vectorises (indexed from l0 it does not)
        lw_r = lw[l0:l1]
        for j in range(l1 - l0):
            sl_r[j] = s_lo + ds * lw_r[j]


def _add_modes_py(wi, wo, out, Dms, Kms, C, seg, lw, astep, chunk):
    """out += f_KC s per pair: the shape C on the albedo nodes (``astep``), the lobe's amount Dms on
    the 0.5° nodes of the 1-D tables (``interpolation._refine_deficit``)."""
    P = wi.shape[0]
    L = out.shape[1]
    NA = C.shape[0]
    NT = Dms.shape[0]
    fstep = 90.0 / (NT - 1)
    K = C.shape[2]
    n_chunks = (P + chunk - 1) // chunk
    for c in _prange(n_chunks):  # chunks of pairs: per-chunk buffers for the node and wavelength sums
        sk = np.empty(K + C.shape[3])
        sl = np.empty(L)
        for p in range(c * chunk, min(P, (c + 1) * chunk)):
            ix, iy, iz = wi[p, 0], wi[p, 1], wi[p, 2]
            ox, oy, oz = wo[p, 0], wo[p, 1], wo[p, 2]
            if iz <= 0.0 or oz <= 0.0:
                continue
            ri = np.sqrt(ix * ix + iy * iy)
            ro = np.sqrt(ox * ox + oy * oy)
            cphi = 2.0
            if ri > 1e-9 and ro > 1e-9:
                cphi = min(max(-(ix * ox + iy * oy) / (ri * ro), -1.0), 1.0)
            thi = np.arccos(min(iz, 1.0)) * (180.0 / np.pi)
            tho = np.arccos(min(oz, 1.0)) * (180.0 / np.pi)
            a0, fa = _angle_pos_nb(thi / astep, NA)  # the shape's 2° nodes
            b0, fb = _angle_pos_nb(tho / astep, NA)
            _lobe_at_wavelengths_nb(C, a0, fa, b0, fb, cphi, seg, lw, sk, sl)
            d0, fd = _angle_pos_nb(thi / fstep, NT)  # the amount's 0.5° nodes
            e0, fe = _angle_pos_nb(tho / fstep, NT)
            gd = 1.0 - fd
            ge = 1.0 - fe
            da0 = Dms[d0]
            da1 = Dms[d0 + 1]
            db0 = Dms[e0]
            db1 = Dms[e0 + 1]
            o = out[p]
            for l in range(L):  # branch-free: vectorises
                o[l] += sl[l] * ((da0[l] * gd + da1[l] * fd) * (db0[l] * ge + db1[l] * fe) * Kms[l])


if _nb is not None:
    _prange = _nb.prange
    _lobe_at_wavelengths_nb = _nb.njit(inline="always", fastmath=True, cache=True)(_lobe_at_wavelengths)
    _add_modes = _nb.njit(parallel=True, fastmath=True, cache=True)(_add_modes_py)
else:  # pragma: no cover
    _prange = range
    _lobe_at_wavelengths_nb = _lobe_at_wavelengths
    _add_modes = _add_modes_py


def _node_weights(tab):
    """Each wavelength's node interval and weight: (lk, lw), linear in the index."""
    nodes, li = tab._ms_nodes, np.arange(tab.L)
    if nodes.size > 1:
        lk = np.clip(np.searchsorted(nodes, li, side="right") - 1, 0, nodes.size - 2)
        lw = np.clip((li - nodes[lk]) / (nodes[lk + 1] - nodes[lk]), 0.0, 1.0)
    else:
        lk, lw = np.zeros(tab.L, np.int64), np.zeros(tab.L)
    return lk.astype(np.int64), lw.astype(float)


def _node_runs(lk, K):
    """Run boundaries of the node intervals: wavelengths seg[k] … seg[k + 1] − 1 have lk = k
    (lk non-decreasing; one run, 0 … L, with a single node)."""
    return np.searchsorted(lk, np.arange(max(K - 1, 1) + 1), side="left").astype(np.int64)


def lobe_factor(tab, wi, wo) -> np.ndarray:
    """s(λ) = c_0 + 2 Σ_m c_m cos(m φ) (≥ −1) for the pairs (P, 3) -> (P, L): the multiple lobe
    is f_KC (1 + s); NumPy, the same numbers as the kernels. Zeros without shape tables."""
    C = tab._ms_modes_spectral
    wi = np.asarray(wi, float).reshape(-1, 3)
    wo = np.asarray(wo, float).reshape(-1, 3)
    if C.shape[-1] == 0:
        return np.zeros((wi.shape[0], tab.L))
    NA = C.shape[0]
    xi = np.clip(_deg(wi[:, 2]) / tab.astep, 0, NA - 1.000001)
    xo = np.clip(_deg(wo[:, 2]) / tab.astep, 0, NA - 1.000001)
    a0, b0 = xi.astype(int), xo.astype(int)
    fa, fb = (xi - a0)[:, None, None], (xo - b0)[:, None, None]
    c = (C[a0, b0] * (1 - fa) * (1 - fb) + C[a0, b0 + 1] * (1 - fa) * fb + C[a0 + 1, b0] * fa * (1 - fb)
         + C[a0 + 1, b0 + 1] * fa * fb)  # (P, K, 1 + M)
    ri, ro = np.hypot(wi[:, 0], wi[:, 1]), np.hypot(wo[:, 0], wo[:, 1])
    ok = (ri > 1e-9) & (ro > 1e-9)
    cphi = np.clip(-(wi[:, 0] * wo[:, 0] + wi[:, 1] * wo[:, 1]) / np.where(ok, ri * ro, 1.0), -1.0, 1.0)
    cos_m = np.cos(np.outer(np.arccos(cphi), np.arange(1, C.shape[-1])))  # (P, M)
    s = c[..., 0] + np.where(ok[:, None], 2 * np.einsum("pkm,pm->pk", c[..., 1:], cos_m), 0.0)
    s = np.maximum(s, -1.0)
    s = np.concatenate([s, s[:, -1:]], axis=1)
    lk, lw = _node_weights(tab)
    return s[:, lk] * (1.0 - lw) + s[:, lk + 1] * lw


def add_azimuth_modes(tab, wi, wo, out):
    """out (P, L) += f_KC s: the multiple lobe's polar shape c_0 and azimuthal modes for the
    pairs (P, 3), on top of the separable f_KC that the tables' kernel adds."""
    C = tab._ms_modes_spectral
    if C.shape[-1] == 0:
        return
    lk, lw = _node_weights(tab)
    _add_modes(np.ascontiguousarray(wi, float), np.ascontiguousarray(wo, float), out, np.ascontiguousarray(tab.Dms_fine),
               np.ascontiguousarray(tab.Kms, float), C, _node_runs(lk, C.shape[2]), lw, float(tab.astep), _CHUNK_PAIRS)
