"""``nmmm match TARGET RECIPE --vary ...`` writes a complete result folder (issue 17 item 3)."""

import csv
from pathlib import Path

import numpy as np

from nmmm.cli import main
from nmmm.matching import RecipeModel, read_cgats
from nmmm.recipes.schema import example_path, read_toml, parse_recipe


def test_match_cli_writes_the_folder(tmp_path, capsys):
    recipe = example_path("hematite_tint")
    m = RecipeModel(recipe, ["pigments.0.fraction=0.005:0.08"])
    R = m.reflectance([0.021])
    target = tmp_path / "batch.csv"
    target.write_text("wavelength_nm,batch 7\n" + "\n".join(f"{w:g},{r:.6f}" for w, r in zip(m.wavelength_nm, R)) + "\n")
    out = tmp_path / "res"
    rc = main(["match", str(target), str(recipe), "--vary", "pigments.0.fraction=0.005:0.08", "-t", "A", "-t", "TL84",
               "-o", str(out), "--no-progress"])
    assert rc == 0
    said = capsys.readouterr().out
    assert "pigments.0.fraction = 0.021" in said and "dE00 = 0.0000" in said
    for name in ("matched_recipe.toml", "matches.csv", "spectra.csv", "spectra.png", "report.md", "prediction.cgats",
                 "match.json"):
        assert (out / name).is_file(), name
    rows = list(csv.DictReader((out / "matches.csv").open()))
    assert rows[0]["rank"] == "1" and float(rows[0]["dE00"]) < 0.01
    assert {"pigments.0.fraction", "metamerism_index_A", "metamerism_index_FL11", "illuminant", "dL", "dC", "dH"} <= set(rows[0])
    raw, _, _ = read_toml(out / "matched_recipe.toml")
    assert parse_recipe(raw, base_dir=recipe.parent).pigments[0].fraction == 0.021
    np.testing.assert_allclose(read_cgats(out / "prediction.cgats").reflectance[0], R, atol=1e-5)
    assert not list(tmp_path.glob(".res.incomplete-*"))


def test_match_cli_bad_input_is_one_line(tmp_path, capsys):
    target = tmp_path / "pc.csv"
    target.write_text("wavelength_nm,reflectance\n400,10\n500,20\n600,30\n")
    rc = main(["match", str(target), str(example_path("hematite_tint")), "--vary", "pigments.0.fraction=0:0.1",
               "-o", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("error: ") and "percent" in err and err.count("\n") == 1
    rc = main(["match", "lab:50,10", str(example_path("hematite_tint")), "--vary", "pigments.0.fraction=0:0.1"])
    assert rc == 2 and "lab:L,a,b" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "data" / "matching"


def test_calibrate_cli_on_the_shipped_ladder(tmp_path, capsys):
    import json

    out = tmp_path / "cal"
    assert main(["calibrate", str(EXAMPLES / "ladder.toml"), "-o", str(out)]) == 0
    said = capsys.readouterr().out
    assert "k_scale = 1.2" in said and "1:2 (left out)" in said
    size = json.loads((out / "calibration.json").read_text())["values"]["size_scale"]
    assert f"multiply pigments.0.diameter_nm by {size:.4g}" in said
    assert "hematite is uniaxial" in said and "one isotropic n, k" in said
    got = json.loads((out / "calibration.json").read_text())
    assert abs(got["values"]["k_scale"] - 1.25) < 3 * got["standard_errors"]["k_scale"] + 1e-3
    assert got["de00_after"]["1:2"] <= 1.0 < got["de00_before"]["1:2"]
    rows = list(csv.DictReader((out / "calibration.csv").open()))
    assert [r["role"] for r in rows].count("left out") == 1
    assert "wavelength_nm,n,k" in (out / "hematite_calibrated.csv").read_text()


def test_match_cli_reads_the_shipped_cxf_batch(tmp_path, capsys):
    out = tmp_path / "m"
    assert main(["match", str(EXAMPLES / "batch.cxf"), str(EXAMPLES / "tint_base.toml"), "--vary",
                 "pigments.0.fraction=0.005:0.08", "-o", str(out), "--no-progress"]) == 0
    assert "pigments.0.fraction = 0.021" in capsys.readouterr().out


def test_match_cli_says_which_sample_of_a_multi_sample_file(tmp_path, capsys):
    out = tmp_path / "m"
    args = ["match", str(EXAMPLES / "ladder.cgats"), str(EXAMPLES / "tint_base.toml"), "--vary",
            "pigments.0.fraction=0.005:0.08", "-o", str(out), "--no-progress"]
    main(args + ["--sample", "1:4"])
    assert "matching sample '1:4' (3 of 5; --sample chooses another)" in capsys.readouterr().out


def test_unidentifiable_keys_are_said_in_stdout_and_the_report(tmp_path, capsys):
    """The opaque 60 µm tint: one spectrum fixes only the hematite:rutile ratio, so each fraction's
    σ (10 and 74 here) exceeds its bound span; the match says so instead of reporting fractions."""
    out = tmp_path / "m"
    assert main(["match", str(EXAMPLES / "batch.cxf"), str(EXAMPLES / "tint_base.toml"), "--mode", "spectral",
                 "--vary", "pigments.0.fraction=0.005:0.08", "--vary", "pigments.1.fraction=0.02:0.25",
                 "-o", str(out), "--no-progress"]) == 0
    words = "only the ratio is identifiable from one spectrum; measure over black and white or fix one key"
    std = capsys.readouterr()
    assert std.out.count(words) == 2 and words not in std.err
    assert "pigments.1.fraction = " in std.out and "exceeds its bound span 0.02–0.25" in std.out
    assert (out / "report.md").read_text(encoding="utf-8").count(words) == 2


def test_match_cli_geometry_mismatch_in_words(tmp_path, capsys):
    """The target's geometry canonicalised before comparing (SCE = de:8: no warning; SCI against the
    recipe's de:8: the gloss, and which reads lighter)."""
    from nmmm.matching import MeasuredSpectra, write_cgats

    recipe = example_path("hematite_tint")
    m = RecipeModel(recipe, ["pigments.0.fraction=0.005:0.08"])
    for spelling, words in (("SCE", None), ("SCI", "the target reads lighter")):
        target = write_cgats(tmp_path / f"{spelling}.cgats", MeasuredSpectra(m.wavelength_nm, m.reflectance([0.021])[None],
                                                                            ("batch",), spelling))
        assert main(["match", str(target), str(recipe), "--vary", "pigments.0.fraction=0.005:0.08",
                     "-o", str(tmp_path / spelling), "--no-progress"]) == 0
        err = capsys.readouterr().err
        assert (words in err) if words else ("geometry" not in err)
