"""Bruggeman: limits, symmetry, root selection, n phases, agreement with MG and pyElli."""

import numpy as np
import pytest

from nmmm.ema import bergman_milton_bounds, bruggeman, bruggeman_residual, maxwell_garnett
from nmmm.errors import InvalidInputError

from .conftest import random_eps


def test_limits():
    rng = np.random.default_rng(10)
    ea, eb = random_eps(rng, 40), random_eps(rng, 40)
    np.testing.assert_allclose(bruggeman(ea, eb, 0.0), eb, rtol=1e-10)
    np.testing.assert_allclose(bruggeman(ea, eb, 1.0), ea, rtol=1e-10)
    np.testing.assert_allclose(bruggeman(ea, ea, rng.uniform(0, 1, 40)), ea, rtol=1e-10)


def test_symmetric_under_phase_exchange():
    rng = np.random.default_rng(11)
    ea, eb, f = random_eps(rng, 500), random_eps(rng, 500), rng.uniform(0, 1, 500)
    np.testing.assert_allclose(bruggeman(ea, eb, f), bruggeman(eb, ea, 1 - f), rtol=1e-9)
    np.testing.assert_allclose(bruggeman([ea, eb], [f, 1 - f]), bruggeman([eb, ea], [1 - f, f]), rtol=1e-9)


def test_closed_form_real_phases():
    """Two real phases: the positive root of 2ε² − bε − ε_a ε_b = 0,
    b = (3f − 1) ε_a + (2 − 3f) ε_b (Bruggeman 1935), between the phases."""
    ea, eb = 12.0, 1.7
    f = np.linspace(0, 1, 101)
    b = (3 * f - 1) * ea + (2 - 3 * f) * eb
    ref = (b + np.sqrt(b * b + 8 * ea * eb)) / 4
    out = bruggeman(ea, eb, f)
    np.testing.assert_allclose(out.real, ref, rtol=1e-12)
    assert np.all(out.imag == 0)


def test_agrees_with_maxwell_garnett_to_first_order_in_p():
    """Both are eps_m (1 + 3 p beta + ...), beta = (eps_i - eps_m)/(eps_i + 2 eps_m); they differ at
    O(p²) by eps_m 6 beta³ p². Series by hand: MG = eps_m (1 + 2 p beta)/(1 - p beta)
    = eps_m (1 + 3 p beta + 3 p² beta² + ...); inserting u = 1 + a p + b p² into Bruggeman's
    p (r - u)/(r + 2u) + (1 - p)(1 - u)/(1 + 2u) = 0 (r = eps_i/eps_m) gives a = 3 beta,
    b = 3 beta² + 6 beta³."""
    rng = np.random.default_rng(12)
    ea, eb = random_eps(rng, 100), random_eps(rng, 100)
    beta = (ea - eb) / (ea + 2 * eb)
    p = np.array([1e-3, 1e-4])[:, None]
    d = (bruggeman(ea, eb, p) - maxwell_garnett(ea, eb, p)) / eb
    assert np.all(np.abs(d) / (3 * np.abs(beta) * p) < 30 * p)  # equal at first order
    rel = np.abs(d / (6 * beta**3 * p**2) - 1)  # the O(p²) difference, to O(p)
    assert np.all(rel[0] < 0.05) and np.all(rel[1] < 0.005)


def test_exactly_one_root_in_the_upper_half_plane_and_residual():
    """The premise of the root choice (Milton 1981): for lossy phases one root of the Bruggeman
    polynomial has Im > 0; the returned one satisfies the equation."""
    rng = np.random.default_rng(13)
    for n in (2, 3, 4):
        eps = [random_eps(rng, 2000) for _ in range(n)]
        fr = list(rng.dirichlet(np.ones(n), 2000).T)
        out = bruggeman(eps, fr)
        assert np.all(out.imag > 0)
        res = bruggeman_residual(out, eps, fr)
        assert np.max(np.abs(res)) < 1e-9
        # numpy's own root finder on the same polynomial, one root at a time (independent)
        from numpy.polynomial import polynomial as P

        for s in range(0, 2000, 200):
            poly = np.zeros(1, complex)
            for i in range(n):
                term = np.array([fr[i][s] * eps[i][s], -fr[i][s]])
                for j in range(n):
                    if j != i:
                        term = P.polymul(term, [eps[j][s], 2])
                poly = P.polyadd(poly, term)
            roots = P.polyroots(poly)
            assert np.sum(roots.imag > 1e-9 * np.abs(roots)) == 1
            np.testing.assert_allclose(out[s], roots[np.argmax(roots.imag)], rtol=1e-8)


