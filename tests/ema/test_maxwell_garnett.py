"""Maxwell Garnett: limits, Hashin–Shtrikman identity, shapes, pyElli cross-check."""

import numpy as np
import pytest

from nmmm.ema import (
    Shape,
    hashin_shtrikman_bounds,
    maxwell_garnett,
    maxwell_garnett_ellipsoid,
    maxwell_garnett_multi,
    maxwell_garnett_polarizability,
    maxwell_garnett_shape,
    spheroid_depolarization,
)
from nmmm.errors import InvalidInputError

from .conftest import random_eps


def test_limits_p0_p1_equal_phases():
    rng = np.random.default_rng(1)
    ei, em = random_eps(rng, 50), random_eps(rng, 50)
    np.testing.assert_allclose(maxwell_garnett(ei, em, 0.0), em, rtol=1e-13)
    np.testing.assert_allclose(maxwell_garnett(ei, em, 1.0), ei, rtol=1e-13)
    p = rng.uniform(0, 1, 50)
    np.testing.assert_allclose(maxwell_garnett(em, em, p), em, rtol=1e-13)


def test_dilute_limit_is_rayleigh_polarizability():
    """eps ≈ eps_m (1 + 3 p beta), beta = (eps_i - eps_m)/(eps_i + 2 eps_m), the Rayleigh
    polarizability of dilute spheres (Clausius–Mossotti; Bohren & Huffman eq. 8.50); the series of
    eq. (2), (1 + 2x)/(1 - x) = 1 + 3x + 3x² + 3x³/(1 - x) with x = p beta, gives the remainder."""
    ei, em = -10 + 1.2j, 2.13
    beta = (ei - em) / (ei + 2 * em)
    for p in (1e-2, 1e-3, 1e-4):
        x = p * beta
        err = abs(maxwell_garnett(ei, em, p) - em * (1 + 3 * x + 3 * x**2))
        assert err == pytest.approx(abs(3 * em * x**3 / (1 - x)), rel=1e-4)


def test_equals_hashin_shtrikman_bound_of_the_host():
    """Real phases: MG with the lower-ε host is the HS lower bound, with the higher the upper
    (Hashin & Shtrikman 1962: eps_HS(eps_ref) = (Σ f_i/(eps_i + 2 eps_ref))^-1 - 2 eps_ref)."""
    rng = np.random.default_rng(2)
    e1, e2 = rng.uniform(1, 20, 200), rng.uniform(1, 20, 200)
    f = rng.uniform(0, 1, 200)
    lo, hi = hashin_shtrikman_bounds([e1, e2], [f, 1 - f])
    mg_in_1 = maxwell_garnett(e2, e1, 1 - f)  # phase 1 is the host
    mg_in_2 = maxwell_garnett(e1, e2, f)
    low_host = np.where(e1 < e2, mg_in_1, mg_in_2)
    high_host = np.where(e1 < e2, mg_in_2, mg_in_1)
    np.testing.assert_allclose(low_host.real, lo, rtol=1e-12)
    np.testing.assert_allclose(high_host.real, hi, rtol=1e-12)
    # the HS formula written independently, host = phase 2
    hs2 = 1 / (f / (e1 + 2 * e2) + (1 - f) / (3 * e2)) - 2 * e2
    np.testing.assert_allclose(mg_in_2.real, hs2, rtol=1e-12)


def test_pyelli_maxwell_garnett_agrees(gold_silica):
    elli = pytest.importorskip("elli")
    w, _, _, ea, es = gold_silica
    host = elli.IsotropicMaterial(elli.TableEpsilon(lbda=w, epsilon=es))
    guest = elli.IsotropicMaterial(elli.TableEpsilon(lbda=w, epsilon=ea))
    for f in (0.0005, 0.05, 0.3, 0.8):
        ref = elli.MaxwellGarnettEMA(host, guest, f).get_tensor(w)[:, 0, 0]
        np.testing.assert_allclose(maxwell_garnett(ea, es, f), ref, rtol=1e-10)


def test_broadcast_401_wavelengths_by_1000_fractions(gold_silica):
    w, _, _, ea, es = gold_silica
    ea, es = ea[:401, None], es[:401, None]
    p = np.linspace(0, 1, 1000)
    out = maxwell_garnett(ea, es, p)
    assert out.shape == (401, 1000)
    assert np.all(out.imag >= 0)
    np.testing.assert_allclose(out[123, 456], maxwell_garnett(ea[123, 0], es[123, 0], p[456]))


def test_ellipsoid_sphere_reduces_to_eq2():
    rng = np.random.default_rng(3)
    ei, em, p = random_eps(rng, 30), random_eps(rng, 30), rng.uniform(0, 1, 30)
    L = np.full(3, 1 / 3)
    ref = maxwell_garnett(ei, em, p)
    np.testing.assert_allclose(maxwell_garnett_ellipsoid(ei, em, p, L), ref, rtol=1e-12)
    al = maxwell_garnett_ellipsoid(ei, em, p, L, orientation="aligned")
    assert al.shape == (30, 3)
    np.testing.assert_allclose(al, np.repeat(ref[:, None], 3, 1), rtol=1e-12)


