"""Matching a recipe to a target made by the forward model at known values (issue 17 item 3)."""

import warnings

import numpy as np
import pytest

from nmmm.errors import InvalidInputError, RecipeError
from nmmm.matching import RecipeModel, match_recipe, parse_bound
from nmmm.recipes.schema import example_path, read_toml, set_key

FREE = ["pigments.0.fraction=0.005:0.08", "pigments.1.fraction=0.02:0.25"]
TRUE = np.array([0.021, 0.15])


@pytest.fixture(scope="module")
def thin_tint():
    """The shipped hematite tint at 8 µm over white: hiding incomplete, so both fractions show."""
    raw, _, _ = read_toml(example_path("hematite_tint"))
    return RecipeModel(set_key(raw, "film.thickness_nm", 8000.0), FREE)


def test_linear_path_is_the_mixture_optics(thin_tint):
    from nmmm.layers.coat_stack import coat_optics

    assert thin_tint._linear is not None
    opts, stack = thin_tint.optics(TRUE)
    rec_raw = thin_tint.matched_raw_exact(TRUE)
    from nmmm.recipes.paint_stack import recipe_stack
    from nmmm.recipes.schema import parse_recipe

    st = recipe_stack(parse_recipe(rec_raw), thin_tint.mats, thin_tint.wavelength_nm)
    full = coat_optics(st.coats[-1], thin_tint.wavelength_nm)
    np.testing.assert_allclose(opts[-1].mu_a_per_nm, full.mu_a_per_nm, rtol=1e-10)
    np.testing.assert_allclose(opts[-1].mu_s_per_nm, full.mu_s_per_nm, rtol=1e-10)
    np.testing.assert_allclose(opts[-1].phase_moments, full.phase_moments, atol=1e-10)


@pytest.mark.parametrize("mode", ["colorimetric", "spectral"])
def test_recovers_known_fractions(thin_tint, mode):
    target = thin_tint.reflectance(TRUE, "ad")
    res = match_recipe(thin_tint, target, mode=mode)
    assert res.de00 < 0.01
    got = np.array([res.values[k.split("=")[0]] for k in FREE])
    np.testing.assert_allclose(got, TRUE, rtol=0.01)  # 1 % of each fraction
    assert all(v < 0.01 for v in res.metamerism.values())
    assert set(res.metamerism) == {"A", "FL11"}
    assert res.evaluations["ad"] > 0 and res.evaluations["km"] > 0
    # identifiable: the standard error at noise 0.002 is below the fraction itself
    assert res.standard_errors["pigments.0.fraction"] < TRUE[0]


def test_noisy_target_still_matches_colour(thin_tint):
    target = thin_tint.reflectance(TRUE, "ad") + np.random.default_rng(7).normal(0, 0.002, thin_tint.wavelength_nm.size)
    res = match_recipe(thin_tint, np.clip(target, 0, 1))
    assert res.de00 <= 0.5


def test_matched_recipe_runs_to_the_same_spectrum(thin_tint):
    from nmmm.recipes.run import compute
    from nmmm.recipes.schema import parse_recipe

    res = match_recipe(thin_tint, thin_tint.reflectance(TRUE, "ad"))
    run = compute(parse_recipe(res.recipe_raw), progress=False)
    np.testing.assert_allclose(run.spectra[run.primary], res.reflectance, atol=2e-4)


def test_cielab_target(thin_tint):
    from nmmm.colour import spectra_to_lab

    lab = spectra_to_lab(thin_tint.wavelength_nm, thin_tint.reflectance(TRUE, "ad"))
    res = match_recipe(thin_tint, target_lab=lab)
    assert res.de00 < 0.01
    assert res.metamerism == {}


def test_unreachable_target_warns_with_the_missing_direction(thin_tint):
    from nmmm.colour import spectra_to_lab

    lab = spectra_to_lab(thin_tint.wavelength_nm, thin_tint.reflectance(TRUE, "ad")) + np.array([0, -40.0, -40.0])
    with pytest.warns(UserWarning, match="cannot reach it"):
        res = match_recipe(thin_tint, target_lab=lab)
    assert res.de00 > 1 and res.warnings


