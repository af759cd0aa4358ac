"""[effect] by its composition (issue 18 items 2, 3, 6 and Bad input): one model for recipe and demo."""

import tomllib
import warnings

import numpy as np
import pytest

from nmmm.errors import RecipeError
from nmmm.recipes.run import compute
from nmmm.recipes.schema import example_path, parse_recipe, set_key

EFFECT_RECIPES = ("grey_metallic", "red_metallic", "fe2o3_mica_pearl")


def _raw(name, step_nm=20.0):
    raw = tomllib.loads(example_path(name).read_text())
    raw["spectral"]["step_nm"] = step_nm
    raw.pop("image", None)
    return raw


def _run(raw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return compute(parse_recipe(raw, base_dir=example_path("grey_metallic").parent), progress=False)


def test_grey_metallic_recipe_and_demo_paint_give_identical_multiangle_cielab():
    from nmmm.appearance.deposit import grey_metallic_from_deposit
    from nmmm.appearance.multiangle import multiangle_lab

    raw = _raw("grey_metallic")
    res = _run(raw)
    w = np.arange(380.0, 781.0, 20.0)
    g = [m["aspecular_deg"] for m in res.multiangle]
    paint, _ = grey_metallic_from_deposit(wavelength_nm=w)  # the demo's paint (nmmm.demo.appearance)
    ref = multiangle_lab(paint, w, g, illuminant="D65", observer=raw.get("lighting", {}).get("observer", "2"))
    lab = np.array([[m["L"], m["a"], m["b"]] for m in res.multiangle])
    np.testing.assert_allclose(lab, ref.lab, rtol=0, atol=1e-9)
    assert res.scalars["flake_optical_depth"] == pytest.approx(paint.flakes.optical_depth, rel=1e-12)


@pytest.mark.parametrize("name", EFFECT_RECIPES)
def test_shipped_effect_recipes_fall_in_lightness_and_flop_in_range(name):
    res = _run(_raw(name, step_nm=10.0))
    Ls = {m["aspecular_deg"]: m["L"] for m in res.multiangle}
    seq = [Ls[a] for a in (15.0, 25.0, 45.0, 75.0, 110.0) if a in Ls]
    assert len(seq) >= 4
    # flakes lying near the surface: L* falls from 15° to 110° aspecular (McCamy 1996; ASTM E2194)
    assert all(a > b for a, b in zip(seq, seq[1:])), seq
    fi = res.scalars["flop_index"]
    # Alman (1987) flop index of effect paints: silver metallics up to ~15-17; darker coloured effect paints
    # (low L*45) somewhat higher; a solid is ~0
    assert 5.0 < fi < 25.0, fi
    assert res.scalars["flake_optical_depth"] > 0.1


def test_coloured_recipes_are_coloured():
    red = {m["aspecular_deg"]: m for m in _run(_raw("red_metallic")).multiangle}
    assert red[45.0]["a"] > 8 and red[45.0]["b"] > 5  # iron-oxide red (brownish) away from the glint
    pearl = {m["aspecular_deg"]: m for m in _run(_raw("fe2o3_mica_pearl")).multiangle}
    assert pearl[15.0]["C"] > 30 and 30 < pearl[15.0]["h_deg"] < 70  # bronze: an orange hue near specular


def test_older_statistical_effect_keys_keep_working():
    from nmmm.appearance.brdf import metallic_paint
    from nmmm.appearance.multiangle import multiangle_lab

    raw = {"name": "old metallic", "spectral": {"step_nm": 20},
           "effect": {"flakes": "aluminium", "optical_depth": 1.5, "tilt_deg": 10.0, "body_reflectance": 0.2},
           "viewing": {"aspecular_deg": [15, 45, 110]}}
    res = _run(raw)
    w = np.arange(380.0, 781.0, 20.0)
    ref = multiangle_lab(metallic_paint(1.5, 10.0, body_reflectance=0.2), w, [15, 45, 110], illuminant="D65",
                         observer="2")
    np.testing.assert_allclose([[m["L"], m["a"], m["b"]] for m in res.multiangle], ref.lab, atol=1e-9)


def test_expert_override_of_the_derived_layer():
    raw = set_key(set_key(_raw("grey_metallic"), "effect.optical_depth", 1.2), "effect.tilt_deg", 9.0)
    res = _run(raw)
    assert res.scalars["flake_optical_depth"] == 1.2
    assert "expert override: optical_depth, tilt_deg" in " ".join(res.notes)


def test_volume_derivation_and_layered_flake_from_the_recipe():
    raw = set_key(_raw("fe2o3_mica_pearl"), "effect.derive", "volume")
    res = _run(raw)
    assert res.scalars["flake_optical_depth"] == pytest.approx(0.02 * 20e3 / 520.0, rel=1e-12)


# -- bad input -----------------------------------------------------------------------------


def _bad(raw, match):
    with pytest.raises(RecipeError, match=match):
        _run(raw)


def test_fraction_that_cannot_fit_at_the_orientation_spread():
    raw = set_key(set_key(_raw("grey_metallic"), "effect.flakes.fraction", 0.05), "effect.flakes.tilt_std_deg", 90.0)
    raw = set_key(raw, "effect.derive", "volume")
    _bad(raw, r"effect\.flakes\.fraction: 0\.05 of 20 µm × 300 nm flakes cannot fit the coat at a tilt spread of 90")


def test_flakes_thicker_than_the_coat():
    raw = set_key(set_key(_raw("grey_metallic"), "effect.flakes.thickness_nm", 25000), "effect.flakes.fraction", 0.001)
    _bad(raw, r"effect\.flakes\.thickness_nm: flakes 25000 nm thick do not fit in a basecoat 20000 nm thick")


def test_tilt_distribution_that_is_not_a_density():
    raw = set_key(_raw("grey_metallic"), "effect.flakes.tilt_density", {"tilt_deg": [0, 10, 20],
                                                                         "density_per_sr": [1.0, -0.2, 0.0]})
    raw = set_key(raw, "effect.derive", "volume")
    _bad(raw, r"effect\.flakes\.tilt_density: the tilt density is negative")


def test_layered_flake_with_an_unphysical_layer():
    raw = _raw("fe2o3_mica_pearl")
    raw["effect"]["flakes"]["layers"][0]["thickness_nm"] = 0.3
    _bad(raw, r"effect\.flakes\.layers\[0\]\.thickness_nm: 0\.3 nm is not a physical film")
    raw = _raw("fe2o3_mica_pearl")
    raw["effect"]["flakes"]["layers"][1]["compound"] = "micca"
    _bad(raw, r"effect\.flakes\.layers\[1\]\.compound: unknown compound 'micca' \(did you mean 'mica'\?\)")


def test_composition_keys_need_a_flakes_table():
    raw = {"effect": {"flakes": "aluminium", "coat_thickness_um": 20}}
    with pytest.raises(RecipeError, match=r"effect.*coat_thickness_um: describe the flakes as a \[effect\.flakes\] table"):
        parse_recipe(raw)
    raw = {"effect": {"flakes": {"material": "aluminium", "fraction": 0.01, "layers": [{"compound": "x",
                                                                                      "thickness_nm": 5}]}}}
    with pytest.raises(RecipeError, match="exactly one of 'material'"):
        parse_recipe(raw)


def test_demo_coloured_coats_are_the_recipes():
    """nmmm.demo.appearance builds the coloured metallic and pearl from the shipped recipes' EffectCoat: the demo's
    multi-angle CIELAB equals the recipe run's."""
    from nmmm.appearance.multiangle import multiangle_lab
    from nmmm.demo.appearance import _recipe_coat

    w = np.arange(380.0, 781.0, 20.0)
    for name in ("red_metallic", "fe2o3_mica_pearl"):
        res = _run(_raw(name))
        g = [m["aspecular_deg"] for m in res.multiangle]
        ref = multiangle_lab(_recipe_coat(name, w).brdf(w)[0], w, g, illuminant="D65", observer="10")
        np.testing.assert_allclose([[m["L"], m["a"], m["b"]] for m in res.multiangle], ref.lab, rtol=0, atol=1e-9)


def test_flake_face_roughness_and_rims_reach_the_brdf():
    """[effect.flakes] face_roughness (GGX α of the faces) and edge_width_nm (rim width w, f_e = 4 w / ⟨D⟩) are the
    FlakeLayer's surface_roughness and edge_fraction; both default to 0 (mirror flakes, the renderer's glints). Rough
    faces and rims lift the far side: L* falls more from 75° to 110° than with mirror flakes (review O)."""
    from nmmm.appearance.deposit import grey_metallic_coat
    from nmmm.recipes.effect_schema import build_effect_coat

    w = np.arange(380.0, 781.0, 20.0)
    paint, _ = grey_metallic_coat().brdf(w)
    assert paint.flakes.surface_roughness == 0.0 and paint.flakes.edge_fraction == 0.0
    raw = _raw("grey_metallic")
    rough = set_key(set_key(raw, "effect.flakes.face_roughness", 0.05), "effect.flakes.edge_width_nm", 500.0)
    rec = parse_recipe(rough, base_dir=example_path("grey_metallic").parent)
    p1, _ = build_effect_coat(rec.effect, {}, name="x").brdf(w)
    assert p1.flakes.surface_roughness == 0.05
    assert p1.flakes.edge_fraction == pytest.approx(4 * 500.0 / 20e3, rel=1e-12)
    L = {m["aspecular_deg"]: m["L"] for m in _run(rough).multiangle}
    L0 = {m["aspecular_deg"]: m["L"] for m in _run(raw).multiangle}
    assert L[75.0] - L[110.0] > 5 * (L0[75.0] - L0[110.0]) > 0
    assert L[15.0] < L0[15.0]  # the near-specular lobe is widened


def test_flake_face_roughness_and_edge_width_bad_input():
    _bad(set_key(_raw("grey_metallic"), "effect.flakes.face_roughness", 1.5), r"effect\.flakes\.face_roughness")
    _bad(set_key(_raw("grey_metallic"), "effect.flakes.edge_width_nm", -1.0), r"effect\.flakes\.edge_width_nm")


def test_an_error_inside_the_flakes_table_is_shown_alone():
    """effect.flakes is "aluminium" | "mica" | a table: an error inside the table is reported by its key, with
    did-you-mean for a misspelt one, not behind "Input should be 'aluminium' or 'mica' (got {the whole table})"
    (review O)."""
    raw = _raw("grey_metallic")
    raw["effect"]["flakes"]["face_roughnes"] = 0.1
    with pytest.raises(RecipeError) as exc:
        parse_recipe(raw)
    msg = str(exc.value)
    assert msg.startswith("effect.flakes.face_roughnes: unknown key (did you mean 'face_roughness'?)"), msg
    assert "Input should be 'aluminium'" not in msg
    raw = _raw("fe2o3_mica_pearl")
    raw["effect"]["flakes"]["layers"][1]["thickness_nm"] = -400
    with pytest.raises(RecipeError, match=r"^effect\.flakes\.layers\[1\]\.thickness_nm: must be a finite number > 0"):
        parse_recipe(raw)
    with pytest.raises(RecipeError, match=r"effect\.flakes.*Input should be 'aluminium' or 'mica'"):
        parse_recipe({"effect": {"flakes": "silver"}})  # a string that is not one of the two keeps its message
