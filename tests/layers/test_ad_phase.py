"""Adding–doubling with a general (Legendre-series) phase function, and the Mie phase
function of a paint film.

Independent references: iadpython (Prahl's adding-doubling, HG only) run here; the exact
semi-infinite isotropic solution through Chandrasekhar's H-function, solved here from its
integral equation; miepython's unpolarized phase function projected on Legendre
polynomials by scipy quadrature.
"""

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import eval_legendre

from nmmm.errors import InvalidInputError
from nmmm.layers.adding_doubling_method import adding_doubling, hg_legendre_moments
from nmmm.layers.distributions import lognormal, monodisperse
from nmmm.layers.paint import PaintFilm, mie_phase_moments, paint_reflectance

iad = pytest.importorskip("iadpython")
miepython = pytest.importorskip("miepython")


def _fluxes(r):
    return np.array([r.reflectance, r.transmittance, r.diffuse_reflectance, r.diffuse_transmittance])


@pytest.mark.parametrize("a,b,g,n,N", [(0.9, 1.0, 0.5, 1.0, 16), (0.99, 5.0, 0.8, 1.5, 16), (0.5, 0.3, 0.9, 1.4, 24)])
def test_hg_as_legendre_series_matches_hg_path_and_iadpython(a, b, g, n, N):
    s = iad.Sample(a=a, b=b, g=g, n=n, n_above=n, n_below=n, quad_pts=N)
    ref = np.array(s.rt())
    # more moments than the quadrature uses: the series is cut at N and delta-M'd with f = g^N
    gen = adding_doubling(a, b, None, n_slab=n, quad_pts=N, phase_moments=hg_legendre_moments(g, 60), quadrature="prahl")
    hg = adding_doubling(a, b, g, n_slab=n, quad_pts=N, quadrature="prahl")
    np.testing.assert_allclose(_fluxes(gen), ref, atol=2e-5)
    np.testing.assert_allclose(_fluxes(gen), _fluxes(hg), atol=1e-12)


def test_per_element_phase_moments_broadcast():
    g = np.array([0.2, 0.6, 0.85])
    gen = adding_doubling(0.95, 2.0, None, n_slab=1.5, phase_moments=hg_legendre_moments(g, 17), quad_pts=16,
                         quadrature="prahl")  # iadpython's nodes
    s = iad.Sample(a=0.95, b=2.0, g=g, n=1.5, n_above=1.5, n_below=1.5, quad_pts=16)
    np.testing.assert_allclose(gen.reflectance, s.rt()[0], atol=2e-5)


def _chandrasekhar_h(a, n=400, iters=3000):
    """H(μ) for isotropic scattering, albedo a: 1/H(μ) = √(1−a) + (a/2)∫ μ' H(μ')/(μ+μ') dμ'
    (Chandrasekhar, Radiative Transfer, 1960, ch. V, eq. 5.9 in its alternative form)."""
    x, w = np.polynomial.legendre.leggauss(n)
    mu, wq = (x + 1) / 2, w / 2
    h = np.ones(n)
    for _ in range(iters):
        h_new = 1 / (np.sqrt(1 - a) + a / 2 * np.sum(wq * mu * h / (mu[:, None] + mu), axis=1))
        if np.max(np.abs(h_new - h)) < 1e-13:
            break
        h = h_new
    H = lambda m: 1 / (np.sqrt(1 - a) + a / 2 * np.sum(wq * mu * h / (m + mu)))  # noqa: E731
    return mu, wq, h, H


@pytest.mark.parametrize("a", [0.5, 0.9, 0.99])
def test_isotropic_semi_infinite_against_chandrasekhar(a):
    mu, wq, h, H = _chandrasekhar_h(a)
    # the solver itself: zeroth moment α0 = ∫H dμ = (2/a)(1 − √(1−a)) (Chandrasekhar 1960, eq. 5.27)
    assert np.sum(wq * h) == pytest.approx(2 / a * (1 - np.sqrt(1 - a)), rel=1e-8)
    # plane albedo r(μ0) = 1 − H(μ0)√(1−a) and spherical albedo 1 − 2√(1−a)∫H μ dμ
    # (van de Hulst 1980, §4.3; Chandrasekhar 1960, ch. V) — index-matched, isotropic χ_l = 0 (l > 0)
    r_col = 1 - H(1.0) * np.sqrt(1 - a)
    r_dif = 1 - 2 * np.sqrt(1 - a) * np.sum(wq * h * mu)
    r = adding_doubling(a, np.inf, None, n_slab=1.0, phase_moments=[1.0], quad_pts=16)
    assert float(r.reflectance) == pytest.approx(r_col, abs=1e-6)
    assert float(r.diffuse_reflectance) == pytest.approx(r_dif, abs=1e-6)


