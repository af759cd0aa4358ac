"""Bad input to matching (issue 17, "Bad input"): each a clear error or a clear warning, never a silently
poor match reported as good — target in percent or outside [0, 1], a varied key that does not exist or is
not numeric, LO >= HI, a palette whose colourants cannot reach the target (how far, which direction)."""

import warnings

import numpy as np
import pytest

from nmmm.cli import main
from nmmm.errors import InvalidInputError, RecipeError
from nmmm.matching import RecipeModel, match_recipe, parse_bound, select_colourants
from nmmm.recipes.schema import example_path, read_toml, set_key

FREE = ["pigments.0.fraction=0.005:0.08", "pigments.1.fraction=0.02:0.25"]


@pytest.fixture(scope="module")
def tint():
    raw, _, _ = read_toml(example_path("hematite_tint"))
    m = RecipeModel(set_key(raw, "film.thickness_nm", 8000.0), FREE)
    return m, m.reflectance(np.array([0.021, 0.15]), "ad")


def test_target_in_percent_or_outside_0_1(tint):
    m, R = tint
    with pytest.raises(InvalidInputError, match=r"percent, not factors \(0-1\); divide by 100"):
        match_recipe(m, R * 100)
    high = R.copy()
    high[3] = 1.2
    with pytest.raises(InvalidInputError, match=r"spans .*1\.2; a reflectance factor of a paint lies in \[0, 1\]"):
        match_recipe(m, high)
    low = R.copy()
    low[0] = -0.03
    with pytest.raises(InvalidInputError, match=r"spans -0\.03.*lies in \[0, 1\]"):
        match_recipe(m, low)
    bad = R.copy()
    bad[2] = np.nan
    with pytest.raises(InvalidInputError, match="non-finite"):
        match_recipe(m, bad)
    with pytest.raises(InvalidInputError, match=r"target spectrum has 5 values; the recipe's grid has 16.*on_grid"):
        match_recipe(m, R[:5])
    with pytest.raises(InvalidInputError, match=r"0 <= L\* <= 100"):
        match_recipe(m, target_lab=[120.0, 0.0, 0.0])


def test_varied_keys_that_do_not_exist_or_are_not_numeric():
    raw, _, _ = read_toml(example_path("hematite_tint"))
    with pytest.raises(RecipeError, match="no such key"):
        RecipeModel(raw, ["pigments.7.fraction=0:0.1"])
    with pytest.raises(RecipeError, match="no such key"):
        RecipeModel(raw, ["film.thicknes_nm=1000:2000"])
    with pytest.raises(RecipeError, match=r"pigments.0.compound: is 'hematite', not a number"):
        RecipeModel(raw, ["pigments.0.compound=0:1"])
    with pytest.raises(RecipeError, match="a key is given twice"):
        RecipeModel(raw, ["pigments.0.fraction=0:0.1", "pigments.0.fraction=0:0.2"])
    with pytest.raises(RecipeError, match="at least one KEY=LO:HI"):
        RecipeModel(raw, [])


@pytest.mark.parametrize("spec, said", [
    ("pigments.0.fraction=0.1:0.1", "LO must be below HI"),
    ("pigments.0.fraction=0.2:0.1", "LO must be below HI"),
    ("pigments.0.fraction=a:0.1", "LO and HI must be numbers"),
    ("pigments.0.fraction=0:inf", "finite"),
    ("pigments.0.fraction=0:0.1:0.2", "two numbers"),
    ("pigments.0.fraction=-0.1:0.1", r"a fraction lies in \[0, 1\]"),
    ("pigments.0.fraction", "write KEY=LO:HI"),
])
def test_bounds(spec, said):
    with pytest.raises(RecipeError, match=said):
        parse_bound(spec)


def test_cli_lo_not_below_hi_is_one_error_line(tmp_path, capsys):
    target = tmp_path / "t.csv"
    target.write_text("wavelength_nm,t\n400,0.2\n500,0.3\n600,0.5\n700,0.6\n")
    rc = main(["match", str(target), str(example_path("hematite_tint")), "--vary", "pigments.0.fraction=0.1:0.1",
               "-o", str(tmp_path / "o"), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("error: ") and "LO must be below HI" in err and err.count("\n") == 1
    rc = main(["match", str(target), str(example_path("hematite_tint")), "--vary", "pigments.9.fraction=0:0.1",
               "-o", str(tmp_path / "o"), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and "no such key" in err and err.count("\n") == 1
    assert not (tmp_path / "o").exists()


def test_unreachable_target_says_how_far_and_which_direction(tint):
    """A saturated blue from hematite + rutile: ΔE00 of the best and the hue missing, in words."""
    m, _ = tint
    blue = [50.0, 0.0, -40.0]
    with pytest.warns(UserWarning, match=r"the best match is ΔE00 = \d+\.\d\d \(> 1\).*cannot reach it — .*too") as rec:
        res = match_recipe(m, target_lab=blue)
    said = " ".join(str(w.message) for w in rec)
    assert f"ΔE00 = {res.de00:.2f}" in said and "add a colourant that supplies the missing direction" in said
    assert res.warnings and res.de00 > 10


def test_palette_that_cannot_reach_the_target_is_warned(tint):
    """Colourant selection over the same palette: the best subset's distance and the missing direction
    are said (before, every subset's warning was silenced and the ranking alone was returned)."""
    m, _ = tint
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        sel = select_colourants(m, 2, target_lab=[50.0, 0.0, -40.0])
    said = [str(w.message) for w in rec if "palette cannot reach" in str(w.message)]
    assert len(said) == 1, [str(w.message) for w in rec]
    assert f"ΔE00 = {sel[0].de00:.2f}" in said[0] and "too" in said[0] and "allow more colourants" in said[0]


def test_reachable_palette_is_not_warned(tint):
    m, R = tint
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        sel = select_colourants(m, 2, target_reflectance=R)
    assert sel[0].de00 < 0.01
    assert not [w for w in rec if "cannot reach" in str(w.message)]
