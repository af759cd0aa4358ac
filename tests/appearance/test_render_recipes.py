"""Every paint recipe has a plate image (issue 19 item 1): a solid film renders a mono or
stereo plate from the BRDF that gives its colours, ``nmmm render plate --paint RECIPE.toml``
takes a recipe, and a recipe with no painted surface is refused naming ``image``."""

import json
import tomllib

import numpy as np
import pytest
from click.testing import CliRunner

from nmmm.errors import RecipeError
from nmmm.recipes.schema import example_path, parse_recipe


def _hematite(image: dict | None):
    p = example_path("hematite_paint")
    raw = tomllib.loads(p.read_text())
    raw["spectral"]["step_nm"] = 20
    raw["pigment"]["size_nodes"] = 8
    if image is not None:
        raw["image"] = image
    return parse_recipe(raw, base_dir=p.parent)


@pytest.fixture(scope="module")
def hematite_mono():
    from nmmm.recipes.run import compute

    return compute(_hematite({"stereo": False, "pixels": [36, 24]}), progress=False)


def test_solid_recipe_renders_a_mono_plate(hematite_mono):
    res = hematite_mono
    assert set(res.images) == {"view"} and set(res.spectral_images) == {"view"}
    img = res.images["view"]
    assert img.shape == (24, 36, 3) and np.all(np.isfinite(img))
    centre = img[8:16, 12:24].reshape(-1, 3).mean(0)
    assert centre[0] > 1.5 * centre[1] > 0 and centre[1] >= centre[2]  # hematite: a rusty red, not grey
    assert any("solid paint" in n for n in res.notes)


def test_solid_plate_brdf_reads_the_recipe_spectrum(hematite_mono):
    """The plate's BRDF, integrated over the hemisphere at 8° incidence without the coat's
    mirror reflection (a d/8 SCE reading by quadrature, independent of the Saunderson
    inversion that built it), gives the recipe's primary spectrum within dE00 < 1."""
    from nmmm.colour import spectra_to_lab
    from nmmm.recipes.plate_image import recipe_paint
    from nmmm.recipes.run import build_materials

    res = hematite_mono
    r, w = res.recipe, res.wavelength_nm
    brdf = recipe_paint(r, build_materials(r, w, progress=False), w, res)
    th = np.radians(8.0)
    wi = np.array([0.0, np.sin(th), np.cos(th)])
    mu, wmu = np.polynomial.legendre.leggauss(24)
    mu, wmu = 0.5 * (mu + 1), 0.5 * wmu  # cos θo on (0, 1)
    phi = (np.arange(32) + 0.5) * 2 * np.pi / 32
    M, P = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(1 - M**2)
    wo = np.stack([s * np.cos(P), s * np.sin(P), M], -1).reshape(-1, 3)
    f = np.asarray(brdf.evaluate(w, np.broadcast_to(wi, wo.shape), wo, components=("base", "multiple")), float)
    weights = (np.repeat(wmu, phi.size) * 2 * np.pi / phi.size * M.ravel())[:, None]  # cos θo dΩ
    reading = (f * weights).sum(0)
    R = np.asarray(res.spectra[res.primary])
    lab = spectra_to_lab(w, np.stack([R, reading]))
    from colour.difference import delta_E_CIE2000

    assert float(delta_E_CIE2000(lab[0], lab[1])) < 1.0
    assert np.max(np.abs(reading - R)) < 0.01


def test_solid_recipe_stereo_pair():
    from nmmm.recipes.run import compute

    res = compute(_hematite({"stereo": True, "pixels": [24, 16]}), progress=False)
    assert set(res.images) == {"left eye", "right eye"}
    a, b = res.images["left eye"], res.images["right eye"]
    assert a.shape == b.shape == (16, 24, 3) and not np.array_equal(a, b)  # the eyes see the plate from 6.5 cm apart


