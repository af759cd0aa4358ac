"""The report as a formulator reads it (issue 25): the demo, a compare and a sweep report rendered in
Debian's chromium at 1366 px — no horizontal overflow, no console error, every image loaded, every
plot with labelled axes (checked on the figure objects while they were saved) — plus the pieces:
summary box, recipe names instead of A/B, legends in words, out-of-gamut marks, what-next commands,
sanity warnings, explicit dispersion units."""

import os
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from nmmm.recipes.figures import audit_axis_labels
from nmmm.recipes.run import _dump_toml
from nmmm.recipes.schema import parse_recipe, set_key

from .conftest import fast_raw

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]
VIEWPORT = {"width": 1366, "height": 900}
SHOTS = os.environ.get("NMMM_REPORT_SHOTS")  # a folder to keep the screenshots in (to look at them)


@pytest.fixture(scope="module")
def reports(tmp_path_factory):
    """The three reports, built once with every saved figure's axis labels recorded."""
    from nmmm.demo.runner import run_sections
    from nmmm.recipes.compare import compare_recipes
    from nmmm.recipes.sweep import sweep

    d = tmp_path_factory.mktemp("reports")
    a = fast_raw("hematite_paint", step_nm=20.0)
    b = fast_raw("hematite_paint_ethylcellulose", step_nm=20.0)
    (d / "epoxy.toml").write_text(_dump_toml(a))
    (d / "ethylcellulose.toml").write_text(_dump_toml(b))
    with warnings.catch_warnings(), audit_axis_labels() as saved:
        warnings.simplefilter("ignore")
        demo = run_sections(d / "demo", only=["grey_metallic", "interference_pigment", "nmmm.demo.materials"],
                            progress=False)
        cmp = compare_recipes(str(d / "epoxy.toml"), str(d / "ethylcellulose.toml"), d / "compare",
                              illuminants=["D65", "A"], progress=False)
        sw = sweep(str(d / "epoxy.toml"), ["pigment.fraction=0.05,0.1", "pigment.dependent_scattering=false,true"],
                   d / "sweep", serial=True, progress=False)
    assert demo.failures == []
    return {"demo": demo.report, "compare": Path(cmp["report"]), "sweep": Path(sw["report"]), "saved": saved,
            "compare_result": cmp, "sweep_result": sw, "dir": d}


def test_every_saved_figure_has_labelled_axes_with_units(reports):
    saved = reports["saved"]
    assert len(saved) >= 8  # spectra, n k, multi-angle, overlay, sweep, the materials hook's plots
    assert [(name, miss) for name, miss in saved if miss] == []


def _render(path: Path, name: str, media: str = "screen", width: int = VIEWPORT["width"]):
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": width, "height": VIEWPORT["height"]})
            errors = []
            page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.emulate_media(media=media)
            page.goto(path.resolve().as_uri())
            page.wait_for_load_state("load")
            info = page.evaluate("""() => ({
                scrollWidth: document.documentElement.scrollWidth,
                images: Array.from(document.images).map(i => i.complete ? i.naturalWidth : 0),
                summaries: document.querySelectorAll('.summary').length,
                firstSummaryTop: (document.querySelector('.summary') || {getBoundingClientRect: () => ({top: -1})})
                                 .getBoundingClientRect().top,
                text: document.body.innerText})""")
            if SHOTS:
                Path(SHOTS).mkdir(parents=True, exist_ok=True)
                page.screenshot(path=str(Path(SHOTS) / f"{name}-{media}-first.png"), full_page=False)
                page.screenshot(path=str(Path(SHOTS) / f"{name}-{media}-full.png"), full_page=True)
        finally:
            browser.close()
    return errors, info


@pytest.mark.browser
@pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium at /usr/bin/chromium")
@pytest.mark.parametrize("which", ["demo", "compare", "sweep"])
def test_report_fits_1366_px_and_loads_every_image(reports, which):
    errors, info = _render(reports[which], which)
    assert errors == []
    assert info["scrollWidth"] <= VIEWPORT["width"], f"{which}: the page is {info['scrollWidth']} px wide"
    assert info["images"] and all(w > 0 for w in info["images"])
    assert "What next" in info["text"]
    if which != "sweep":
        assert info["summaries"] >= 2  # a summary box per recipe
    # and on an A4 page (794 px at 96 dpi) with the print stylesheet
    errors, info = _render(reports[which], which, media="print", width=794)
    assert errors == [] and info["scrollWidth"] <= 794


