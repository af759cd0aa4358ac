"""Wiener, Hashin–Shtrikman and Bergman–Milton bounds; Looyenga."""

import numpy as np
import pytest

from nmmm.ema import (
    bergman_milton_bounds,
    bruggeman,
    hashin_shtrikman_bounds,
    looyenga,
    maxwell_garnett,
    maxwell_garnett_ellipsoid,
    wiener_bounds,
)
from nmmm.errors import InvalidInputError

from .conftest import random_eps


def test_real_bounds_are_nested_and_contain_the_mixing_rules():
    rng = np.random.default_rng(20)
    for n in (2, 3, 4):
        eps = [rng.uniform(1, 30, 500) for _ in range(n)]
        fr = list(rng.dirichlet(np.ones(n), 500).T)
        wl, wu = wiener_bounds(eps, fr)
        hl, hu = hashin_shtrikman_bounds(eps, fr)
        br = bruggeman(eps, fr).real
        lo = looyenga(eps, fr).real
        tol = 1e-9
        assert np.all(wl.real <= hl + tol) and np.all(hl <= br + tol) and np.all(br <= hu + tol)
        assert np.all(hu <= wu.real + tol)
        assert np.all((lo >= wl.real - tol) & (lo <= wu.real + tol))


def test_complex_regions_end_at_the_maxwell_garnett_points_and_collapse_for_real_phases():
    ea, eb, f = -8 + 1.1j, 2.2 + 0.05j, 0.3
    r = bergman_milton_bounds(ea, eb, f)
    mg_a_in_b, mg_b_in_a = maxwell_garnett(ea, eb, f), maxwell_garnett(eb, ea, 1 - f)
    for arc in (r.arc_1, r.arc_2):
        np.testing.assert_allclose(arc[0], mg_a_in_b, rtol=1e-12)
        np.testing.assert_allclose(arc[-1], mg_b_in_a, rtol=1e-12)
    np.testing.assert_allclose(hashin_shtrikman_bounds([ea, eb], [f, 1 - f]), (mg_a_in_b, mg_b_in_a))
    real = bergman_milton_bounds(6.0, 2.0, 0.4)
    lo, hi = hashin_shtrikman_bounds([6.0, 2.0], [0.4, 0.6])
    for arc in (real.arc_1, real.arc_2):
        assert np.all(np.abs(arc.imag) < 1e-12) and np.all((arc.real >= lo - 1e-12) & (arc.real <= hi + 1e-12))
    w = bergman_milton_bounds(6.0, 2.0, 0.4, kind="wiener")
    wl, wu = wiener_bounds([6.0, 2.0], [0.4, 0.6])
    assert np.isclose(w.arc_1.real.min(), wl.real) and np.isclose(w.arc_1.real.max(), wu.real)


def test_laminates_of_laminates_lie_in_the_wiener_region():
    """Realizable anisotropic microstructures (a series stack of a parallel laminate and a
    series laminate) must lie in the Wiener (first-order Bergman–Milton) region."""
    rng = np.random.default_rng(21)
    ea, eb = random_eps(rng, 400), random_eps(rng, 400)
    f1, f2, t = rng.uniform(0, 1, (3, 400))
    eA = f1 * ea + (1 - f1) * eb                 # parallel laminate, a-fraction f1
    eB = 1 / (f2 / ea + (1 - f2) / eb)           # series laminate, a-fraction f2
    eff = 1 / (t / eA + (1 - t) / eB)
    f = t * f1 + (1 - t) * f2
    region = bergman_milton_bounds(ea, eb, f, kind="wiener", n_points=801)
    assert np.all(region.contains(eff))


def test_isotropic_media_in_hs_region_and_hs_region_in_wiener_region():
    rng = np.random.default_rng(22)
    ea, eb, f = random_eps(rng, 200), random_eps(rng, 200), rng.uniform(0.01, 0.99, 200)
    hs = bergman_milton_bounds(ea, eb, f, n_points=801)
    wi = bergman_milton_bounds(ea, eb, f, kind="wiener", n_points=801)
    assert np.all(hs.contains(maxwell_garnett(ea, eb, f)))
    assert np.all(wi.contains(hs.arc_1[:, ::40].T).T) and np.all(wi.contains(hs.arc_2[:, ::40].T).T)
    # aligned ellipsoids are anisotropic: outside the HS region in general, inside Wiener's
    al = maxwell_garnett_ellipsoid(ea, eb, f, [0.05, 0.05, 0.9], orientation="aligned")
    assert np.all(wi.contains(al[:, 0]))


def test_looyenga_matches_pyelli_and_limits(gold_silica):
    elli = pytest.importorskip("elli")
    w, _, _, ea, es = gold_silica
    host = elli.IsotropicMaterial(elli.TableEpsilon(lbda=w, epsilon=es))
    guest = elli.IsotropicMaterial(elli.TableEpsilon(lbda=w, epsilon=ea))
    for f in (0.01, 0.3, 0.7):
        ref = elli.LooyengaEMA(host, guest, f).get_tensor(w)[:, 0, 0]
        np.testing.assert_allclose(looyenga(ea, es, f), ref, rtol=1e-10)
    np.testing.assert_allclose(looyenga(ea, es, 0.0), es, rtol=1e-12)
    np.testing.assert_allclose(looyenga(ea, es, 1.0), ea, rtol=1e-12)
    assert np.all(looyenga(ea, es, 0.4).imag >= 0)


def test_bounds_bad_input():
    with pytest.raises(InvalidInputError, match="sum to 1"):
        wiener_bounds([1.0, 2.0], [0.2, 0.2])
    with pytest.raises(InvalidInputError, match="kind"):
        bergman_milton_bounds(1.0, 2.0, 0.5, kind="tight")
    with pytest.raises(InvalidInputError, match="two phases"):
        hashin_shtrikman_bounds([1.0 + 1j, 2.0, 3.0], [0.2, 0.3, 0.5])
