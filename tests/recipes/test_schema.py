"""Recipe validation: every invalid recipe names the offending key."""

import pytest

from nmmm.errors import RecipeError
from nmmm.recipes.schema import example_recipes, get_key, load_recipe, parse_recipe, set_key
from nmmm.recipes.sweep import grid_points, parse_vary

from .conftest import fast_raw


def test_shipped_examples_validate():
    ex = example_recipes()
    assert {"gold_ruby_glass", "hematite_paint", "grey_metallic", "interference_pigment"} <= set(ex)
    macros = {name: load_recipe(p).macro for name, p in ex.items()}
    assert macros["gold_ruby_glass"] == "plate"
    assert macros["hematite_paint"] == "film"
    assert macros["grey_metallic"] == "effect"
    assert macros["interference_pigment"] == "thin_film"


def _err(raw) -> str:
    with pytest.raises(RecipeError) as ei:
        parse_recipe(raw)
    return str(ei.value)


@pytest.mark.parametrize(
    "key, value, expected",
    [
        ("pigment.fraction", 7, "pigment.fraction: must be in [0, 1]"),
        ("pigment.fraction", -0.1, "pigment.fraction: must be in [0, 1]"),
        ("pigment.fraction", float("nan"), "pigment.fraction: must be in [0, 1]"),
        ("film.thickness_nm", -5.0, "film.thickness_nm: must be a finite number > 0"),
        ("film.solver", "monte-carlo", "film.solver"),
        ("film.substrate_reflectance", 1.5, "film.substrate_reflectance: must be in [0, 1]"),
        ("pigment.compound", "haematite", "pigment.compound: unknown compound 'haematite' (did you mean 'hematite'?)"),
        ("binder.compound", "resin", "binder.compound: unknown compound 'resin'"),
        ("pigment.fractoin", 0.05, "pigment.fractoin: unknown key (did you mean 'fraction'?)"),
        ("compounds.epoxy.model", "cauchi", "compounds.epoxy: unknown dispersion model 'cauchi'"),
        ("lighting.illuminants", ["D66"], "lighting: illuminants[0]: unknown illuminant 'D66'"),
        ("spectral.stop_nm", 300.0, "spectral: stop_nm (300) must exceed start_nm"),
        ("spectral.start_nm", 200.0, "spectral: colours need a grid inside 360–830 nm"),
        ("pigment.size_spread", 0.5, "pigment.size_spread"),
        ("pigment.diameter_nm", 200.0, "pigment: a cube pigment is sized by edge_nm or body_diagonal_nm; got"),
        ("pigment.shape", "rod", "pigment: a rod pigment is sized by diameter_nm + length_nm"),
        # no silent coercion or unbounded values
        ("pigment.fraction", "0.05", "pigment.fraction: Input should be a valid number"),
        ("pigment.fraction", True, "pigment.fraction: Input should be a valid number"),
        ("film.thickness_nm", float("inf"), "film.thickness_nm: must be a finite number > 0; got inf"),
    ],
)
def test_invalid_values_name_the_key(key, value, expected):
    raw = set_key(fast_raw("hematite_paint"), key, value)
    assert expected in _err(raw)


def test_level_errors_name_the_level_key():
    raw = fast_raw("gold_ruby_glass")
    msg = _err(set_key(raw, "levels[0].inclusions[0].fraction", 1.5))
    assert msg.startswith("levels[0].inclusions[0].fraction: must be in [0, 1]")
    msg = _err(set_key(raw, "levels[0].host", "glass"))
    assert msg.startswith("levels[0].host: unknown compound 'glass'")
    msg = _err(set_key(raw, "levels[0].method", "magic"))
    assert msg.startswith("levels[0]: unknown homogenization method 'magic'")
    msg = _err(set_key(raw, "levels[0].inclusions[0].shape", "spheroid"))
    assert "levels[0].inclusions[0]: shape 'spheroid' needs aspect_ratio" in msg
    msg = _err(set_key(raw, "plate.compound", "ruby"))
    assert msg.startswith("plate.compound: unknown compound 'ruby'")


def test_image_keys_are_bounded():
    raw = fast_raw("grey_metallic")
    assert "image.pixels[0]: Input should be less than or equal to 4096" in _err(set_key(raw, "image.pixels", [10**5, 20]))
    assert "image.pixels[1]: Input should be greater than or equal to 1" in _err(set_key(raw, "image.pixels", [30, 0]))
    assert _err(set_key(raw, "image.light_position_cm", [0, 0, -10])).startswith(
        "image: light_position_cm must be finite and above the plate")


def test_compound_needs_exactly_one_source():
    raw = set_key(fast_raw("gold_ruby_glass"), "compounds.gold.n", 1.5)
    assert "compounds.gold: give exactly one of" in _err(raw)


def test_macro_object_required_and_unique():
    raw = fast_raw("hematite_paint")
    del raw["film"]
    assert "exactly one macro object" in _err(raw)
    raw = fast_raw("hematite_paint")
    raw["plate"] = {"compound": "epoxy"}
    assert "exactly one macro object" in _err(raw)
    raw = fast_raw("hematite_paint")
    del raw["pigment"]
    assert _err(raw).startswith("pigment: required key is missing")


def test_toml_syntax_and_missing_file(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text("[pigment]\nfraction = = 0.1\n")
    with pytest.raises(RecipeError, match="TOML syntax"):
        load_recipe(p)
    with pytest.raises(RecipeError, match="not found"):
        load_recipe(tmp_path / "missing.toml")


def test_bad_database_key_names_the_compound():
    from nmmm.recipes.run import build_materials

    r = parse_recipe(set_key(fast_raw("gold_ruby_glass"), "compounds.gold.database", "main/Au/Nobody"))
    with pytest.raises(RecipeError, match=r"^compounds\.gold: "):
        build_materials(r)


def test_bad_model_parameters_name_the_compound():
    from nmmm.recipes.run import build_materials

    raw = set_key(fast_raw("hematite_paint"), "compounds.epoxy.params.Z", 1.0)
    with pytest.raises(RecipeError, match=r"^compounds\.epoxy\.params: "):
        build_materials(parse_recipe(raw))


def test_dotted_keys_and_vary_specs():
    raw = fast_raw("interference_pigment")
    assert get_key(raw, "thin_film.layers[1].thickness_nm") == 120
    assert get_key(set_key(raw, "thin_film.layers.1.thickness_nm", 90), "thin_film.layers[1].thickness_nm") == 90
    assert get_key(raw, "thin_film.layers[1].thickness_nm") == 120  # set_key copies
    assert parse_vary("pigment.fraction=0.05:0.10:11")[1][:3] == [0.05, 0.055, 0.06]
    assert len(parse_vary("pigment.fraction=0.05:0.10:11")[1]) == 11
    assert parse_vary("pigment.diameter_nm=100,250,500") == ("pigment.diameter_nm", [100, 250, 500])
    assert len(grid_points(["a=1:2:3", "b=x,y"])) == 6
    for bad in ("pigment.fraction", "a=1:2", "a=1:2:x", "=3"):
        with pytest.raises(RecipeError):
            parse_vary(bad)
    with pytest.raises(RecipeError, match="no such key"):
        get_key(raw, "thin_film.layers[9].thickness_nm")
