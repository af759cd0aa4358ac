"""Issue 18 (table build time): the vectorised table builders equal a straightforward per-wavelength
evaluation — the loops they replaced, kept here as references (no timings in tests)."""

from dataclasses import replace

import numpy as np
import pytest

from nmmm.appearance.brdf import CoatMedium, metallic_paint
from nmmm.appearance.brdf import ms_azimuth
from nmmm.appearance.brdf.interpolation import _deg, _lerp_table
from nmmm.appearance.brdf.ms_azimuth import _core_weight, _node_cells, flake_kernels, gauss_nodes
from nmmm.appearance.flakes import TiltDistribution, edge_scatter_fraction

W = np.linspace(380.0, 780.0, 9)


def _reference_flake_kernels(tab, mu, sn, dmu, n_modes, n_phi, core_deg, wl):
    """The flake kernel as before issue 18's table-speed work: the reflectance read per azimuth,
    node pair and wavelength, summed into G; the core by a sparse transfer per mode."""
    from scipy import sparse

    Rts = (tab.Rf[:, wl], tab.Rf0[:, wl])
    L, n_mu = Rts[0].shape[1], mu.size
    ph = (np.arange(n_phi) + 0.5) * np.pi / n_phi
    uk = np.stack([sn, 0 * sn, -mu], -1)
    G = np.zeros((n_modes + 1, 2, 2, n_mu, n_mu, L))
    cm = np.cos(np.outer(np.arange(n_modes + 1), ph))
    for iq, q in enumerate(ph):
        for s_out, sz in enumerate((1.0, -1.0)):
            uj = np.stack([sn * np.cos(q), sn * np.sin(q), sz * mu], -1)
            hv = uj[:, None, :] - uk[None, :, :]
            hn = np.linalg.norm(hv, axis=-1)
            hn = np.where(hn > 1e-12, hn, 1.0)
            c = np.abs(np.sum(hv * uk[None, :, :], axis=-1)) / hn
            hz = np.abs(hv[..., 2]) / hn
            pdf = tab.tilt.pdf(hz) * (1.0 - _core_weight(np.degrees(np.arccos(np.clip(hz, -1.0, 1.0))), core_deg))
            wgt = pdf / (4 * mu[None, :]) * (dmu[:, None] * 2 * np.pi / n_phi)
            dc = _deg(c.ravel())
            for v, Rt in enumerate(Rts):
                contrib = wgt[..., None] * _lerp_table(Rt, dc, tab.step).reshape(wgt.shape + (L,))
                G[:, s_out, v] += cm[:, iq, None, None, None] * contrib[None]
    # the nearly flat flakes, cell to cell
    n = tab.n
    mu_c = np.sqrt(1.0 - 1.0 / (n * n))
    hi, lo = _node_cells(mu, dmu, mu_c)
    edges = np.concatenate([hi[:1], lo])
    x, wx = np.polynomial.legendre.leggauss(16)
    tmax = np.radians(core_deg[1])
    t = 0.5 * (x + 1) * tmax
    wt = 0.5 * tmax * wx * np.sin(t) * tab.tilt.pdf(np.cos(t)) * _core_weight(np.degrees(t), core_deg)
    p = (np.arange(48) + 0.5) * np.pi / 48
    T, P = np.meshgrid(t, p, indexing="ij")
    h = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1).reshape(-1, 3)
    wh = np.broadcast_to((wt * 2 * np.pi / 48)[:, None], T.shape).reshape(-1)
    kk = np.broadcast_to(np.arange(n_mu)[:, None], (n_mu, h.shape[0]))
    for i in range(4):
        mu_in = hi - (i + 0.5) / 4 * dmu
        uk = np.stack([np.sqrt(np.clip(1 - mu_in * mu_in, 0, 1)), 0 * mu_in, -mu_in], -1)
        c = uk @ h.T
        out = uk[:, None, :] - 2.0 * c[..., None] * h[None]
        w = wh[None] * np.abs(c) / mu[:, None] / 4
        phi_o = np.arctan2(out[..., 1], out[..., 0])
        j = np.clip(np.searchsorted(-edges, -np.abs(out[..., 2]), side="right") - 1, 0, n_mu - 1)
        row = (np.where(out[..., 2] > 0, 0, 1) * n_mu + j) * n_mu + kk
        D = sparse.csr_matrix((w.ravel(), (row.ravel(), np.arange(c.size))), shape=(2 * n_mu * n_mu, c.size))
        dc = _deg(np.abs(c).ravel())
        for v, Rt in enumerate(Rts):
            R = _lerp_table(Rt, dc, tab.step)
            for m in range(n_modes + 1):
                G[m, :, v] += (D @ (np.cos(m * phi_o).ravel()[:, None] * R)).reshape(2, n_mu, n_mu, L)
    return G