def test_glass_recipe_takes_an_image_and_a_paint_refuses_the_light_table_naming_the_key():
    # issue 19 item 1: a [plate] recipe now has a plate image (tests/appearance/test_render_glass_sky_tilt.py
    # checks its radiance); the light table, a back-light, only makes sense behind a transparent plate
    p = example_path("gold_ruby_glass")
    raw = tomllib.loads(p.read_text())
    raw["image"] = {"stereo": False}
    assert parse_recipe(raw, base_dir=p.parent).image.scene == "point"
    h = example_path("hematite_paint")
    raw = tomllib.loads(h.read_text())
    raw["image"] = {"stereo": False, "scene": "light-table"}
    with pytest.raises(RecipeError, match=r"image.scene: 'light-table' .* needs a \[plate\] or \[thin_film\]"):
        parse_recipe(raw, base_dir=h.parent)


def test_render_plate_cli_takes_a_recipe(tmp_path):
    from nmmm.recipes.render_cli import render

    src = example_path("hematite_paint").read_text().replace("step_nm = 10", "step_nm = 20")
    rec = tmp_path / "hematite.toml"
    rec.write_text(src)
    out = CliRunner().invoke(render, ["plate", str(tmp_path / "p"), "--paint", str(rec), "--width", "30",
                                      "--height", "20"])
    assert out.exit_code == 0, out.output
    info = json.loads(out.output)
    assert "Hematite" in info["plate"] and all((tmp_path / f).exists() for f in ("p.exr", "p.png"))
    bad = CliRunner().invoke(render, ["plate", str(tmp_path / "q"), "--paint", str(tmp_path / "missing.toml")])
    assert bad.exit_code == 2 and "missing.toml" in bad.output and "does not exist" in bad.output


def test_render_plate_cli_takes_glass_and_thin_film_recipes_and_a_cie_sky(tmp_path):
    """Issue 19 items 1-2: ``--paint`` a [plate] recipe (glass on a light table, its T(θ, λ) in front of it),
    a [thin_film] recipe (its R(θ, λ) in the booth); ``--sky TYPE`` (the CIE standard general sky)."""
    from nmmm.recipes.render_cli import render

    glass = tmp_path / "glass.toml"
    glass.write_text(example_path("gold_ruby_glass").read_text().replace("step_nm = 5", "step_nm = 20"))
    out = CliRunner().invoke(render, ["plate", str(tmp_path / "g"), "--paint", str(glass), "--width", "30",
                                      "--height", "20"])
    assert out.exit_code == 0, out.output
    info = json.loads(out.output)
    assert "RecipeSpecularPlate" in info["plate"] and "light table" in info["plate"] and (tmp_path / "g.png").exists()
    film = CliRunner().invoke(render, ["plate", str(tmp_path / "f"), "--paint", str(example_path("interference_pigment")),
                                       "--booth", "45", "--width", "30", "--height", "20"])
    assert film.exit_code == 0, film.output
    assert json.loads(film.output)["display"]["mono"]["plate_mean_cd_m2"] > 0
    sky = CliRunner().invoke(render, ["plate", str(tmp_path / "s"), "--paint", "solid", "--sky", "12", "--width", "30",
                                      "--height", "20", "--cells", "100", "60"])
    assert sky.exit_code == 0, sky.output
    bad = CliRunner().invoke(render, ["plate", str(tmp_path / "b"), "--paint", "solid", "--sky", "17"])
    assert bad.exit_code == 2 and "--sky" in bad.output
    # review N: --sky with --booth rendered the booth and dropped the sky without a word
    both = CliRunner().invoke(render, ["plate", str(tmp_path / "c"), "--paint", "solid", "--sky", "12", "--booth", "45"])
    assert both.exit_code == 2 and "--sky" in both.output and "--booth" in both.output


def test_recipe_image_in_the_viewing_booth():
    """[image] scene = "booth": the plate among grey walls (no black void), tone-mapped."""
    from nmmm.recipes.run import compute

    res = compute(_hematite({"stereo": False, "pixels": [36, 24], "scene": "booth-overhead", "fov_deg": 40.0}), progress=False)
    img, simg = res.images["view"], res.spectral_images["view"]
    off = ~simg.on_plate
    assert off.any() and np.all(img[off].min(-1) > 0.05)  # the booth's grey behind the plate
    assert np.all((img >= 0) & (img <= 1)) and simg.to_display(tone_map="knee")[1]["clipped_fraction"] <= 0.01


