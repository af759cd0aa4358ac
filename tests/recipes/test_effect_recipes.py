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


# grey_metallic's far side, measured by the Monte-Carlo tracer of tests/appearance/test_brdf_montecarlo.py on the
# recipe's exact coat (test_grey_metallic_far_side_is_flat_by_the_tracer, 8e6 photons, θi = 45°, light side,
# φ 165-180°): f(θo 60-70°) / f(θo 25-35°), i.e. 110° over 75° aspecular, = 0.990 ± 0.008 (1 SE) at 450/550/650 nm
# (0.9919 / 0.9902 / 0.9879; 1.003 on the coat of one deposit cell, τ 0.513 and a kernel estimate of its tilts, before
# the derived layer became the composition's: τ 0.533, the deposit's half-normal tilt law, band 0.663-1)
GREY_FAR_RATIO_TRACER, GREY_FAR_RATIO_SE = 0.990, 0.008


def _Y(L):  # CIE 1976 lightness inverted (L* > 8): relative luminance Y/Yn
    return ((np.asarray(L, float) + 16.0) / 116.0) ** 3


@pytest.mark.parametrize("name", EFFECT_RECIPES)
def test_shipped_effect_recipes_fall_in_lightness_and_flop_in_range(name):
    res = _run(_raw(name, step_nm=10.0))
    Ls = {m["aspecular_deg"]: m["L"] for m in res.multiangle}
    seq = [Ls[a] for a in (15.0, 25.0, 45.0, 75.0)]
    # flakes lying near the surface: L* falls from 15° to 75° aspecular (McCamy 1996; ASTM E2194)
    assert all(a > b for a, b in zip(seq, seq[1:])), seq
    # ... and on to 110° where the physics says so (issue 18's acceptance). Beyond 75° the flakes' lobe is spent and
    # what is left is diffuse: the primer seen through the flake layer, light from flake to flake, rims. The red
    # metallic's pigment and the pearl's interference flakes keep darkening there; grey_metallic's mirror flakes
    # (τ 0.53 over a 0.35 grey primer) leave a far side that the tracer finds flat (GREY_FAR_RATIO_TRACER), so the
    # model's 110°/75° ratio averaged over the tracer's own bins (φ 165-180°; 1.0156 / 1.0136 / 1.0110) is held to
    # the tracer's measurement within 4 SE (3.0 SE now), like with like; in-plane, as L* is computed, the model
    # gives 1.023 (+0.39 L*): its azimuth modes brighten the plane of incidence on the light side by ~0.01 over
    # the bin's average, held below 0.015
    if name == "grey_metallic":
        ratio = _Y(Ls[110.0]) / _Y(Ls[75.0])
        mc = _montecarlo_module()
        rec = parse_recipe(_raw("grey_metallic"), base_dir=example_path("grey_metallic").parent)
        from nmmm.recipes.effect_schema import build_effect_coat

        paint, _ = build_effect_coat(rec.effect, {}, name="grey").brdf(mc.WAVELENGTHS)
        b = paint.bin_average(mc.WAVELENGTHS, mc._wi(45.0), (25.0, 35.0, 60.0, 70.0), (165.0, 180.0), n_quad=24)
        ratio_bin = b[2, 0] / b[0, 0]
        assert np.all(np.abs(ratio_bin - GREY_FAR_RATIO_TRACER) < 4 * GREY_FAR_RATIO_SE), (ratio_bin, ratio)
        assert np.all(np.abs(ratio - ratio_bin) < 0.015), (Ls, ratio, ratio_bin)
    else:
        assert Ls[75.0] > Ls[110.0], Ls
    fi = res.scalars["flop_index"]
    # Alman (1987) flop index of effect paints: silver metallics up to ~15-17; darker coloured effect paints
    # (low L*45) somewhat higher; a solid is ~0
    assert 5.0 < fi < 25.0, fi
    assert res.scalars["flake_optical_depth"] > 0.1