def test_aligned_needles_and_plates_are_wiener_laminates():
    """L -> 0 along the field: parallel layers/cylinders, eps = arithmetic mean; L -> 1: series
    layers, harmonic mean (Wiener 1912) — exact analytic limits of aligned MG."""
    ei, em, f = -8 + 0.9j, 2.25 + 0.01j, 0.3
    aligned = maxwell_garnett_ellipsoid(ei, em, f, [0.0, 0.5, 0.5], orientation="aligned")
    np.testing.assert_allclose(aligned[0], f * ei + (1 - f) * em, rtol=1e-13)
    aligned = maxwell_garnett_ellipsoid(ei, em, f, [1.0, 0.0, 0.0], orientation="aligned")
    np.testing.assert_allclose(aligned[0], 1 / (f / ei + (1 - f) / em), rtol=1e-13)


def test_random_orientation_first_order_is_mean_polarizability():
    """Dilute random ellipsoids: eps ≈ eps_m (1 + p <alpha>) with <alpha> the orientational mean
    of (eps_i - eps_m)/(eps_m + L_j (eps_i - eps_m)) (Bohren & Huffman eq. 5.32 / §8.5)."""
    ei, em = -12 + 1.0j, 2.1
    L = spheroid_depolarization(3.0)
    alpha = np.mean((ei - em) / (em + L * (ei - em)))
    p = 1e-6
    np.testing.assert_allclose(maxwell_garnett_ellipsoid(ei, em, p, L), em * (1 + p * alpha), rtol=1e-9)


def test_depolarization_broadcasts_over_shapes(gold_silica):
    w, _, _, ea, es = gold_silica
    L = spheroid_depolarization(np.array([1.0, 2.0, 3.0, 4.0]))  # (4, 3)
    out = maxwell_garnett_ellipsoid(ea[:, None], es[:, None], 0.0005, L[None, :, :])
    assert out.shape == (w.size, 4)
    peaks = w[np.argmax(out.imag, axis=0)]
    assert np.all(np.diff(peaks) > 0)  # longitudinal resonance red-shifts with aspect ratio


def test_shape_cube_and_polarizability_form():
    ei, em, p = -6 + 0.5j, 2.25, 0.01
    # sphere through the polarizability form = eq. (2)
    alpha = 3 * (ei - em) / (ei + 2 * em)
    np.testing.assert_allclose(maxwell_garnett_polarizability(em, p, alpha), maxwell_garnett(ei, em, p), rtol=1e-13)
    np.testing.assert_allclose(maxwell_garnett_shape(ei, em, p, Shape.sphere()), maxwell_garnett(ei, em, p), rtol=1e-13)
    # cube: conducting limit alpha -> 3.6442 (Sihvola et al. 2007), first order (eps_i - eps_m)/eps_m
    from nmmm.ema import cube_polarizability

    assert abs(cube_polarizability(1e9 + 0j, 1.0) - 3.6442) < 1e-6
    np.testing.assert_allclose(cube_polarizability(1.001 + 0j, 1.0), 0.001, rtol=1e-3)
    cube = maxwell_garnett_shape(np.array([ei]), em, p, Shape.cube())
    assert cube.shape == (1,) and cube.imag[0] > 0


def test_multi_populations_reduce_to_single():
    ei, em = -6 + 0.5j, 2.25
    one = maxwell_garnett(ei, em, 0.2)
    two = maxwell_garnett_multi(em, [(ei, 0.12, None), (ei, 0.08, Shape.sphere())])
    np.testing.assert_allclose(two, one, rtol=1e-13)


@pytest.mark.parametrize("bad", [
    dict(fraction=1.2), dict(fraction=-0.1), dict(fraction=np.nan), dict(ei=np.nan), dict(ei=2 - 1j),
])
def test_bad_input(bad):
    kw = dict(ei=2 + 0.1j, em=1.5, fraction=0.2) | bad
    with pytest.raises(InvalidInputError):
        maxwell_garnett(kw["ei"], kw["em"], kw["fraction"])


def test_bad_depolarization():
    with pytest.raises(InvalidInputError, match="sum to 1"):
        maxwell_garnett_ellipsoid(2.0, 1.0, 0.1, [0.5, 0.5, 0.5])
    with pytest.raises(InvalidInputError, match="length 3"):
        maxwell_garnett_ellipsoid(2.0, 1.0, 0.1, [0.5, 0.5])
    with pytest.raises(InvalidInputError, match="orientation"):
        maxwell_garnett_ellipsoid(2.0, 1.0, 0.1, [1 / 3] * 3, orientation="sideways")
    with pytest.raises(InvalidInputError, match="sum to"):
        maxwell_garnett_multi(1.0, [(2.0, 0.7, None), (3.0, 0.6, None)])