def test_demo_report_summary_box_first_and_three_next_commands(reports):
    html = reports["demo"].read_text()
    sec = html[html.index("<section id='s0'>"):html.index("<section id='s1'>")]
    assert sec.index("class='summary'") < sec.index("class='figures'") < sec.index("<table>")
    outro = html[html.index("class='outro'"):]
    assert len(re.findall(r"<li>", outro)) == 3
    for cmd in ("nmmm run my_paint.toml", "nmmm compare hematite_paint my_paint.toml", "nmmm sweep my_paint.toml"):
        assert cmd in outro
    assert "nmmm run grey_metallic -o" in html  # the command that reproduces a recipe section
    assert "@media print" in html and "@page" in html


def test_demo_report_is_compressed(reports):
    """Images are re-encoded for the report: it is smaller than the image files it shows."""
    html = reports["demo"].read_text()
    folder = reports["demo"].parent
    pngs = sum(p.stat().st_size for p in folder.rglob("*.png"))
    assert len(html.encode()) < 0.6 * pngs


def test_compare_names_recipes_not_a_and_b(reports):
    html = reports["compare"].read_text()
    text = re.sub(r"<[^>]+>", " ", html[html.index("<body>"):])
    assert "L* A" not in text and "A: " not in text and "B: " not in text
    assert "Hematite paint (7 %): L*, a*, b*" in text and "ethylcellulose binder: L*, a*, b*" in text
    assert "illuminant A" in text and "First recipe: Hematite paint (7 %)" in text
    rows = reports["compare_result"]["rows"]  # the public rows keep their keys
    assert {"L_A", "L_B", "dE00"} <= set(rows[0])


def test_compare_folders_are_named_after_the_recipes(reports):
    cmp = reports["compare_result"]
    folders = [Path(f) for f in cmp["folders"]]
    assert [f.name for f in folders] == ["Hematite_paint_7", "Hematite_paint_7_ethylcellulose_binder"]
    assert all((f / "spectra.csv").is_file() and (f / "results.nc").is_file() for f in folders)
    assert not (reports["dir"] / "compare" / "A").exists() and not (reports["dir"] / "compare" / "B").exists()


def test_recipe_folders_tell_equal_names_apart():
    from nmmm.recipes.compare import recipe_folders

    assert recipe_folders("Hematite paint (7 %)", "hematite paint 7") == ("Hematite_paint_7_first",
                                                                          "hematite_paint_7_second")
    assert recipe_folders("", "***") == ("recipe_first", "recipe_second")
    assert recipe_folders("White", "Tint") == ("White", "Tint")


def test_compare_terminal_lines_use_the_recipe_names(reports, monkeypatch):
    """``nmmm compare`` prints the recipes by name; "A" is only ever illuminant A."""
    from click.testing import CliRunner

    import nmmm.recipes.compare as compare_module
    from nmmm.recipes import cli

    monkeypatch.setattr(compare_module, "compare_recipes", lambda *a, **k: reports["compare_result"])
    d = reports["dir"]
    r = CliRunner().invoke(cli.compare, [str(d / "epoxy.toml"), str(d / "ethylcellulose.toml"), "-i", "D65",
                                         "-i", "A", "-o", str(d / "compare"), "--no-progress"])
    assert r.exit_code == 0, r.output
    lines = r.output.splitlines()
    assert lines[0] == "first recipe: Hematite paint (7 %)"
    assert lines[1] == "second recipe: Hematite paint (7 %), ethylcellulose binder"
    geometry = reports["compare_result"]["rows"][0]["geometry"]
    assert any(ln.startswith(f"{geometry}, illuminant A: dE00 = ") for ln in lines), lines
    body = "\n".join(lines[2:])
    assert "(A:" not in body and "; B:" not in body
    assert body.count("(Hematite paint (7 %): L* ") == len(reports["compare_result"]["rows"])
    assert "Hematite_paint_7_ethylcellulose_binder" in r.output


