"""Stimulus pairs of the 2AFC experiment made from recipes (issue 10: 'pairs can be produced
by nmmm itself from a recipe'): the written pairs file loads with the experiment's own
loader, and its computed image is the recipe's own output image, pixel for pixel."""

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from nmmm.errors import RecipeError
from nmmm.experiment.pairs import load_pairs
from nmmm.recipes.pairs import make_experiment_pairs
from nmmm.recipes.run import run_recipe

from .conftest import fast_raw


def _photo(path, size):
    rng = np.random.default_rng(0)
    Image.fromarray(rng.integers(0, 255, (size[1], size[0], 3), dtype=np.uint8)).save(path)
    return path


def _png(path):
    return np.asarray(Image.open(path).convert("RGB"), int)


def test_rendered_recipe_pairs_load_and_match_the_run_image(grey_metallic_run, tmp_path):
    recipe, res, _ = grey_metallic_run
    photo = _photo(tmp_path / "plate.jpg", (300, 200))  # same 3:2 aspect as the 30 x 20 render
    out = make_experiment_pairs([(str(recipe), photo, "grey metallic"), (res, photo)], tmp_path / "exp" / "pairs.toml",
                                progress=False, repetitions=2)
    ps = load_pairs(out)
    assert len(ps) == 2 and ps.settings.repetitions == 2
    assert ps.pairs[0].photo == photo.resolve()
    ref = _png(res.files["image left eye"])  # what `nmmm run` itself wrote
    for p in ps.pairs:
        assert p.rendered.parent == out.parent / "rendered"
        np.testing.assert_allclose(_png(p.rendered), ref, atol=1)  # 8-bit rounding only


def test_recipe_without_image_gives_a_swatch_of_its_colour(tmp_path):
    raw = fast_raw("interference_pigment", step_nm=20.0)
    photo = _photo(tmp_path / "plate.png", (400, 300))
    res = run_recipe(raw, tmp_path / "run", progress=False, report=False)
    out = make_experiment_pairs([(raw, photo, "mica")], tmp_path / "pairs.toml", progress=False)
    img = _png(load_pairs(out).pairs[0].rendered)
    assert img.shape == (300, 400, 3)  # the photograph's aspect ratio
    row = next(c for c in res.colours if c["spectrum"] == res.primary and c["illuminant"] == "D65")
    np.testing.assert_allclose(img.reshape(-1, 3), np.broadcast_to(np.round(np.array(row["srgb"]) * 255), (400 * 300, 3)),
                               atol=1)


def test_aspect_mismatch_names_image_pixels(grey_metallic_run, tmp_path):
    recipe, res, _ = grey_metallic_run
    with pytest.raises(RecipeError, match=r"image\.pixels.*30x20.*100x100"):
        make_experiment_pairs([(res, _photo(tmp_path / "sq.png", (100, 100)))], tmp_path / "p.toml", progress=False)
    with pytest.raises(RecipeError, match="no rendered view 'top'"):
        make_experiment_pairs([(res, _photo(tmp_path / "r.png", (30, 20)))], tmp_path / "p.toml", view="top",
                              progress=False)
    with pytest.raises(RecipeError, match=r"pairs\[1\]"):
        make_experiment_pairs([str(recipe)], tmp_path / "p.toml", progress=False)


def test_cli_run_pair_with(grey_metallic_run, tmp_path):
    from nmmm.recipes.cli import run

    recipe, res, _ = grey_metallic_run
    photo = _photo(tmp_path / "plate.png", (60, 40))
    r = CliRunner().invoke(run, [str(recipe), "-o", str(tmp_path / "o"), "--no-progress", "--pair-with", str(photo)])
    assert r.exit_code == 0, r.output
    ps = load_pairs(tmp_path / "o" / "pairs.toml")
    np.testing.assert_allclose(_png(ps.pairs[0].rendered), _png(tmp_path / "o" / "image_left_eye.png"), atol=1)
    bad = CliRunner().invoke(run, [str(recipe), "-o", str(tmp_path / "o2"), "--pair-with", str(tmp_path / "none.png")])
    assert bad.exit_code == 2 and "photograph (--pair-with)" in bad.output and "not found" in bad.output
    assert not (tmp_path / "o2").exists()  # refused before running