def test_isotropic_finite_slab_against_iadpython():
    s = iad.Sample(a=0.9, b=1.5, g=0.0, n=1.4, n_above=1.4, n_below=1.4, quad_pts=16)
    r = adding_doubling(0.9, 1.5, None, n_slab=1.4, phase_moments=np.eye(1, 5)[0], quad_pts=16, quadrature="prahl")
    np.testing.assert_allclose(_fluxes(r), s.rt(), atol=2e-5)


def _lossless_film(distribution, thickness_nm=5e3, substrate=0.0):
    return PaintFilm(pigment=2.6 + 0j, binder=1.5 + 0j, distribution=distribution, volume_fraction=0.1, thickness_nm=thickness_nm, substrate_reflectance=substrate)


def test_mie_moments_against_miepython_phase_function():
    # one size, relative index 2.6/1.5, x = π·600·1.5/550 ≈ 5.1: a strongly non-HG phase function
    w = np.array([550.0])
    chi = mie_phase_moments(_lossless_film(monodisperse(600.0)), w, n_moments=8)[0]
    m, x = 2.6 / 1.5, np.pi * 600.0 * 1.5 / 550.0
    p = lambda t: float(miepython.i_unpolarized(m, x, np.array([t]), norm="one")[0])  # noqa: E731
    norm = quad(p, -1, 1, limit=400)[0]
    ref = [quad(lambda t: p(t) * eval_legendre(ell, t), -1, 1, limit=400)[0] / norm for ell in range(8)]
    np.testing.assert_allclose(chi, ref, atol=2e-6)
    g_ref = miepython.efficiencies_mx(m, x)[3]
    assert chi[1] == pytest.approx(float(g_ref), abs=1e-8)
    assert np.max(np.abs(chi[2:] - chi[1] ** np.arange(2, 8))) > 0.05  # not HG


def test_energy_conservation_with_mie_phase_function():
    w = np.array([450.0, 550.0, 650.0])
    chi = mie_phase_moments(_lossless_film(lognormal(400.0, 1.3, n_nodes=12)), w, n_moments=17)
    tau = np.array([0.05, 1.0, 8.0, 60.0])[:, None]
    for n in (1.0, 1.5):
        r = adding_doubling(1.0, tau, None, n_slab=n, phase_moments=chi)
        np.testing.assert_allclose(r.reflectance + r.transmittance, 1.0, atol=1e-10)
        np.testing.assert_allclose(r.diffuse_reflectance + r.diffuse_transmittance, 1.0, atol=1e-10)
        white = adding_doubling(1.0, tau, None, n_slab=n, substrate_reflectance=1.0, phase_moments=chi)
        np.testing.assert_allclose(white.reflectance, 1.0, atol=1e-10)
    # the whole paint chain, lossless pigment and binder on a white substrate: all comes back
    film = _lossless_film(lognormal(400.0, 1.3, n_nodes=12), substrate=1.0)
    R = paint_reflectance(film, w, solver="ad", phase_function="mie").reflectance
    np.testing.assert_allclose(R, 1.0, atol=1e-9)


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(g=0.5, phase_moments=[1.0, 0.5]),
        dict(g=None),
        dict(g=None, phase_moments=[0.9, 0.5]),
        dict(g=None, phase_moments=[1.0, 1.3]),
        dict(g=None, phase_moments=[1.0] * 20),
    ],
)
def test_bad_phase_input(kwargs):
    with pytest.raises(InvalidInputError):
        adding_doubling(0.9, 1.0, n_slab=1.5, **kwargs)


def test_bad_phase_function_name():
    with pytest.raises(InvalidInputError):
        paint_reflectance(_lossless_film(monodisperse(300.0)), [550.0], solver="ad", phase_function="rayleigh")