def test_sweep_report_legends_in_words_and_opacity_explained(reports):
    html = reports["sweep"].read_text()
    assert "pigment volume fraction (1)" in html and "L* under D65" in html
    assert "dependent scattering" in html
    assert "hides its substrate" in html and "tint" in html  # the unchanged masstone explained
    # ... for the series where it holds (independent scattering), not for the one that changes
    # the differences it quotes, recomputed from the sweep's table with colour-science's CIEDE2000: independent
    # scattering leaves an opaque film's colour to K/S alone, which the concentration does not change (0.00)
    import colour

    df = reports["sweep_result"]["results"]

    def de(dep):
        rows = df[df["param:pigment.dependent_scattering"].astype(bool) == dep].sort_values("param:pigment.fraction")
        lab = rows[["L_D65", "a_D65", "b_D65"]].to_numpy(float)
        return float(colour.delta_E(lab[0], lab[-1], method="CIE 2000"))

    assert de(False) < 0.005 and de(True) > 0.1
    assert ("The masstone hardly changes from 0.05 to 0.1 volume fraction (ΔE00 under D65: "
            f"{de(False):.2f} with dependent scattering (Percus–Yevick packing): off; {de(True):.2f} with dependent "
            "scattering (Percus–Yevick packing): on)") in html
    assert html.count("hides its substrate") == 1  # said once, not once per series
    assert html.count("<h2>") == 0 and html.count("<h1>") == 1  # one section: its title is the page's
    assert "nmmm sweep " in html and "--vary pigment.fraction=0.05,0.1" in html


