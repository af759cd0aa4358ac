"""Adding–doubling against iadpython (run here on the same inputs) and analytic limits.

iadpython 0.5.3 is wrong for a slab of index 1 at >= 32 quadrature points: those cases are
not used. iadpython puts glass slides above and below; slides of the slab's own index make
plain air/slab interfaces.
"""

import numpy as np
import pytest
from scipy.special import expn

from nmmm.errors import InvalidInputError
from nmmm.layers.adding_doubling_method import adding_doubling, radau_quadrature

iad = pytest.importorskip("iadpython")

CASES = [
    (0.9, 1.0, 0.0, 1.0, 8),
    (0.9, 1.0, 0.5, 1.0, 16),
    (0.99, 5.0, 0.8, 1.5, 16),
    (0.5, 0.3, 0.9, 1.4, 16),
    (1.0, 2.0, 0.7, 1.5, 16),
    (0.95, 1e4, 0.6, 1.55, 16),
    (0.999, 50.0, 0.3, 1.33, 24),
]


@pytest.mark.parametrize("a,b,g,n,N", CASES)
def test_against_iadpython(a, b, g, n, N):
    s = iad.Sample(a=a, b=b, g=g, n=n, n_above=n, n_below=n, quad_pts=N)
    ur1, ut1, uru, utu = s.rt()
    r = adding_doubling(a, b, g, n_slab=n, quad_pts=N, quadrature="prahl")  # iadpython's nodes
    np.testing.assert_allclose(
        [r.reflectance, r.transmittance, r.diffuse_reflectance, r.diffuse_transmittance],
        [ur1, ut1, uru, utu],
        atol=2e-5,
    )


def test_vectorised_batch_matches_iadpython_arrays():
    a = np.array([0.3, 0.8, 0.95, 0.999])
    s = iad.Sample(a=a, b=2.0, g=0.6, n=1.5, n_above=1.5, n_below=1.5, quad_pts=16)
    ur1, ut1, uru, utu = s.rt()
    r = adding_doubling(a, 2.0, 0.6, n_slab=1.5, quad_pts=16, quadrature="prahl")
    np.testing.assert_allclose(r.reflectance, ur1, atol=2e-5)
    np.testing.assert_allclose(r.transmittance, ut1, atol=2e-5)


def test_opaque_slab_is_the_thick_limit():
    r_inf = adding_doubling(0.95, np.inf, 0.6, n_slab=1.55, quad_pts=16, quadrature="prahl")
    s = iad.Sample(a=0.95, b=1e4, g=0.6, n=1.55, n_above=1.55, n_below=1.55, quad_pts=16)
    assert float(r_inf.reflectance) == pytest.approx(s.rt()[0], abs=2e-5)
    assert float(r_inf.transmittance) < 1e-15


def test_energy_conservation():
    tau = np.array([0.01, 0.5, 3.0, 40.0])
    for n in (1.0, 1.5):
        r = adding_doubling(1.0, tau, 0.85, n_slab=n)
        np.testing.assert_allclose(r.reflectance + r.transmittance, 1.0, atol=1e-10)
        np.testing.assert_allclose(r.diffuse_reflectance + r.diffuse_transmittance, 1.0, atol=1e-10)
        # on a white Lambertian substrate, under a lossless clear coat, nothing is lost
        w = adding_doubling(1.0, tau, 0.85, n_slab=n, substrate_reflectance=1.0)
        np.testing.assert_allclose(w.reflectance, 1.0, atol=1e-10)
    # with absorption, R + T < 1
    r = adding_doubling(0.9, tau, 0.5, n_slab=1.5)
    assert np.all(r.reflectance + r.transmittance < 1)


def test_non_scattering_limits():
    tau = np.array([0.05, 0.7, 2.0])
    # no interfaces: Beer-Lambert
    r = adding_doubling(0.0, tau, 0.0, n_slab=1.0)
    np.testing.assert_allclose(r.transmittance, np.exp(-tau), rtol=1e-6)  # diamond start: O(dtau^3)
    # two Fresnel interfaces, incoherent: T = (1-R)^2 e^-t / (1 - R^2 e^-2t)
    R = ((1.5 - 1) / (1.5 + 1)) ** 2
    r = adding_doubling(0.0, tau, 0.0, n_slab=1.5)
    np.testing.assert_allclose(r.transmittance, (1 - R) ** 2 * np.exp(-tau) / (1 - R**2 * np.exp(-2 * tau)), rtol=1e-6)
    np.testing.assert_allclose(r.specular_reflectance, R)
    # Lambertian substrate under an absorbing non-scattering layer, index 1:
    # R = rho e^-t 2 E3(t)
    rho = 0.6
    r = adding_doubling(0.0, tau, 0.0, n_slab=1.0, substrate_reflectance=rho, quad_pts=32)
    np.testing.assert_allclose(r.reflectance, rho * np.exp(-tau) * 2 * expn(3, tau), rtol=2e-4)
    # the same layer given as a clear coat over a zero-thickness slab
    c = adding_doubling(0.0, 0.0, 0.0, n_slab=1.0, substrate_reflectance=rho, clear_coat_optical_thickness=tau, quad_pts=32)
    np.testing.assert_allclose(c.reflectance, rho * np.exp(-tau) * 2 * expn(3, tau), rtol=2e-4)


def test_lambertian_substrate_under_interface_is_saunderson():
    # no slab: R = k1 + (1-k1) rho (1-k2) / (1 - k2 rho) with Judd's k2 = 0.596 for n = 1.5
    rho = np.array([0.2, 0.5, 0.9])
    r = adding_doubling(0.0, 0.0, 0.0, n_slab=1.5, substrate_reflectance=rho, quad_pts=32)
    k1, k2 = 0.04, 0.5963
    np.testing.assert_allclose(r.reflectance, k1 + (1 - k1) * rho * (1 - k2) / (1 - k2 * rho), atol=3e-4)


def test_radau_quadrature_integrates_polynomials():
    x, w = radau_quadrature(6, 0.2, 1.0)
    assert x[-1] == pytest.approx(1.0)
    for p in range(10):  # exact to degree 2n - 2 = 10
        assert np.sum(w * x**p) == pytest.approx((1 - 0.2 ** (p + 1)) / (p + 1), rel=1e-12)


@pytest.mark.parametrize(
    "kwargs",
    [dict(albedo=1.2), dict(optical_thickness=-1.0), dict(g=1.0), dict(n_slab=0.5), dict(quad_pts=7), dict(substrate_reflectance=1.5)],
)
def test_bad_input(kwargs):
    args = dict(albedo=0.9, optical_thickness=1.0, g=0.5, n_slab=1.5)
    args.update(kwargs)
    with pytest.raises(InvalidInputError):
        adding_doubling(**args)
