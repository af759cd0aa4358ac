"""The fast paths of match_recipe (issue 17 Speed): the KM start's own KM algebra equals the coat-stack
KM solver, the cached CIELAB equals nmmm.colour.spectra_to_lab, the Broyden quasi-Newton finds a known
least-squares minimum, and the KM start and the centre start reach the same match."""

import warnings

import numpy as np
import pytest

from nmmm.matching import RecipeModel, match_recipe
from nmmm.matching.recipe_match import _forward_jacobian, _lab_function, _quasi_newton
from nmmm.recipes.schema import example_path, read_toml, set_key

FREE3 = ["pigments.0.fraction=0.005:0.08", "pigments.1.fraction=0.02:0.25", "pigments.2.fraction=0:0.02"]


def _three(geometry="de:8", clear_coat_nm=0.0):
    raw, _, _ = read_toml(example_path("hematite_tint"))
    raw = set_key(raw, "film.thickness_nm", 8000.0)
    raw = set_key(raw, "measurement.geometry", geometry)
    if clear_coat_nm:
        raw = set_key(raw, "film.clear_coat_nm", clear_coat_nm)
    raw["compounds"]["black"] = {"n": 1.9, "k": 0.6}
    raw["pigments"].append({"compound": "black", "fraction": 0.004, "diameter_nm": 60})
    return RecipeModel(raw, FREE3)


@pytest.mark.parametrize("geometry,clear", [("de:8", 0.0), ("di:8", 0.0), ("45a:0", 0.0), ("de:8", 20000.0)])
def test_km_path_is_the_coat_stack_km_solver(geometry, clear):
    from nmmm.layers.coat_stack import stack_reflectance

    m = _three(geometry, clear)
    assert m._km_terms is not None
    for x in ([0.021, 0.15, 0.006], [0.005, 0.02, 0.0], [0.08, 0.25, 0.02]):
        opts, stack = m.optics(np.array(x))
        ref = stack_reflectance(stack, m.wavelength_nm, "km", m.geometry, optics=opts).reflectance
        np.testing.assert_allclose(m.reflectance(np.array(x), "km"), ref, rtol=0, atol=1e-12)


@pytest.mark.parametrize("illuminant", ["D65", "A", "F11"])
def test_cached_lab_is_spectra_to_lab(illuminant):
    from nmmm.colour import spectra_to_lab

    w = np.arange(400.0, 701.0, 20.0)
    lab = _lab_function(w, illuminant, "2")
    rng = np.random.default_rng(3)
    for R in [*rng.uniform(0, 1, (20, w.size)), np.full(w.size, 0.001), np.ones(w.size)]:  # dark: CIE's linear branch
        np.testing.assert_allclose(lab(R), spectra_to_lab(w, R, illuminant), rtol=0, atol=1e-10)


def test_quasi_newton_finds_a_known_least_squares_minimum():
    """y = a exp(-b t) + c on [0,1]^3 (scaled), exact data: the minimum is the generating point, from a
    deliberately wrong starting Jacobian (half the true one) and from forward differences."""
    t = np.linspace(0, 3, 25)
    truth = np.array([0.3, 0.7, 0.2])

    def model(u):
        return (0.5 + u[0]) * np.exp(-(0.2 + 2 * u[1]) * t) + u[2]

    y = model(truth)
    calls = []

    def fun(u):
        calls.append(1)
        return model(u) - y

    u0 = np.array([0.6, 0.3, 0.5])
    J_wrong = 0.5 * _forward_jacobian(fun, u0, fun(u0))
    for J0 in (J_wrong, None):
        calls.clear()
        u, r = _quasi_newton(fun, u0, J0, stop_norm=1e-10)
        np.testing.assert_allclose(u, truth, atol=1e-8)
        assert np.linalg.norm(r) < 1e-10 and len(calls) <= 80