def test_sweep_plot_legend_entries_are_words_with_units(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import pandas as pd
    from matplotlib.figure import Figure

    from nmmm.recipes.sweep_report import plot_sweep

    w = [400.0, 500.0, 600.0]
    df = pd.DataFrame([{"param:pigment.fraction": f, "param:film.thickness_nm": t, "L_D65": 30 + 100 * f + t / 1e4,
                        "primary": "reflectance (substrate 0.8)", "wavelength_nm": w, "spectrum": [0.1, 0.2, 0.3]}
                       for f in (0.05, 0.1) for t in (10000.0, 20000.0, 40000.0)])
    legends = []
    original = Figure.savefig

    def spy(self, *a, **k):
        legends.extend(t.get_text() for ax in self.axes if ax.get_legend() for t in ax.get_legend().get_texts())
        return original(self, *a, **k)

    Figure.savefig = spy
    try:
        plot_sweep(df, tmp_path / "s.png")
    finally:
        Figure.savefig = original
    assert "film thickness = 20 µm" in legends
    assert "pigment volume fraction = 0.05 (5 %); film thickness = 10 µm" in legends
    assert not any("param:" in t or "=0.05" in t for t in legends)


def test_curve_styles_tell_twelve_curves_apart():
    from nmmm.recipes.figures import curve_styles

    styles = curve_styles(12)
    assert len({(s["color"], s["linestyle"]) for s in styles}) == 12


def test_missing_axis_labels_reads_the_figure():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from nmmm.recipes.figures import missing_axis_labels

    fig, (a1, a2, a3) = plt.subplots(1, 3)
    a1.plot([0, 1], [0, 1])
    a1.set_xlabel("wavelength (nm)")
    a2.plot([0, 1], [0, 1])
    a2.set(xlabel="wavelength (nm)", ylabel="transmittance")
    a3.imshow(np.zeros((4, 4)))
    a3.axis("off")
    miss = missing_axis_labels(fig)
    plt.close(fig)
    assert len(miss) == 2 and "no y label" in miss[0] and "'transmittance' has no unit" in miss[1]


def test_out_of_range_colours_are_marked():
    from nmmm.recipes.report import srgb_note

    assert "brighter than white (L* = 140)" in srgb_note([1.0, 1.0, 1.0], L=140.0)
    assert srgb_note([1.2, 0.4, -0.1], L=60.0) == "outside the sRGB gamut: shown clipped"
    assert srgb_note([0.5, 0.4, 0.3], L=60.0) == ""


def test_a_flake_swatch_brighter_than_white_is_marked_in_the_report(tmp_path):
    from nmmm.recipes.report import result_section, write_report
    from nmmm.recipes.run import compute

    raw = fast_raw("grey_metallic", step_nm=20.0)
    raw["viewing"]["aspecular_deg"] = [-15.0, 15.0, 45.0, 110.0]
    raw.pop("image", None)
    htmls = {}
    for tilt in (6.0, 12.0):  # well-aligned flakes glint brighter than white near the specular
        raw["effect"]["tilt_deg"] = tilt
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = compute(parse_recipe(raw), progress=False)
        Ls = {m["aspecular_deg"]: m["L"] for m in res.multiangle}
        htmls[tilt] = (Ls, write_report([result_section(res)], tmp_path / f"r{tilt:g}.html").read_text())
    Ls, html = htmls[6.0]
    assert Ls[-15.0] > 100 and Ls[15.0] > 100 and Ls[110.0] < 100
    assert html.count("brighter than white (L* = ") >= 2 and "L* above 100 at aspecular -15°, 15°" in html
    Ls, html = htmls[12.0]
    assert max(Ls.values()) < 100 and "brighter than white" not in html  # nothing to mark: no mark


@pytest.mark.parametrize("thickness_nm, expected", [(20.0, "0.02 µm"), (800_000.0, "800 µm"), (20_000.0, None)])
def test_pigmented_coat_thickness_outside_paint_range_warns_in_um(thickness_nm, expected):
    from nmmm.recipes.sanity import sanity_warnings

    raw = set_key(fast_raw("hematite_paint"), "film.thickness_nm", thickness_nm)
    msgs = sanity_warnings(parse_recipe(raw))
    if expected is None:
        assert msgs == []
    else:
        assert len(msgs) == 1 and expected in msgs[0] and "film.thickness_nm" in msgs[0]
    if thickness_nm == 20.0:
        assert "write film.thickness_nm = 20000" in msgs[0]


def test_run_warns_about_a_20_nm_paint_film():
    from nmmm.recipes.run import compute
    from nmmm.recipes.sanity import UnusualRecipeWarning

    raw = set_key(fast_raw("hematite_paint", step_nm=20.0), "film.thickness_nm", 20.0)
    with pytest.warns(UnusualRecipeWarning, match="0.02 µm pigmented coat"):
        compute(parse_recipe(raw), progress=False)


def test_unchanged_masstone_note():
    from nmmm.recipes.sanity import masstone_unchanged_note

    same = [[24.6, 18.8, 18.6], [24.6, 18.8, 18.6], [24.61, 18.8, 18.6]]
    assert "(ΔE00 = 0.01 under A)" in masstone_unchanged_note([0.05, 0.07, 0.10], same, 20.0, illuminant="A")
    note = masstone_unchanged_note([0.05, 0.07, 0.10], same, 20.0)
    assert "20 µm film hides its substrate" in note and "tint" in note and "over black" in note
    assert masstone_unchanged_note([0.05, 0.10], [[24.6, 18.8, 18.6], [30.0, 25.0, 20.0]]) == ""


def test_cauchy_coefficients_with_explicit_units():
    """B_um2 / C_um4 / B_nm2 / C_nm4 give the Cauchy formula written out by hand (λ in µm)."""
    from nmmm.errors import RecipeError
    from nmmm.recipes.run import build_materials

    A, B, C = 1.566, 0.00796, 0.00014
    w = np.array([400.0, 550.0, 700.0])
    by_hand = A + B / (w / 1000) ** 2 + C / (w / 1000) ** 4
    base = fast_raw("hematite_paint")
    for params in ({"A": A, "B": B, "C": C}, {"A": A, "B_um2": B, "C_um4": C}, {"A": A, "B_nm2": B * 1e6, "C_nm4": C * 1e12}):
        raw = set_key(base, "compounds.epoxy.params", params)
        n = build_materials(parse_recipe(raw), w)["epoxy"].n(w)
        np.testing.assert_allclose(n, by_hand, rtol=1e-12)
    with pytest.raises(RecipeError, match=r"compounds.epoxy.params: .*B is given twice"):
        build_materials(parse_recipe(set_key(base, "compounds.epoxy.params", {"A": A, "B": B, "B_um2": B})), w)


def test_ellipsometry_model_file_takes_explicit_units(tmp_path):
    from nmmm.ellipsometry.model import read_model

    text = """
name = "epoxy on silicon"
ambient = 1.0
[substrate]
n = 3.9
[[layers]]
name = "epoxy"
thickness_nm = 500
model = "cauchy"
A = 1.5
{b}
"""
    w = np.array([400.0, 700.0])
    ns = []
    for b in ("B = 0.004", "B_um2 = 0.004", "B_nm2 = {value = 4000, min = 0, max = 1e5}"):
        p = tmp_path / "m.toml"
        p.write_text(text.replace("{b}", b))
        m = read_model(p)
        stack = m.build(m.values)
        ns.append(stack.layers[0][0].n(w) if isinstance(stack.layers[0], tuple) else stack.layers[0].material.n(w))
    np.testing.assert_allclose(ns[1], ns[0], rtol=1e-12)
    np.testing.assert_allclose(ns[2], ns[0], rtol=1e-12)
    np.testing.assert_allclose(ns[0], 1.5 + 0.004 / (w / 1000) ** 2, rtol=1e-12)
    assert "epoxy.B_nm2" in read_model(p).values


def test_failed_compare_and_sweep_leave_no_output_folder(tmp_path, monkeypatch):
    """One CLI voice (issue 25 item 5): a bad recipe is one 'error:' line with exit status 2, and neither
    `nmmm compare` nor `nmmm sweep` leaves an empty output folder (or a lock file) behind; a comparison
    whose second run fails removes the folder it made."""
    from click.testing import CliRunner

    import nmmm.recipes.run as run_module
    from nmmm.errors import RecipeError
    from nmmm.recipes import cli
    from nmmm.recipes.compare import compare_recipes

    good = tmp_path / "good.toml"
    good.write_text(_dump_toml(fast_raw("hematite_paint", step_nm=20.0)))
    bad = tmp_path / "bad.toml"
    bad.write_text(_dump_toml(set_key(fast_raw("hematite_paint", step_nm=20.0), "film.thickness_nm", -5.0)))
    runner = CliRunner()
    for cmd, args in ((cli.compare, [str(good), str(bad), "-o", str(tmp_path / "cmp")]),
                      (cli.sweep, [str(bad), "--vary", "pigment.fraction=0.05,0.1", "--serial", "-o",
                                   str(tmp_path / "sw")])):
        r = runner.invoke(cmd, args + ["--no-progress"])
        assert r.exit_code == 2, r.output
        assert r.output.startswith("error: film.thickness_nm: must be a finite number > 0") and r.output.count("\n") == 1
    assert not (tmp_path / "cmp").exists() and not (tmp_path / "sw").exists()
    assert not (tmp_path / ".cmp.nmmm-lock").exists()

    calls = []
    real = run_module.run_recipe

    def second_fails(*a, **k):
        calls.append(1)
        if len(calls) == 2:
            raise RecipeError("the second run failed")
        return real(*a, **k)

    monkeypatch.setattr(run_module, "run_recipe", second_fails)
    with warnings.catch_warnings(), pytest.raises(RecipeError, match="second run failed"):
        warnings.simplefilter("ignore")
        compare_recipes(str(good), str(good), tmp_path / "cmp2", progress=False)
    assert not (tmp_path / "cmp2").exists() or list((tmp_path / "cmp2").iterdir())  # never empty


def test_k_axis_starts_at_zero_for_lossless_compounds(tmp_path, monkeypatch):
    """The n, k plot of a run: k is on a symlog axis that starts at 0 (no negative decades drawn below
    the k = 0 of lossless TiO2, mica and binder)."""
    import matplotlib.figure

    from nmmm.recipes.run import run_recipe

    seen = {}
    real = matplotlib.figure.Figure.savefig

    def record(fig, fname, *a, **k):
        seen[Path(str(fname)).name] = [ax.get_ylim() for ax in fig.axes]
        return real(fig, fname, *a, **k)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", record)
    p = tmp_path / "ip.toml"
    p.write_text(_dump_toml(fast_raw("interference_pigment", step_nm=20.0)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run_recipe(str(p), tmp_path / "out", progress=False, report=False)
    (n_lim, k_lim) = seen["nk.png"]
    assert k_lim[0] == 0.0 and k_lim[1] > 0.0 and n_lim[0] > 1.0