def test_inside_hashin_shtrikman_region():
    """Bruggeman describes a realizable isotropic composite, so it must lie in the
    Bergman–Milton (complex Hashin–Shtrikman) region."""
    rng = np.random.default_rng(14)
    ea, eb, f = random_eps(rng, 300), random_eps(rng, 300), rng.uniform(0.01, 0.99, 300)
    region = bergman_milton_bounds(ea, eb, f, kind="hashin_shtrikman", n_points=801)
    assert np.all(region.contains(bruggeman(ea, eb, f), rtol=1e-6))


def _drude_silver_like(w):
    """ε = 1 − ωp²/(ω² + iγω), ħωp = 9 eV, ħγ = 0.07 eV (an analytic, causal metal)."""
    E = 1239.841984 / w
    return 1 - 9.0**2 / (E**2 + 1j * 0.07 * E)


def test_root_continuous_in_wavelength_where_the_textbook_root_fails():
    """A Drude metal in glass over 200–2000 nm: the chosen root is passive, smooth in wavelength
    and solves the equation, whereas the textbook '+ sqrt' (principal branch) root of the
    quadratic lands on the gain branch (Im ε < 0) over much of the range."""
    w = np.arange(200.0, 2001.0, 1.0)
    em = _drude_silver_like(w)
    for f in (0.1, 0.2, 0.33, 0.5, 0.7):
        out = bruggeman(em, 2.25, f)
        assert np.all(out.imag >= 0)
        assert np.max(np.abs(np.diff(out)) / np.abs(out[1:])) < 0.1  # a branch jump is O(1)
        assert np.max(np.abs(bruggeman_residual(out, [em, 2.25], [f, 1 - f]))) < 1e-10
        b = (3 * f - 1) * em + (2 - 3 * f) * 2.25
        naive = (b + np.sqrt(b * b + 8 * em * 2.25)) / 4
        if f != 0.33:
            assert np.sum(naive.imag < 0) > 100


def test_pyelli_bruggeman_agrees_on_drude_metal():
    elli = pytest.importorskip("elli")
    w = np.arange(200.0, 2001.0, 1.0)
    em = _drude_silver_like(w)
    host = elli.IsotropicMaterial(elli.TableEpsilon(lbda=w, epsilon=np.full(w.size, 2.25 + 0j)))
    guest = elli.IsotropicMaterial(elli.TableEpsilon(lbda=w, epsilon=em))
    for f in (0.1, 0.5, 0.7):
        ref = elli.BruggemanEMA(host, guest, f).get_tensor(w)[:, 0, 0]
        np.testing.assert_allclose(bruggeman(em, 2.25, f), ref, rtol=1e-9)


def test_continuous_in_wavelength_with_gold(gold_silica):
    w, _, _, ea, es = gold_silica
    for f in (0.2, 0.33, 0.4, 0.6):
        out = bruggeman(ea, es, f)
        assert np.all(out.imag >= 0)
        assert np.max(np.abs(np.diff(out)) / np.abs(out[1:])) < 0.05


def test_pyelli_bruggeman_agrees(gold_silica):
    elli = pytest.importorskip("elli")
    w, _, _, ea, es = gold_silica
    host = elli.IsotropicMaterial(elli.TableEpsilon(lbda=w, epsilon=es))
    guest = elli.IsotropicMaterial(elli.TableEpsilon(lbda=w, epsilon=ea))
    for f in (0.0005, 0.1, 0.33, 0.5, 0.9):
        ref = elli.BruggemanEMA(host, guest, f).get_tensor(w)[:, 0, 0]
        np.testing.assert_allclose(bruggeman(ea, es, f), ref, rtol=1e-9)


def test_three_phases_with_a_repeated_phase_is_two_phase():
    rng = np.random.default_rng(15)
    ea, eb = random_eps(rng, 100), random_eps(rng, 100)
    f = rng.uniform(0, 1, 100)
    three = bruggeman([ea, ea, eb], [f / 2, f / 2, 1 - f])
    np.testing.assert_allclose(three, bruggeman(ea, eb, f), rtol=1e-8)