def test_cannot_reach_names_the_hue_direction_in_words():
    """The 'cannot reach' warning's hue: the CIE hue angle difference h_ab(match) - h_ab(target),
    computed here from atan2 by hand, and the hue the match has turned towards."""
    from nmmm.matching.recipe_match import _hue_words, _missing_words

    def lab(L, C, h):
        return np.array([L, C * np.cos(np.radians(h)), C * np.sin(np.radians(h))])

    assert _hue_words(lab(40, 30, 30), lab(40, 30, 50)) == "too yellow: Δh° +20.0"  # a red turned yellower
    assert _hue_words(lab(40, 30, 30), lab(40, 30, 15)) == "too red: Δh° -15.0"
    assert _hue_words(lab(60, 30, 135), lab(60, 30, 115)) == "too yellow: Δh° -20.0"  # a green turned yellower
    assert _hue_words(lab(60, 30, 135), lab(60, 30, 160)) == "too green: Δh° +25.0"
    assert _hue_words(lab(50, 20, 350), lab(50, 20, 10)) == "too red: Δh° +20.0"  # across 0°
    assert _hue_words(lab(50, 20, 250), lab(50, 20, 200)) == "too green: Δh° -50.0"
    assert _hue_words(lab(50, 20, 230), lab(50, 20, 39)) == "too red: Δh° +169.0"  # past blue to red
    assert _hue_words(lab(50, 1, 250), lab(50, 20, 200)) is None  # a near-neutral target has no hue angle
    words = _missing_words(np.array([0.0, 0.0, 10.4]), lab(40, 30, 30), lab(40, 30, 50))
    assert words.startswith("too yellow: Δh° +20.0 (ΔH* +10.40)")


def test_bad_inputs(thin_tint):
    raw, _, _ = read_toml(example_path("hematite_tint"))
    with pytest.raises(RecipeError, match="no such key"):
        RecipeModel(raw, ["pigments.5.fraction=0:0.1"])
    with pytest.raises(RecipeError, match="not a number"):
        RecipeModel(raw, ["pigments.0.compound=0:1"])
    with pytest.raises(RecipeError, match="LO must be below HI"):
        parse_bound("pigments.0.fraction=0.2:0.1")
    with pytest.raises(RecipeError, match="fraction lies in"):
        parse_bound("pigments.0.fraction=0:2")
    with pytest.raises(RecipeError, match="KEY=LO:HI"):
        parse_bound("pigments.0.fraction")
    target = thin_tint.reflectance(TRUE, "ad")
    with pytest.raises(InvalidInputError, match="percent"):
        match_recipe(thin_tint, target * 100)
    with pytest.raises(InvalidInputError, match="spectral match needs a target spectrum"):
        match_recipe(thin_tint, target_lab=[50, 10, 10], mode="spectral")


def test_bounds_are_checked_up_front_with_the_values_typed():
    """A bound the recipe refuses is named, with the value the user typed, before any fit (before,
    a negative thickness LO surfaced later at a value the optimiser had chosen)."""
    raw, _, _ = read_toml(example_path("hematite_tint"))
    with pytest.raises(RecipeError, match=r"film.thickness_nm=-500:16000: LO = -500 is not a valid value"):
        RecipeModel(raw, ["film.thickness_nm=-500:16000"])
    with pytest.raises(RecipeError, match=r"pigments.0.diameter_nm=-5:300: LO = -5 is not a valid value.*> 0"):
        RecipeModel(raw, ["pigments.0.diameter_nm=-5:300"])


def test_other_keys_take_the_recipe_path():
    raw, _, _ = read_toml(example_path("hematite_tint"))
    m = RecipeModel(set_key(raw, "film.thickness_nm", 8000.0), ["film.thickness_nm=4000:16000"])
    assert m._linear is None
    target = m.reflectance([10000.0], "ad")
    res = match_recipe(m, target, mode="spectral")
    assert res.values["film.thickness_nm"] == pytest.approx(10000.0, rel=0.01)
    assert res.de00 < 0.01


def test_three_colourants():
    """Hematite, rutile and a black (n 1.9 + 0.6i, 60 nm) at 8 µm over white."""
    raw, _, _ = read_toml(example_path("hematite_tint"))
    raw = set_key(raw, "film.thickness_nm", 8000.0)
    raw["compounds"]["black"] = {"n": 1.9, "k": 0.6}
    raw["pigments"].append({"compound": "black", "fraction": 0.004, "diameter_nm": 60})
    m = RecipeModel(raw, FREE + ["pigments.2.fraction=0:0.02"])
    true = np.array([0.021, 0.15, 0.006])
    target = m.reflectance(true, "ad")
    spectral = match_recipe(m, target, mode="spectral")
    got = np.array(list(spectral.values.values()))
    np.testing.assert_allclose(got, true, rtol=0.05)
    assert spectral.de00 < 0.01
    colorimetric = match_recipe(m, target)
    assert colorimetric.de00 < 0.01
    # the scale of three fractions is weakly identifiable at noise 0.002: the reported errors say so
    assert colorimetric.standard_errors["pigments.1.fraction"] > 0.05


def test_metamerism_penalty_runs_and_keeps_the_match(thin_tint):
    res = match_recipe(thin_tint, thin_tint.reflectance(TRUE, "ad"), metamerism_weight=1.0, test_illuminants=("A", "TL84"))
    assert res.de00 < 0.01 and max(res.metamerism.values()) < 0.01
    assert set(res.metamerism) == {"A", "FL11"}