def test_effect_recipe_in_the_booth_has_glints():
    import tomllib as _t

    from nmmm.recipes.run import compute

    p = example_path("grey_metallic")
    raw = _t.loads(p.read_text())
    raw["spectral"]["step_nm"] = 40
    raw["image"].update({"pixels": [36, 24], "scene": "booth", "stereo": False, "renderer": "auto"})
    res = compute(parse_recipe(raw, base_dir=p.parent), progress=False)
    assert res.spectral_images["view"].metadata["n_glints"] > 0 and res.images["view"].shape == (24, 36, 3)


def test_booth_view_shows_face_and_flop():
    """The recipe plate image's default eye (plate_image.VIEW_TILT_DEG) in the 45° booth: the
    aspecular range it records in the image metadata equals the one computed from the plate's
    own points (a grid over the 15 cm × 10 cm plate, eye and source positions, no camera rays),
    and spans the near-specular face (≤ 15°) and the flop (≥ 30°) — at the former 30° eye the
    whole plate lay 5–25° off specular and a grey metallic rendered nearly white (review M)."""
    from nmmm.appearance.render import ViewingBooth
    from nmmm.recipes.plate_image import VIEW_TILT_DEG
    from nmmm.recipes.run import compute

    res = compute(_hematite({"stereo": False, "pixels": [60, 40], "scene": "booth"}), progress=False)
    img = res.spectral_images["view"]
    lo, med, hi = img.metadata["aspecular_deg"]
    t = np.radians(VIEW_TILT_DEG)
    eye = np.array([0.0, -400.0 * np.sin(t), 400.0 * np.cos(t)])
    src = np.asarray(ViewingBooth(source="45").lights()[0].position_mm, float)
    X, Y = np.meshgrid(np.linspace(-75, 75, 301), np.linspace(-50, 50, 201))
    P = np.stack([X, Y, 0 * X], axis=-1)
    to_eye = eye - P
    to_src = src - P
    # the aspecular angle: between the direction to the source and the eye's direction mirrored at z = 0
    mirrored_eye = to_eye * np.array([-1.0, -1.0, 1.0])
    c = np.sum(mirrored_eye * to_src, -1) / np.linalg.norm(to_eye, axis=-1) / np.linalg.norm(to_src, axis=-1)
    a = np.degrees(np.arccos(c))
    assert lo == pytest.approx(a.min(), abs=0.6) and hi == pytest.approx(a.max(), abs=0.6)
    assert lo <= 15.0 and hi >= 30.0 and lo < med < hi
    assert img.metadata["view_deg_from_normal"] == VIEW_TILT_DEG


def test_composition_effect_plate_uses_the_coats_flakes(monkeypatch):
    """A composition [effect] recipe's plate image (the recipe runner in the booth, and
    ``nmmm render plate --paint``) tiles its EffectCoat's own flake cell (the deposit behind its
    statistical BRDF), not flakes redrawn at the expert optical depth."""
    import nmmm.appearance.render as render
    from nmmm.recipes.render_cli import plate_from_recipe_file
    from nmmm.recipes.run import _effect_coat, compute

    path = example_path("grey_metallic")
    raw = tomllib.loads(path.read_text())
    raw["spectral"]["step_nm"] = 40
    raw["image"].update(scene="booth", stereo=False, pixels=[30, 20])
    rec = parse_recipe(raw, base_dir=path.parent)
    coat = _effect_coat(rec)
    d, fl = coat.derived(), coat.flake_list()
    seen = []
    real = render.render_plate
    monkeypatch.setattr(render, "render_plate", lambda plate, *a, **k: seen.append(plate) or real(plate, *a, **k))
    compute(rec, progress=False)
    (cli_plate, _) = plate_from_recipe_file(path)
    for plate in (seen[0], cli_plate):
        assert len(plate.flakes) == len(fl)
        np.testing.assert_allclose(plate.flakes.region_nm, fl.region_nm)
        cw, ch = plate.cell_mm
        assert len(plate.flakes) / (cw * ch) == pytest.approx(d.number_density_per_mm2, rel=1e-6)