def test_lossless_metal_limiting_absorption():
    """Real negative metal ε with a dielectric: the result is the Im >= 0 root, equal to the
    limit of a slightly lossy metal."""
    f = np.linspace(0, 1, 201)
    lossless = bruggeman(-10.0 + 0j, 2.25, f)
    lossy = bruggeman(-10.0 + 1e-6j, 2.25, f)
    assert np.all(lossless.imag >= 0)
    np.testing.assert_allclose(lossless, lossy, atol=1e-4)


def test_broadcast_and_bad_input(gold_silica):
    w, _, _, ea, es = gold_silica
    out = bruggeman(ea[:401, None], es[:401, None], np.linspace(0, 1, 1000))
    assert out.shape == (401, 1000) and np.all(out.imag >= 0)
    with pytest.raises(InvalidInputError, match="sum to 1"):
        bruggeman([1.0, 2.0], [0.3, 0.3])
    with pytest.raises(InvalidInputError, match="one fraction per phase"):
        bruggeman([1.0, 2.0], [1.0])
    with pytest.raises(InvalidInputError):
        bruggeman(1.0, 2.0, 1.5)
    with pytest.raises(InvalidInputError):
        bruggeman([1.0, np.nan], [0.5, 0.5])


def test_ellipsoidal_grains_one_upper_root_and_dilute_limit():
    """Polder–van Santen (random ellipsoids): passive root solving the equation; dilute limit
    eps_m (1 + p <alpha>) as Maxwell Garnett (Bohren & Huffman §8.5)."""
    from nmmm.ema import Shape, maxwell_garnett_ellipsoid, spheroid_depolarization

    rng = np.random.default_rng(16)
    ea, eb, f = random_eps(rng, 1000), random_eps(rng, 1000), rng.uniform(0, 1, 1000)
    for shapes in ([Shape.spheroid(4.0), None], [Shape.spheroid(0.1), Shape.spheroid(3.0)],
                   [Shape((0.0, 0.0, 1.0)), None], [Shape.cube(), None]):
        out = bruggeman(ea, eb, f, shapes=shapes)
        assert np.all(out.imag >= 0)
        assert np.max(np.abs(bruggeman_residual(out, [ea, eb], [f, 1 - f], shapes=shapes))) < 1e-9
    ei, em, p = -12 + 1.0j, 2.1, 1e-6
    L = spheroid_depolarization(4.0)
    np.testing.assert_allclose(bruggeman(ei, em, p, shapes=[Shape.spheroid(4.0), None]),
                               maxwell_garnett_ellipsoid(ei, em, p, L), rtol=1e-10)
    np.testing.assert_allclose(bruggeman(ea, eb, f, shapes=[Shape.sphere(), None]), bruggeman(ea, eb, f), rtol=1e-9)
    with pytest.raises(InvalidInputError, match="random"):
        bruggeman(ea, eb, f, shapes=[Shape.spheroid(2.0, orientation="aligned"), None])


def _general(ea, eb, p):
    """The n-phase Aberth/Newton root finder, bypassing the two-sphere closed form."""
    from nmmm.ema.bruggeman_rule import _bruggeman_general, _groups, _phases

    e, f = _phases([ea, eb], [p, 1 - np.asarray(p, float)])
    return _bruggeman_general(e, f, *_groups(2, None))


