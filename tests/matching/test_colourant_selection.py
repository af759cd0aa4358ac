"""Colourant selection (issue 17 item 3): a target made by the forward model from 2 of a 4-colourant
palette is matched with at most 2 colourants; the right pair ranks first."""

import csv

import numpy as np
import pytest

from nmmm.cli import main
from nmmm.errors import InvalidInputError
from nmmm.matching import RecipeModel
from nmmm.matching.colourant_selection import select_colourants
from nmmm.recipes.schema import example_path, read_toml, set_key

PALETTE = ["pigments.0.fraction=0:0.08", "pigments.1.fraction=0:0.25", "pigments.2.fraction=0:0.02",
           "pigments.3.fraction=0:0.2"]
KEYS = [p.split("=")[0] for p in PALETTE]
TRUE = np.array([0.021, 0.15, 0.0, 0.0])  # hematite + rutile; no black, no baryte


def _palette_raw():
    """Hematite, rutile, a black (n 1.9 + 0.6i, 60 nm) and baryte (n 1.64, 800 nm), 8 µm over
    white, on the shipped 400–700 nm / 20 nm grid."""
    raw, _, _ = read_toml(example_path("hematite_tint"))
    raw = set_key(raw, "film.thickness_nm", 8000.0)
    raw["compounds"]["black"] = {"n": 1.9, "k": 0.6}
    raw["compounds"]["baryte"] = {"n": 1.64}
    raw["pigments"].append({"compound": "black", "fraction": 0.004, "diameter_nm": 60})
    raw["pigments"].append({"compound": "baryte", "fraction": 0.05, "diameter_nm": 800})
    return raw


@pytest.fixture(scope="module")
def palette():
    m = RecipeModel(_palette_raw(), PALETTE)
    return m, m.reflectance(TRUE, "ad")


def test_the_right_pair_ranks_first(palette, capsys):
    m, target = palette
    sel = select_colourants(m, 2, target, progress=True)
    assert "colourant subsets" in capsys.readouterr().err  # the progress bar over subsets
    assert len(sel) == 4 + 6  # every subset of 1 or 2 of 4
    best = sel[0]
    assert best.colourants == ("pigments.0.fraction", "pigments.1.fraction")
    assert best.stage == "ad" and best.de00 < 0.3
    np.testing.assert_allclose([best.values[k] for k in KEYS], TRUE, rtol=0.05, atol=1e-12)  # excluded: exactly 0
    assert set(best.metamerism) == {"A", "FL11"} and all(v < 0.3 for v in best.metamerism.values())
    # ranked: the finished (adding-doubling) subsets by ΔE00, then the KM-ranked rest
    finished = [s for s in sel if s.stage == "ad"]
    assert len(finished) == 3 and sel[:3] == finished
    assert [s.de00 for s in finished] == sorted(s.de00 for s in finished)
    assert [s.de00 for s in sel[3:]] == sorted(s.de00 for s in sel[3:])
    for s in sel:  # at most 2 colourants, the excluded ones at 0
        assert 1 <= len(s.colourants) <= 2
        assert all(s.values[k] == 0.0 for k in KEYS if k not in s.colourants)


@pytest.mark.parametrize("n", [0, 5])
def test_max_colourants_out_of_range_is_a_clear_error(palette, n):
    m, target = palette
    with pytest.raises(InvalidInputError, match=r"choose 1 to 4 \(the palette has 4 colourants"):
        select_colourants(m, n, target)


def test_cli_max_colourants_writes_ranked_subsets(tmp_path, palette, capsys):
    from nmmm.recipes.run import _dump_toml

    m, target = palette
    recipe = tmp_path / "palette.toml"
    recipe.write_text(_dump_toml(_palette_raw()), encoding="utf-8")
    tfile = tmp_path / "target.csv"
    tfile.write_text("wavelength_nm,panel\n" + "\n".join(f"{w:g},{r:.6f}" for w, r in zip(m.wavelength_nm, target)) + "\n")
    out = tmp_path / "res"
    args = ["match", str(tfile), str(recipe)] + [a for p in PALETTE for a in ("--vary", p)] + ["-o", str(out), "--no-progress"]
    assert main(args + ["--max-colourants", "2"]) == 0
    said = capsys.readouterr().out
    assert "pigments.0.fraction + pigments.1.fraction" in said
    rows = list(csv.DictReader((out / "matches.csv").open()))
    assert len(rows) == 10 and rows[0]["rank"] == "1"
    assert set(KEYS) | {"dE00", "metamerism_index_A", "metamerism_index_FL11", "illuminant"} <= set(rows[0])
    assert rows[0]["colourants"] == "pigments.0.fraction + pigments.1.fraction" and float(rows[0]["dE00"]) < 0.3
    assert float(rows[0]["pigments.2.fraction"]) == 0.0 and float(rows[0]["pigments.3.fraction"]) == 0.0
    raw, _, _ = read_toml(out / "matched_recipe.toml")
    assert raw["pigments"][2]["fraction"] == 0.0 and abs(raw["pigments"][0]["fraction"] - 0.021) < 0.001
    assert main(args[:-3] + ["-o", str(tmp_path / "bad"), "--max-colourants", "5"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "choose 1 to 4" in err


def test_cielab_target_ranks_single_colourants(palette):
    from nmmm.colour import spectra_to_lab

    m, target = palette
    sel = select_colourants(m, 1, target_lab=spectra_to_lab(m.wavelength_nm, target))
    assert len(sel) == 4 and all(len(s.colourants) == 1 for s in sel)
    assert all(s.metamerism == {} for s in sel)  # no target spectrum: no metamerism index
    assert sel[0].colourants == ("pigments.0.fraction",)  # only hematite makes a red
    assert [s.stage for s in sel] == ["ad"] * 3 + ["km"]
