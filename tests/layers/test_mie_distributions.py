"""Size distributions, equivalent spheres, Percus–Yevick S(q) and per-volume cross sections.

References used here: log-normal moments ⟨D^k⟩ = D_g^k exp(k²σ²/2) (analytic); the PY
compressibility limit S(0) = (1−f)⁴/(1+2f)² and S(q) = 1/(1 − ρ ĉ(q)) from Wertheim's (1963)
direct correlation function c(r) (Fourier transformed numerically here); the sphere's
C/V = 3Q/(2D) computed with miepython.
"""

import numpy as np
import pytest
from scipy.integrate import quad

from nmmm.errors import InvalidInputError
from nmmm.layers.distributions import (
    equivalent_sphere_diameter,
    histogram,
    lognormal,
    monodisperse,
    percus_yevick_structure_factor,
    pigment_optics,
)


def test_lognormal_moments():
    dg, sg = 180.0, 1.4
    dist = lognormal(dg, sg, n_nodes=64)
    s = np.log(sg)
    for k in (1, 2, 3, 6):
        assert dist.moment(k) == pytest.approx(dg**k * np.exp(k * k * s * s / 2), rel=2e-3)


def test_histogram_uniform_bin():
    dist = histogram([100.0, 300.0], [5.0], nodes_per_bin=8)
    assert dist.moment(1) == pytest.approx(200.0)
    assert dist.moment(2) == pytest.approx((300.0**3 - 100.0**3) / 3 / 200.0, rel=2e-3)


def test_equivalent_spheres():
    a = 144.0
    assert equivalent_sphere_diameter("cube", edge_nm=a) == pytest.approx(a * (6 / np.pi) ** (1 / 3))
    assert equivalent_sphere_diameter("cube", body_diagonal_nm=a * np.sqrt(3)) == pytest.approx(a * (6 / np.pi) ** (1 / 3))
    assert equivalent_sphere_diameter("cube", "surface", edge_nm=a) == pytest.approx(np.sqrt(6 / np.pi) * a)
    L, D = 400.0, 50.0
    V, S = np.pi * D**2 / 4 * L, np.pi * D * L + np.pi * D**2 / 2
    assert equivalent_sphere_diameter("rod", "volume_to_surface", length_nm=L, diameter_nm=D) == pytest.approx(6 * V / S)
    # a spheroid with equal axes is a sphere for every method; near-spherical ones are continuous
    for method in ("volume", "surface", "volume_to_surface"):
        assert equivalent_sphere_diameter("spheroid", method, polar_diameter_nm=90, equatorial_diameter_nm=90) == pytest.approx(90)
        for p in (89.999, 90.001):
            assert equivalent_sphere_diameter("spheroid", method, polar_diameter_nm=p, equatorial_diameter_nm=90) == pytest.approx(90, rel=1e-4)
    with pytest.raises(InvalidInputError):
        equivalent_sphere_diameter("cube")
    with pytest.raises(InvalidInputError):
        equivalent_sphere_diameter("cube", method="nonsense", edge_nm=1)
    with pytest.raises(InvalidInputError):
        equivalent_sphere_diameter("rod", length_nm=-1, diameter_nm=5)


@pytest.mark.parametrize("f", [0.05, 0.2, 0.4])
def test_percus_yevick_against_wertheim_direct_correlation(f):
    # Wertheim (1963): c(r) = -l1 - 6 f l2 (r/d) - f l1/2 (r/d)^3 for r < d, 0 beyond
    l1 = (1 + 2 * f) ** 2 / (1 - f) ** 4
    l2 = -((1 + f / 2) ** 2) / (1 - f) ** 4
    d = 1.0
    rho = 6 * f / (np.pi * d**3)

    def c_hat(q):
        fun = lambda r: (-l1 - 6 * f * l2 * r - f * l1 / 2 * r**3) * (np.sinc(q * r / np.pi)) * 4 * np.pi * r * r
        return quad(fun, 0, d, limit=200)[0]

    for qd in (0.01, 1.0, 3.0, 7.0, 12.0, 25.0):
        ref = 1 / (1 - rho * c_hat(qd))
        assert percus_yevick_structure_factor(qd, f) == pytest.approx(ref, rel=1e-7)
    assert percus_yevick_structure_factor(0.0, f) == pytest.approx((1 - f) ** 4 / (1 + 2 * f) ** 2, rel=1e-12)


def test_percus_yevick_dilute_and_bad_input():
    np.testing.assert_allclose(percus_yevick_structure_factor(np.linspace(0, 20, 50), 0.0), 1.0)
    with pytest.raises(InvalidInputError):
        percus_yevick_structure_factor(1.0, 0.7)
    with pytest.raises(InvalidInputError):
        percus_yevick_structure_factor(1.0, -0.1)


