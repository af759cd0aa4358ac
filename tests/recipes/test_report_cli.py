"""The HTML report (headless chromium), `nmmm compare`, the CLI (`nmmm demo` guarding: tests/demo)."""

import os
from pathlib import Path

import pytest
from click.testing import CliRunner

from nmmm.recipes import cli
from nmmm.recipes.schema import example_path, set_key

from .conftest import fast_raw

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def _open_in_chromium(path: Path):
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page()
            errors = []
            page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(path.resolve().as_uri())
            page.wait_for_load_state("load")
            widths = page.evaluate("Array.from(document.images).map(i => i.complete ? i.naturalWidth : 0)")
            text = page.inner_text("body")
        finally:
            browser.close()
    return errors, widths, text


@pytest.mark.browser
@pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium at /usr/bin/chromium")
def test_report_opens_in_chromium_and_shows_its_images(grey_metallic_run):
    _, res, _ = grey_metallic_run
    html = Path(res.files["report"]).read_text()
    assert "src=\"http" not in html and "<script src" not in html  # self-contained
    errors, widths, text = _open_in_chromium(Path(res.files["report"]))
    assert errors == []
    assert len(widths) >= 3 and all(w > 0 for w in widths)
    assert "Grey metallic plate" in text and "L* (1)" in text and "aspecular angle (°)" in text
    assert "Recipe (TOML)" in text


def test_compare_same_recipe_is_zero_and_matches_colour_science(tmp_path):
    import colour

    from nmmm.recipes.compare import compare_recipes, compare_results

    a = fast_raw("hematite_paint", step_nm=40.0)
    b = set_key(a, "pigment.body_diagonal_nm", 600.0)  # grain-size substitution
    out = compare_recipes(a, b, tmp_path, illuminants=["D65", "A"], progress=False)
    rows = [r for r in out["rows"] if r["illuminant"] == "D65"]
    ref = colour.delta_E([rows[0]["L_A"], rows[0]["a_A"], rows[0]["b_A"]],
                         [rows[0]["L_B"], rows[0]["a_B"], rows[0]["b_B"]], method="CIE 2000")
    assert rows[0]["dE00"] == pytest.approx(float(ref), rel=1e-9)
    assert rows[0]["dE00"] > 0.1
    assert {r["illuminant"] for r in out["rows"]} == {"D65", "A"}
    assert Path(out["report"]).exists() and (tmp_path / "spectra_overlay.png").exists()
    same = compare_results(out["a"], out["a"], ["D65", "A"])
    assert {r["illuminant"] for r in same} == {"D65", "A"} and all(abs(r["dE00"]) < 1e-9 for r in same)


def test_cli_run_and_sweep_and_errors(tmp_path):
    p = tmp_path / "paint.toml"
    p.write_text(example_path("interference_pigment").read_text().replace("step_nm = 5", "step_nm = 20"))
    runner = CliRunner()
    r = runner.invoke(cli.run, [str(p), "-o", str(tmp_path / "out"), "--no-progress"])
    assert r.exit_code == 0, r.output
    assert "L* =" in r.output and (tmp_path / "out" / "report.html").exists()
    first_line = r.output.splitlines()[0]
    r = runner.invoke(cli.run, [str(p), "-o", str(tmp_path / "out2"), "--set", "thin_film.layers[1].thickness_nm=60",
                                "--no-progress"])
    assert r.exit_code == 0, r.output
    assert r.output.splitlines()[0] != first_line  # another TiO2 thickness, another colour
    assert "thickness_nm = 60" in (tmp_path / "out2" / "recipe.toml").read_text()
    r = runner.invoke(cli.sweep, [str(p), "--vary", "thin_film.layers[1].thickness_nm=100,140", "--serial",
                                  "-o", str(tmp_path / "sw"), "--no-progress"])
    assert r.exit_code == 0, r.output
    assert "2 points: 2 computed" in r.output
    assert (tmp_path / "sw" / "report.html").exists()
    r = runner.invoke(cli.sweep, [str(p), "--vary", "thin_film.layers[1].thickness_nm=100,140", "--serial",
                                  "-o", str(tmp_path / "sw"), "--no-progress"])
    assert "0 computed, 2 already done" in r.output
    bad = tmp_path / "bad.toml"
    bad.write_text(p.read_text().replace("thickness_nm = 120", "thickness_nm = -120", 1))
    r = runner.invoke(cli.run, [str(bad), "-o", str(tmp_path / "bad"), "--no-progress"])
    assert r.exit_code != 0 and "thin_film.layers[1].thickness_nm: must be a finite number > 0" in r.output
    r = runner.invoke(cli.run, ["no_such_recipe", "--no-progress"])
    assert r.exit_code != 0 and "shipped" in r.output
    # an output folder that cannot be made, a malformed --set: usage errors (exit 2), no traceback
    from nmmm.demo.cli import demo

    for cmd, args in [(cli.run, [str(p), "-o", str(bad / "x")]), (demo, ["-o", str(bad), "--quick"]),
                      (cli.compare, [str(p), str(p), "-o", str(bad)]),
                      (cli.sweep, [str(p), "--vary", "thin_film.layers[1].thickness_nm=90", "-o", str(bad)])]:
        r = runner.invoke(cmd, args + ["--no-progress"])
        assert r.exit_code == 2 and "cannot create the output folder" in r.output, (cmd.name, r.output)
    r = runner.invoke(cli.run, [str(p), "--set", "=3", "-o", str(tmp_path / "o3"), "--no-progress"])
    assert r.exit_code == 2 and "'--set': '=3': empty key" in r.output


def test_top_level_cli_maps_the_commands():
    from nmmm.cli import cli as top

    r = CliRunner().invoke(top, ["--help"])
    for name in ("run", "demo", "compare", "sweep"):
        assert name in r.output
    r = CliRunner().invoke(top, ["sweep", "--help"])
    assert "--vary" in r.output and "--scheduler" in r.output


def test_report_writes_complex_numbers_as_a_reader_would():
    """Packages' tables hold permittivities; the report shows 'a + bi', not Python's '(a+bj)'."""
    from nmmm.recipes.report import _fmt

    assert _fmt(2.80509 + 0.14491j) == "2.805 + 0.145i"
    assert _fmt("(2.80509-0.14491j)") == "2.805 − 0.145i"  # as read back from a CSV table
    assert _fmt("(not complex)") == "(not complex)"


def test_report_keeps_text_tables_aligned(tmp_path):
    """A hook's plain-text table (aligned columns) is shown preformatted, prose as paragraphs."""
    from nmmm.recipes.report import write_report

    table = "observer  k/n    Pc\nS01       12/20  60.0\nS02       11/20  55.0"
    p = write_report([{"title": "t", "text": "Prose that\nwraps.\n\n" + table}], tmp_path / "r.html", title="t")
    html = p.read_text()
    assert "<pre class='texttable'>observer  k/n    Pc\nS01       12/20  60.0" in html
    assert "<p>Prose that\nwraps.</p>" in html
