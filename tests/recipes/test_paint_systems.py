"""Recipes of real paint systems (issue 16): [[pigments]], [[coats]], [substrate], [measurement],
the formulator's numbers in scalars/summary, and errors naming the key path."""

import pytest

from nmmm.errors import RecipeError
from nmmm.recipes.run import compute
from nmmm.recipes.schema import example_path, load_recipe, read_toml, parse_recipe


def test_three_coat_stack_runs_and_reports_hiding():
    res = compute(load_recipe(example_path("three_coat_solid")), progress=False)
    assert res.summary["geometry"] == "di:8"
    assert 0 < res.scalars["contrast_ratio"] <= 1
    assert res.scalars["hiding_thickness_um"] > 1.0
    assert res.summary["masstone_lab"][1] > 5  # a red masstone
    assert any(k.startswith("over white") for k in res.spectra) and any(k.startswith("over black") for k in res.spectra)


def test_tint_runs_with_two_pigments():
    res = compute(load_recipe(example_path("hematite_tint")), progress=False)
    assert res.scalars["a_D65"] > 5 and res.scalars["L_D65"] > 30  # a pink-red tint, lighter than the masstone
    assert "contrast_ratio" in res.summary


def _raw(name):
    return read_toml(example_path(name))[0]


def test_errors_name_the_key_path():
    raw = _raw("hematite_tint")
    raw["pigments"][1]["fraction"] = 0.99
    with pytest.raises(RecipeError, match=r"^pigments: the fractions sum to 1.02"):
        parse_recipe(raw)
    raw = _raw("three_coat_solid")
    del raw["coats"][1]["thickness_nm"]
    with pytest.raises(RecipeError, match=r"coats\[1\]\.thickness_nm: required key is missing"):
        parse_recipe(raw)
    raw = _raw("three_coat_solid")
    raw["coats"][2]["pigments"][0]["compound"] = "rutil"
    with pytest.raises(RecipeError, match=r"coats\[2\]\.pigments\[0\]\.compound: unknown compound 'rutil'"):
        parse_recipe(raw)
    raw = _raw("three_coat_solid")
    raw["measurement"]["geometry"] = "45:45"
    with pytest.raises(RecipeError, match=r"measurement\.geometry"):
        parse_recipe(raw)
    raw = _raw("three_coat_solid")
    raw["substrate"] = {"reflectance": 1.3}
    with pytest.raises(RecipeError, match=r"substrate\.reflectance"):
        parse_recipe(raw)
    raw = _raw("three_coat_solid")
    raw["coats"][0]["thickness_nm"] = -5.0
    with pytest.raises(RecipeError, match=r"coats\[0\]\.thickness_nm: must be a finite number > 0"):
        parse_recipe(raw)