def _wertheim_structure_factor(qd, f):
    """S(q) = 1/(1 − ρ ĉ(q)) with Wertheim's (1963) c(r), Fourier transformed by quadrature."""
    l1 = (1 + 2 * f) ** 2 / (1 - f) ** 4
    l2 = -((1 + f / 2) ** 2) / (1 - f) ** 4
    rho = 6 * f / np.pi
    fun = lambda r: (-l1 - 6 * f * l2 * r - f * l1 / 2 * r**3) * np.sinc(qd * r / np.pi) * 4 * np.pi * r * r
    return 1 / (1 - rho * quad(fun, 0, 1, limit=200)[0])


def test_dependent_scattering_against_miepython_and_wertheim():
    """Ishimaru & Kuga (1982): the dense medium's scattering is the single-particle
    differential cross section weighted by S(q), q = 2k sin(θ/2), integrated over angles.
    Reference: miepython's S1, S2 and Wertheim's S(q), integrated here by Gauss–Legendre;
    in the Rayleigh limit the ratio tends to S(0) = (1 − f)⁴/(1 + 2f)² (PY compressibility)."""
    miepython = pytest.importorskip("miepython")
    f, n_med, m_p, wl = 0.2, 1.55, 2.9 + 0.1j, 550.0
    mu, wq = np.polynomial.legendre.leggauss(96)
    k = 2 * np.pi * n_med / wl
    for D in (10.0, 180.0):
        x = np.pi * D * n_med / wl
        s1, s2 = miepython.S1_S2(m_p / n_med, x, mu, norm="wiscombe")
        phase = np.abs(s1) ** 2 + np.abs(s2) ** 2
        S = np.array([_wertheim_structure_factor(2 * k * np.sqrt((1 - m) / 2) * D, f) for m in mu])
        ratio = np.sum(wq * phase * S) / np.sum(wq * phase)
        g_ref = np.sum(wq * phase * S * mu) / np.sum(wq * phase * S)
        ind = pigment_optics(m_p, n_med, monodisperse(D), [wl])
        dense = pigment_optics(m_p, n_med, monodisperse(D), [wl], dependent_scattering_fraction=f)
        assert float(dense.scattering_per_nm[0]) == pytest.approx(float(ind.scattering_per_nm[0]) * ratio, rel=1e-6)
        assert float(dense.g[0]) == pytest.approx(g_ref, rel=1e-6, abs=1e-9)
        np.testing.assert_allclose(dense.absorption_per_nm, ind.absorption_per_nm, rtol=1e-12)
        if D == 10.0:
            assert ratio == pytest.approx((1 - f) ** 4 / (1 + 2 * f) ** 2, rel=0.01)


def test_monodisperse_cross_sections_per_volume_against_miepython():
    miepython = pytest.importorskip("miepython")
    w = np.array([450.0, 550.0, 650.0])
    D = 220.0
    opt = pigment_optics(2.8 + 0.2j, 1.5, monodisperse(D), w)
    qext, qsca, qback, g = miepython.efficiencies(np.full(3, 2.8 + 0.2j), np.full(3, D), w, n_env=1.5)
    np.testing.assert_allclose(opt.scattering_per_nm, 1.5 * qsca / D, rtol=1e-9)
    np.testing.assert_allclose(opt.absorption_per_nm, 1.5 * (qext - qsca) / D, rtol=1e-9)
    np.testing.assert_allclose(opt.g, g, rtol=1e-9)


def test_structure_factor_correction():
    w = np.linspace(400, 700, 7)
    dist = lognormal(180.0, 1.3, n_nodes=16)
    ind = pigment_optics(2.9 + 0.1j, 1.55, dist, w)
    # at zero fraction S = 1: the angular integral reproduces the independent result
    zero = pigment_optics(2.9 + 0.1j, 1.55, dist, w, dependent_scattering_fraction=0.0, n_angles=128)
    np.testing.assert_allclose(zero.scattering_per_nm, ind.scattering_per_nm, rtol=1e-9)
    np.testing.assert_allclose(zero.g, ind.g, rtol=1e-9)
    # dense packing suppresses scattering of small particles (S(q) < 1 at small q)
    dense = pigment_optics(2.9 + 0.1j, 1.55, dist, w, dependent_scattering_fraction=0.2)
    assert np.all(dense.scattering_per_nm < ind.scattering_per_nm)
    np.testing.assert_allclose(dense.absorption_per_nm, ind.absorption_per_nm)