def test_two_sphere_fast_path_agrees_with_the_general_solver():
    """Two different algorithms (closed-form quadratic vs. Aberth–Ehrlich + Newton on the
    regularised polynomial) with the same limiting-absorption rule: random lossy phases,
    metals (ε = −50 + 1i, −10 + 0.3i, lossless −5), lossless dielectrics, p over all of [0, 1]."""
    from nmmm.ema.bruggeman_rule import _bruggeman_two_spheres

    rng = np.random.default_rng(16)
    n = 4000
    ea, eb = random_eps(rng, n), random_eps(rng, n)
    metals = np.array([-50 + 1j, -10 + 0.3j, -5 + 0j, -2 + 0.01j, -120 + 8j])
    dielectrics = np.array([1.0 + 0j, 2.25 + 0j, 12.0 + 0j, 2.0 + 0.5j])
    ea[: n // 2] = rng.choice(metals, n // 2)
    eb[: n // 4] = rng.choice(dielectrics, n // 4)
    eb[n // 4 : n // 2] = rng.choice(np.r_[metals, dielectrics], n // 4)
    ea[-200:] = rng.choice(dielectrics.real, 200) + 0j
    eb[-200:] = rng.uniform(1, 20, 200) + 0j
    p = rng.uniform(0, 1, n)
    p[:: 10] = rng.choice([0.0, 1 / 3, 0.5, 2 / 3, 1.0], p[:: 10].size)
    fast = _bruggeman_two_spheres(ea, eb, p)
    slow = _general(ea, eb, p)
    np.testing.assert_allclose(fast, slow, rtol=1e-10, atol=1e-12)
    out = bruggeman(ea, eb, p)  # the public call takes the fast path
    np.testing.assert_array_equal(out, np.where(fast.imag < 0, fast.real + 0j, fast))
    assert np.all(out.imag >= 0)
    assert np.max(np.abs(bruggeman_residual(out, [ea, eb], [p, 1 - p]))) < 1e-10


def test_two_sphere_fast_path_where_the_principal_root_is_wrong():
    """ε₁ = −50 + 1i in ε₂ = 2.25 at p = 0.2: the principal-sqrt formula
    (b + sqrt(b² + 8ε₁ε₂))/4 gives a gain root (Im < 0); the fast path returns the other,
    passive root, which is also the general solver's."""
    from nmmm.ema.bruggeman_rule import _bruggeman_two_spheres

    e1, e2 = np.full(3, -50 + 1j), np.full(3, 2.25 + 0j)
    p = np.array([0.1, 0.2, 0.5])
    b = (3 * p - 1) * e1 + (2 - 3 * p) * e2
    naive = (b + np.sqrt(b * b + 8 * e1 * e2)) / 4
    other = -e1 * e2 / (2 * naive)  # product of the roots is −ε₁ε₂/2
    assert np.all(naive.imag < 0) and np.all(other.imag > 0)
    fast = _bruggeman_two_spheres(e1, e2, p)
    np.testing.assert_allclose(fast, other, rtol=1e-12)
    np.testing.assert_allclose(fast, _general(e1, e2, p), rtol=1e-10)


def test_two_sphere_closed_form_against_a_50_digit_reference():
    """Independent reference (mpmath, 50 digits): both roots of 2ε² − bε − ε₁ε₂ = 0 with every
    phase given the loss i·1e-30 (limiting absorption taken literally), the one with the larger
    Im kept. Cases: random lossy phases, metals in dielectrics, lossless dielectrics and
    lossless metals (ties broken only by the perturbation), and a root of 1e-6 beside one of
    −0.35 (b and the square root cancel to 6 digits: formed from the product of the roots)."""
    mp = pytest.importorskip("mpmath")
    from nmmm.ema.bruggeman_rule import _bruggeman_two_spheres

    mp.mp.dps = 50
    rng = np.random.default_rng(23)
    ea, eb = random_eps(rng, 120), random_eps(rng, 120)
    p = rng.uniform(0, 1, 120)
    cases = list(zip(ea, eb, p))
    cases += [(m, d, f) for m in (-50 + 1j, -44 + 13j, -5 + 0j, -0.5 + 0j) for d in (2.25, 1.0 + 0j, 12.0)
              for f in (0.0, 0.1, 1 / 3, 0.5, 0.9, 1.0)]
    cases += [(a, b, f) for a in (1.0, 4.0, 16.0) for b in (2.25, 9.0) for f in (0.05, 0.5, 0.95)]
    cases += [(1e-6 + 0j, 1.0 + 0j, 0.9), (1e-6 + 1e-9j, 1.0 + 0j, 0.9)]
    e1 = np.array([c[0] for c in cases], complex)
    e2 = np.array([c[1] for c in cases], complex)
    f = np.array([c[2] for c in cases], float)
    out = _bruggeman_two_spheres(e1, e2, f)
    tiny = mp.mpc(0, mp.mpf("1e-30"))
    for k, (a, b, q) in enumerate(zip(e1, e2, f)):
        a, b, q = mp.mpc(a.real, a.imag) + tiny, mp.mpc(b.real, b.imag) + tiny, mp.mpf(float(q))
        bb = (3 * q - 1) * a + (2 - 3 * q) * b
        s = mp.sqrt(bb * bb + 8 * a * b)
        ref = max(((bb + s) / 4, (bb - s) / 4), key=lambda r: r.imag)
        ref = complex(ref)
        assert abs(out[k] - ref) <= 1e-13 * abs(ref) + 1e-300, (cases[k], out[k], ref)
    assert np.all(out.imag >= 0)