def _montecarlo_module():
    """tests/appearance/test_brdf_montecarlo.py (its photon tracer ``trace_coat``), loaded by path."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "appearance" / "test_brdf_montecarlo.py"
    spec = importlib.util.spec_from_file_location("_nmmm_brdf_montecarlo", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.slow
def test_grey_metallic_far_side_is_flat_by_the_tracer():
    """The independent check behind GREY_FAR_RATIO_TRACER: the Monte-Carlo photon tracer of
    tests/appearance/test_brdf_montecarlo.py (``trace_coat``: delta tracking through the flake band, Fresnel of the
    Al flakes, Lambertian primer, smooth coat) on the recipe's exact coat — the deposit's tilt density (sampled
    as is), τ = 0.533 in the band z 0.663-1 of the 20 µm basecoat, clear binder n = 1.5, primer 0.35 — at
    θi = 45°, light side (φ 150-180° and 165-180°, folded), θo 25-35° (75° aspecular) and 60-70° (110°), 450/550/650 nm.
    8e6 photons in 16 runs of 5e5 (131 s, loaded machine). Measured: f(60-70°)/f(25-35°) = 0.9919 /
    0.9902 / 0.9879 ± 0.0078 (φ 165-180°; model 1.0156 / 1.0136 / 1.0110, 3.0 SE) and 0.9964 / 0.9946 / 0.9923 ± 0.0056
    (φ 150-180°; model 1.0053 / 1.0035 / 1.0012); every bin within 3.0 SE (the model 1.5-2 SE low at 25-35°,
    3 SE low / 2.7 SE high in the two φ bins at 60-70°). On the previous coat (one deposit cell's τ 0.513, a
    kernel estimate of its tilts, band 0.556-1) the tracer gave 1.0051 / 1.0034 / 1.0011 and the model
    1.0126 / 1.0107 / 1.0083 (φ 165-180°); the model before review P gave 0.974 in its author's light-side bins. The
    ratio's SE treats the two bins as independent (they share photons only through light that escapes twice,
    which correlates them positively: the true SE is smaller). Asserted: bins within 4 SE + 0.1 %, model ratio
    within 4 SE of the tracer's, the tracer's ratio within 4 SE of 1 (flat) and equal to the recorded constant."""
    mc = _montecarlo_module()
    from nmmm.appearance.deposit import grey_metallic_coat

    W = mc.WAVELENGTHS
    raw = _raw("grey_metallic")
    rec = parse_recipe(raw, base_dir=example_path("grey_metallic").parent)
    from nmmm.recipes.effect_schema import build_effect_coat

    paint, _ = build_effect_coat(rec.effect, {}, name="grey").brdf(W)
    ref, _ = grey_metallic_coat().brdf(W)  # the recipe's coat is the demo's (test above): same flakes
    fl = paint.flakes
    assert fl.optical_depth == pytest.approx(ref.flakes.optical_depth, rel=1e-12)
    assert paint.medium is None and fl.surface_roughness == 0.0 and fl.edge_fraction == 0.0
    n = float(paint.coat.material)
    rho = np.asarray(paint.body_reflectance[1], float)
    te, pe = (25.0, 35.0, 60.0, 70.0), (150.0, 165.0, 180.0)
    runs, n_run = 16, 500_000
    S, SE = [], []
    for k in range(runs):
        r = mc.trace_coat(45.0, fl.optical_depth, fl.optics.material.nk(W), fl.tilt, np.zeros(W.size), 0.0, 0.0,
                          fl.depth_range, rho=rho, n=n, n_photons=n_run, theta_edges_deg=te, phi_edges_deg=pe,
                          seed=1800 + k)
        S.append(r["bins"])
        SE.append(r["bins_se"])
    T = np.mean(S, axis=0)  # (θ bin, φ bin, λ)
    Tse = np.sqrt(np.sum(np.square(SE), axis=0)) / runs
    b = paint.bin_average(W, mc._wi(45.0), te, pe, n_quad=24)
    tol = mc.N_SE * Tse + mc.MODEL_TOL_BINS * T
    rows = [0, 2]  # θo 25-35° and 60-70°
    assert np.all(np.abs(b[rows] - T[rows]) < tol[rows]), np.round((b - T) / Tse, 1)[rows]
    for cols in ([0, 1], [1]):  # φ 150-180° (two bins of equal width) and 165-180°
        t75, t110 = T[0, cols].mean(axis=0), T[2, cols].mean(axis=0)
        s75 = np.sqrt(np.sum(Tse[0, cols] ** 2, axis=0)) / len(cols)
        s110 = np.sqrt(np.sum(Tse[2, cols] ** 2, axis=0)) / len(cols)
        rt = t110 / t75
        rse = rt * np.hypot(s110 / t110, s75 / t75)
        rm = b[2, cols].mean(axis=0) / b[0, cols].mean(axis=0)
        assert np.all(np.abs(rm - rt) < mc.N_SE * rse), (cols, rt, rse, rm)
        # flat within the tracer's error: what the quick test's GREY_FAR_RATIO_TRACER records
        assert np.all(np.abs(rt - 1.0) < mc.N_SE * rse), (cols, rt, rse)
        if cols == [1]:
            assert np.all(np.abs(rt - GREY_FAR_RATIO_TRACER) < 0.5 * GREY_FAR_RATIO_SE + 0.003), rt
            assert np.all(np.abs(rse - GREY_FAR_RATIO_SE) < 0.001), rse


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
    faces spread each flake's mirror into a GGX lobe whose tail still reaches 75° aspecular but hardly 110°; rims
    scatter diffusely (∝ the flakes' projected area both ways), adding about as much at both angles. So the far side
    falls by more than with mirror flakes, whose far side is flat (grey_metallic: tracer above), and the
    near-specular peak is lower and wider. Measured (20 nm grid, 550 nm, 1/sr, rough + rims vs mirror): one-flake
    term 1.3e-3 / 3.2e-4 at 75° / 110° vs 1e-5 / 0, multiple lobe 0.0140 / 0.0155 vs 0.0085 / 0.0105;
    L*75 - L*110 = 0.58 against -0.33."""
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
    # margin: the largest bin error of the model that the 6e5-photon tracer left for rough faces and rims (2.1 %,
    # rough + rims + pigment, tests/appearance/test_brdf_montecarlo.py, review P) as L* at 75°: dL* = (L* + 16)/3 · dY/Y ≈ 0.35
    margin = (L0[75.0] + 16.0) / 3.0 * 0.021
    assert L[75.0] - L[110.0] > (L0[75.0] - L0[110.0]) + margin, (L, L0, margin)
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
