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
    with pytest.raises(RecipeError, match=r"substrate\.reflectance: .*must be in \[0, 1\].*got 1\.3"):
        parse_recipe(raw)
    raw["substrate"] = {"reflectance": [0.5, 1.2]}
    with pytest.raises(RecipeError, match=r"substrate\.reflectance: .*must be in \[0, 1\].*got 1\.2 \(item 1\)"):
        parse_recipe(raw)
    raw = _raw("three_coat_solid")
    raw["coats"][0]["thickness_nm"] = -5.0
    with pytest.raises(RecipeError, match=r"coats\[0\]\.thickness_nm: must be a finite number > 0"):
        parse_recipe(raw)


def test_bad_input_names_the_key_and_what_would_be_right():
    """The issue's "Bad input" cases not covered above, each a RecipeError naming the key."""
    from nmmm.recipes.run import compute

    # coat pigment fractions above 1
    raw = _raw("three_coat_solid")
    raw["coats"][2]["pigments"][0]["fraction"] = 0.999
    with pytest.raises(RecipeError, match=r"coats\[2\].*pigment fractions sum to 1.004 > 1"):
        parse_recipe(raw)
    # a negative fraction
    raw = _raw("hematite_tint")
    raw["pigments"][0]["fraction"] = -0.1
    with pytest.raises(RecipeError, match=r"pigments\[0\]\.fraction: must be in \[0, 1\]"):
        parse_recipe(raw)
    # a CPVC above the densest packing of equal spheres (pi/sqrt(18) = 0.7405): film and coat, refused when the
    # recipe is read (it was accepted up to 1 and refused only by compute)
    raw = _raw("hematite_tint")
    raw["film"]["cpvc"] = 0.9
    with pytest.raises(RecipeError, match=r"film\.cpvc: .*less than or equal to 0\.7404804"):
        parse_recipe(raw)
    raw["film"]["cpvc"] = 0.7404804896930611  # the limit itself is a packing
    assert parse_recipe(raw).film.cpvc == raw["film"]["cpvc"]
    raw = _raw("three_coat_solid")
    raw["coats"][1]["cpvc"] = 0.8
    with pytest.raises(RecipeError, match=r"coats\[1\]\.cpvc: .*less than or equal to 0\.7404804"):
        parse_recipe(raw)
    from nmmm.layers.pigment_mixture import MAX_PACKING, check_cpvc

    raw["coats"][1]["cpvc"] = MAX_PACKING  # the parse limit is the compute limit
    assert check_cpvc(parse_recipe(raw).coats[1].cpvc, "cpvc") == MAX_PACKING
    # a substrate reflectance outside [0, 1] in the film table
    raw = _raw("hematite_tint")
    raw["film"]["substrate_reflectance"] = -0.1
    with pytest.raises(RecipeError, match=r"film\.substrate_reflectance: must be in \[0, 1\]"):
        parse_recipe(raw)
    # a negative film thickness
    raw = _raw("hematite_tint")
    raw["film"]["thickness_nm"] = -1.0
    with pytest.raises(RecipeError, match=r"film\.thickness_nm: must be a finite number > 0"):
        parse_recipe(raw)
    # a geometry that does not exist: the known ones are named
    raw = _raw("hematite_tint")
    raw["measurement"]["geometry"] = "d/8"
    with pytest.raises(RecipeError, match=r"measurement\.geometry: .*'di:8'.*'0:45a'"):
        parse_recipe(raw)
    # a coat's binder with data only beyond part of the grid (rutile's DeVore data start at 430 nm)
    raw = _raw("three_coat_solid")
    raw["compounds"]["clear"] = {"database": "main/TiO2/Devore-o"}
    with pytest.raises(RecipeError, match=r"compounds\.clear: wavelengths 400–700 nm reach outside the data range .*"
                                          r"430–1530 nm"):
        compute(parse_recipe(raw), progress=False)


def test_cpvc_is_a_packing_fraction():
    import numpy as np

    from nmmm.errors import InvalidInputError
    from nmmm.layers.coat_stack import Coat
    from nmmm.layers.pigment_mixture import MAX_PACKING, check_cpvc, void_fraction

    assert abs(MAX_PACKING - 0.74048) < 1e-5  # Kepler's pi/sqrt(18)
    assert check_cpvc(0.55) == 0.55
    for bad in (0.0, -0.2, 0.75, 1.0, np.nan, "x"):
        with pytest.raises(InvalidInputError, match="cpvc"):
            check_cpvc(bad)
    with pytest.raises(InvalidInputError, match="cpvc"):
        void_fraction(0.5, 0.8)
    with pytest.raises(InvalidInputError, match=r"coat 'base': cpvc = 0.8"):
        Coat("base", 1e4, 1.5, cpvc=0.8)


def test_hematite_paint_runs_adding_doubling_and_its_multiangle_base_agrees():
    """The seed recipe uses the default solver (adding-doubling); the solid-paint BRDF of its multi-angle
    colours is built on the Lambertian body that reads the AD spectrum, so 45°:0° and 0°:d agree as for KM."""
    import numpy as np

    from nmmm.layers.kubelka_munk import saunderson, saunderson_k1, saunderson_k2
    from nmmm.layers.paint import body_reflectance_from_reading

    for name in ("hematite_paint", "hematite_paint_ethylcellulose"):  # the substitution compares like with like
        assert load_recipe(example_path(name)).film.solver == "ad"
    raw = _raw("hematite_paint")
    raw["spectral"]["step_nm"] = 40.0
    raw["pigment"]["size_nodes"] = 8
    res = compute(parse_recipe(raw), progress=False)
    L45 = next(r["L"] for r in res.multiangle if r["aspecular_deg"] == 45.0)
    assert abs(L45 - res.scalars["L_D65"]) < 1.0
    assert any("adding–doubling 0°/d spectrum" in n for n in res.notes)
    # the body inverts Saunderson's equation (round trip, both specular modes)
    rho = np.linspace(0.0, 0.95, 7)
    for sp in ("included", "excluded"):
        R = saunderson(rho, saunderson_k1(1.566), saunderson_k2(1.566), specular=sp)
        np.testing.assert_allclose(body_reflectance_from_reading(R, 1.566, sp), rho, atol=1e-12)
    # the measurement: KM + Saunderson reflects more than adding-doubling on this paint
    raw["film"]["solver"] = "km"
    km = compute(parse_recipe(raw), progress=False)
    assert km.scalars["L_D65"] > res.scalars["L_D65"] + 3


def test_km_recipe_warns_where_km_is_off():
    """A recipe that asks for Kubelka-Munk hears how far it is from adding-doubling (issue 24 item 5)."""
    import warnings

    from nmmm.layers.km_validity import KMAccuracyWarning
    from nmmm.recipes.run import compute

    raw = _raw("hematite_paint")
    raw["film"]["solver"] = "km"
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        res = compute(parse_recipe(raw), progress=False)
    km = [str(r.message) for r in rec if issubclass(r.category, KMAccuracyWarning)]
    assert len(km) == 1 and "use solver='ad'" in km[0]
    assert res.scalars["km_vs_ad_delta_e00"] > 1.0
    raw["film"].pop("solver")  # the default, adding-doubling, is not checked against itself
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        res = compute(parse_recipe(raw), progress=False)
    assert not [r for r in rec if issubclass(r.category, KMAccuracyWarning)]
    assert "km_vs_ad_delta_e00" not in res.scalars