def _paints():
    al = metallic_paint(name="Al")
    rough = al.with_(flakes=replace(al.flakes, surface_roughness=0.05, edge_fraction=edge_scatter_fraction(20e3)),
                     medium=CoatMedium(W, 1e-4, 3e-5, 0.5, 2e4), name="pigmented Al")
    t = np.linspace(0.0, 40.0, 401)  # half-normal in the tilt, 8 deg: a 1/sin peak per sr (the deposit's law)
    half_normal = TiltDistribution.tabulated(t, np.exp(-0.5 * (t / 8.0) ** 2) / np.maximum(np.sin(np.radians(t)), 1e-3))
    flat = al.with_(flakes=replace(al.flakes, tilt=half_normal, depth_range=(0.4, 1.0)), name="half-normal")
    return [al, rough, flat]


@pytest.mark.parametrize("k", range(3))
def test_flake_kernel_weight_matrix_equals_the_per_wavelength_loop(k):
    tab = _paints()[k].prepare(W)
    th, mu, sn, dmu = gauss_nodes(32, tab.n)
    wl = np.array([0, 3, 8])
    ref = _reference_flake_kernels(tab, mu, sn, dmu, 3, 24, ms_azimuth._CORE_DEG, wl)
    G = flake_kernels(tab, mu, sn, dmu, 3, n_phi=24, wl=wl)
    assert G.shape == ref.shape
    for m in range(4):  # modes m >= 1 change sign: relative to the mode's largest value
        assert np.max(np.abs(G[m] - ref[m])) <= 1e-13 * np.max(np.abs(ref[m])), m
    # all wavelengths = the selected ones, column for column
    assert np.array_equal(flake_kernels(tab, mu, sn, dmu, 0, n_phi=24)[..., wl], flake_kernels(tab, mu, sn, dmu, 0, n_phi=24, wl=wl))


def test_flake_kernel_geometry_cache_gives_the_same_kernel():
    tab = _paints()[2].prepare(W)
    th, mu, sn, dmu = gauss_nodes(32, tab.n)
    ms_azimuth._ENTRIES_CACHE.clear()
    cold = flake_kernels(tab, mu, sn, dmu, 2, n_phi=24)
    assert len(ms_azimuth._ENTRIES_CACHE) == 1
    assert np.array_equal(flake_kernels(tab, mu, sn, dmu, 2, n_phi=24), cold)
    other = metallic_paint(tilt=20.0).prepare(W)  # another tilt law: its own entries
    assert not np.allclose(flake_kernels(other, mu, sn, dmu, 0, n_phi=24)[0], cold[0])
    assert len(ms_azimuth._ENTRIES_CACHE) == 2


def _reference_pigment_kernels(g, mu, sn, dmu, n_modes, n_phi=48):
    """Henyey–Greenstein kernels as before issue 18's table-speed work: one azimuth at a time, every wavelength."""
    L, n = g.size, mu.size
    ph = (np.arange(n_phi) + 0.5) * np.pi / n_phi
    cm = np.cos(np.outer(np.arange(n_modes + 1), ph))
    P = np.zeros((n_modes + 1, 2, n, n, L))
    g2 = g * g
    for iq, q in enumerate(ph):
        for s_out, sz in enumerate((1.0, -1.0)):
            cth = (sn[:, None] * sn[None, :] * np.cos(q) - sz * mu[:, None] * mu[None, :])[..., None]
            p = (1 - g2) / (4 * np.pi * (1 + g2 - 2 * g * cth) ** 1.5)
            wgt = (dmu[:, None] * 2 * np.pi / n_phi / mu[None, :])[..., None] * p
            P[:, s_out] += cm[:, iq, None, None, None] * wgt[None]
    col = P[0].sum(axis=(0, 1))
    P *= np.where(col > 0, (1.0 / mu)[:, None] / np.where(col > 0, col, 1.0), 0.0)[None, None, None]
    return P


@pytest.mark.parametrize("g", [np.array([0.5, 0.5, 0.5]), np.array([0.1, -0.3, 0.1, 0.8]), np.array([0.6])])
def test_pigment_kernels_equal_the_per_wavelength_loop(g):
    from nmmm.appearance.brdf.coat_transport import pigment_kernels

    th, mu, sn, dmu = gauss_nodes(24, 1.5)
    ref = _reference_pigment_kernels(g, mu, sn, dmu, 3)
    P = pigment_kernels(g, mu, sn, dmu, 3)
    assert P.shape == ref.shape
    for m in range(4):
        assert np.max(np.abs(P[m] - ref[m])) <= 1e-13 * np.max(np.abs(ref[m])), m


def test_doubling_in_wavelength_chunks_is_the_one_batch_doubling():
    import numba

    rng = np.random.default_rng(3)
    R = rng.random((20, 12, 12)) * 0.02
    T = rng.random((20, 12, 12)) * 0.02 + 0.9 * np.eye(12)
    one = ms_azimuth.double(R, T, 6)
    n0 = numba.get_num_threads()
    try:
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        split = ms_azimuth.in_chunks(lambda r, t: ms_azimuth.double(r, t, 6), R, T)
    finally:
        numba.set_num_threads(n0)
    assert all(np.array_equal(a, b) for a, b in zip(one, split))
