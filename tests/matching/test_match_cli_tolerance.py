"""``nmmm match --delta-e METHOD --tolerance DE``: the reported difference and pass/fail (issue 17 item 2)."""

import json

import colour
import pytest

from nmmm.cli import main
from nmmm.matching import RecipeModel
from nmmm.recipes.schema import example_path


@pytest.fixture(scope="module")
def target(tmp_path_factory):
    m = RecipeModel(example_path("hematite_tint"), ["pigments.0.fraction=0.005:0.08"])
    R = m.reflectance([0.021])
    path = tmp_path_factory.mktemp("t") / "batch.csv"
    path.write_text("wavelength_nm,batch\n" + "\n".join(f"{w:g},{r:.6f}" for w, r in zip(m.wavelength_nm, R)) + "\n")
    return path


def _match(target, out, *extra):
    # the bound stops short of the target's 0.021: a match with a real difference left
    return main(["match", str(target), str(example_path("hematite_tint")), "--vary", "pigments.0.fraction=0.005:0.015",
                 "-o", str(out), "--no-progress", *extra])


def test_cmc_difference_and_pass_fail_in_stdout_json_and_report(target, tmp_path, capsys):
    assert _match(target, tmp_path / "a", "--delta-e", "CMC(2:1)", "--tolerance", "100") == 0
    said = capsys.readouterr().out
    doc = json.loads((tmp_path / "a" / "match.json").read_text())
    d = doc["difference"]
    ref = float(colour.delta_E(doc["target_lab"], doc["lab"], method="CMC", l=2, c=1))
    assert ref > 0.1 and d["value"] == pytest.approx(ref, rel=1e-9)
    assert d["method"] == "CMC" and d["passes"] is True and d["tolerance"] == 100
    assert f"dE CMC(2:1) = {ref:.4f} under D65; tolerance 100: pass" in said
    assert "dE CMC(2:1)" in (tmp_path / "a" / "report.md").read_text() and "**pass**" in (tmp_path / "a" / "report.md").read_text()
    # the fit stays on ΔE00: the same recipe as without --delta-e
    assert doc["dE00"] == pytest.approx(float(colour.delta_E(doc["target_lab"], doc["lab"], method="CIE 2000")), rel=1e-6)

    # a tight tolerance fails, the default method is ΔE00
    assert _match(target, tmp_path / "b", "--tolerance", str(round(ref / 4, 6))) == 0
    said = capsys.readouterr().out
    d = json.loads((tmp_path / "b" / "match.json").read_text())["difference"]
    assert d["method"] == "CIE 2000" and d["passes"] is False and "FAIL" in said
    assert "**fail**" in (tmp_path / "b" / "report.md").read_text()


@pytest.mark.parametrize("args, words", [
    (["--delta-e", "CIE 1999"], "CIE 1976, CIE 1994, CMC, CIE 2000"),
    (["--delta-e", "CMC(2)"], "(l:c)"),
    (["--delta-e", "dE94(wool)"], "textiles"),
    (["--tolerance", "-1"], "> 0"),
])
def test_bad_method_or_tolerance_is_one_error_line(target, tmp_path, capsys, args, words):
    assert _match(target, tmp_path / "o", *args) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and words in err and err.count("\n") == 1
    assert not (tmp_path / "o").exists()