def test_quasi_newton_stops_at_a_bound_minimum():
    """The unconstrained minimum lies outside [0, 1]: the fit stops on the bound, residual not zero."""
    def fun(u):
        return np.array([u[0] - 1.5, 0.1 * (u[1] - 0.4)])

    u, r = _quasi_newton(fun, np.array([0.2, 0.9]), None, stop_norm=1e-12)
    np.testing.assert_allclose(u, [1.0, 0.4], atol=1e-9)
    assert np.linalg.norm(r) == pytest.approx(0.5, abs=1e-9)


def test_km_start_and_centre_start_reach_the_same_match():
    """The spectral 3-colourant match from the KM optimum (with the KM Jacobian) and from the box
    centre on adding-doubling alone: the same fractions. (Measured: 26 vs 25 adding-doubling
    evaluations spectral, 35 vs 37 colorimetric — the KM optimum lies elsewhere along the valley of the
    weakly identifiable total amount, so the KM start saves about the first Jacobian only.)"""
    m = _three()
    true = np.array([0.021, 0.15, 0.006])
    target = m.reflectance(true, "ad")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for km in (True, False):
            m.evaluations = {}
            res = match_recipe(m, target, mode="spectral", km_start=km)
            assert res.de00 < 0.01
            np.testing.assert_allclose([res.values[b.key] for b in m.bounds], true, rtol=0.01)
            assert ("km" in m.evaluations and m.evaluations["km"] > 0) == km


def test_quasi_newton_says_when_its_cap_ended_it():
    """report['capped']: True when the evaluation cap, not convergence, ended the fit (then match_recipe
    warns instead of reporting the point as the match); False at a converged or bound minimum."""
    t = np.linspace(0, 3, 25)

    def fun(u):
        return (0.5 + u[0]) * np.exp(-(0.2 + 2 * u[1]) * t) + u[2] - (0.8 * np.exp(-1.6 * t) + 0.2)

    for cap, capped in ((4, True), (None, False)):
        how = {}
        _quasi_newton(fun, np.array([0.6, 0.3, 0.5]), None, stop_norm=1e-10, max_evals=cap, report=how)
        assert how["capped"] is capped
    how = {}
    _quasi_newton(lambda u: np.array([u[0] - 1.5, 0.1 * (u[1] - 0.4)]), np.array([0.2, 0.9]), None, 1e-12, report=how)
    assert how["capped"] is False


def test_match_stopped_by_the_cap_is_warned(monkeypatch):
    """A finish the cap ended above ΔE00 0.3 (refine_above_de00) is warned, not reported as the match
    silently (a noisy colorimetric target's finish also meets the cap, at ΔE00 ~0.0005: not warned)."""
    import nmmm.matching.recipe_match as rm
    from nmmm.matching import RecipeModel, match_recipe
    from nmmm.recipes.schema import example_path

    m = RecipeModel(example_path("hematite_tint"), ["pigments.0.fraction=0.005:0.08", "pigments.1.fraction=0.02:0.25"])
    target = m.reflectance(np.array([0.021, 0.15]), "ad")
    monkeypatch.setattr(rm, "_FINISH_MAX_EVALS", 2)
    with pytest.warns(UserWarning, match="stopped at its cap of 2 evaluations before converging"):
        res = match_recipe(m, target, mode="spectral", km_start=False)  # (with the KM start, the centre finish rescues it)
    assert any("cap of 2" in w for w in res.warnings)


def test_a_result_counts_its_own_evaluations():
    """MatchResult.evaluations are the match's own: a second match on the same model does not report
    the first one's too (the model counts over its life)."""
    m = RecipeModel(example_path("hematite_tint"), ["pigments.0.fraction=0.005:0.08"])
    target = m.reflectance(np.array([0.021]), "ad")
    first = match_recipe(m, target, mode="spectral").evaluations
    second = match_recipe(m, target, mode="spectral").evaluations
    assert second == first and sum(m.evaluations.values()) >= sum(first.values()) + sum(second.values())
