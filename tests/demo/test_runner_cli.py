"""``nmmm demo``: each section guarded, failures told in the terminal (title, last line, hint), exit 1."""

import re

from click.testing import CliRunner

from nmmm.demo import cli, sections


def test_demo_guards_each_section_and_exits_nonzero_on_failure(tmp_path, monkeypatch):
    monkeypatch.setattr(sections, "RECIPE_SECTIONS", ("interference_pigment",))
    monkeypatch.setattr(sections, "HOOKS", (("A broken package", "json:loads"),  # TypeError on a Path
                                            ("A package not written yet", "nmmm.no_such_package.examples:demo")))
    r = CliRunner().invoke(cli.demo, ["-o", str(tmp_path), "--no-progress"])
    assert r.exit_code == 1
    assert "1 section(s) failed: A broken package" in r.output
    assert "not available: A package not written yet" in r.output
    html = (tmp_path / "report.html").read_text()
    assert "class='error'" in html and "TypeError" in html
    assert "Interference pigment" in html and "data:image/png;base64," in html


def test_demo_quick_only_succeeds(tmp_path):
    r = CliRunner().invoke(cli.demo, ["-o", str(tmp_path), "--quick", "--only", "interference", "--no-progress"])
    assert r.exit_code == 0, r.output
    assert re.search(r"report: .*report\.html", r.output)


# -- failures told in the terminal (issue 14 item 4) -------------------------------------------


def _needs_h5py(output_dir):
    raise ModuleNotFoundError("No module named 'h5py'", name="h5py")


def _needs_libllvm(output_dir):
    from nmmm.appearance.render.mitsuba_paint import MitsubaUnavailableError

    raise MitsubaUnavailableError("Mitsuba's llvm_ad_spectral variant needs libLLVM >= 17 (found: none)")


def _needs_chromium(output_dir):
    try:
        raise FileNotFoundError("BrowserType.launch: Executable doesn't exist at /usr/bin/chromium")
    except FileNotFoundError as exc:
        raise RuntimeError("cannot take the report's screenshot") from exc


def _needs_pillow(output_dir):
    import importlib

    importlib.import_module("PIL.no_such_submodule_of_pillow")


def test_each_failed_section_is_told_with_its_last_line_and_what_to_install(tmp_path, monkeypatch):
    from nmmm.cli import cli as top

    here = __name__
    monkeypatch.setattr(sections, "RECIPE_SECTIONS", ())
    monkeypatch.setattr(sections, "HOOKS", (("Needs h5py", f"{here}:_needs_h5py"),
                                            ("Needs libLLVM", f"{here}:_needs_libllvm"),
                                            ("Needs chromium", f"{here}:_needs_chromium"),
                                            ("A broken package", "json:loads")))
    r = CliRunner().invoke(top, ["demo", "-o", str(tmp_path), "--no-progress"])
    assert r.exit_code == 1, r.output
    out = r.output
    blocks = {b.splitlines()[0]: b for b in out.split("\n\n") if b.startswith("FAILED")}
    assert set(blocks) == {"FAILED  Needs h5py", "FAILED  Needs libLLVM", "FAILED  Needs chromium",
                           "FAILED  A broken package"}
    assert "error: ModuleNotFoundError: No module named 'h5py'" in blocks["FAILED  Needs h5py"]
    assert "hint:  pip install h5py" in blocks["FAILED  Needs h5py"]
    assert "needs libLLVM >= 17 (found: none)" in blocks["FAILED  Needs libLLVM"]
    assert "hint:  apt-get install libllvm19" in blocks["FAILED  Needs libLLVM"]
    assert "error: RuntimeError: cannot take the report's screenshot" in blocks["FAILED  Needs chromium"]
    assert "hint:  apt-get install chromium" in blocks["FAILED  Needs chromium"]
    assert "error: TypeError: " in blocks["FAILED  A broken package"]  # json.loads of a Path
    assert "4 section(s) failed: Needs h5py; Needs libLLVM; Needs chromium; A broken package" in out
    assert "Traceback" not in out  # the traceback is in the report's error box, not the terminal
    html = (tmp_path / "report.html").read_text()
    assert html.count("class='error'") >= 4 and "Traceback" in html


def test_failure_hint_names_the_install_command():
    from nmmm.demo.runner import failure_hint

    assert failure_hint(ModuleNotFoundError("No module named 'skimage'", name="skimage")) == "pip install scikit-image"
    assert failure_hint(ImportError("h5netcdf: No module named 'h5py'")) == "pip install h5py"
    try:
        _needs_pillow(None)
    except ImportError as exc:
        assert failure_hint(exc) == "pip install pillow"
    try:
        _needs_chromium(None)
    except RuntimeError as exc:
        assert failure_hint(exc) == "apt-get install chromium"
    try:
        _needs_libllvm(None)
    except ImportError as exc:
        assert failure_hint(exc) == "apt-get install libllvm19"
    assert failure_hint(ValueError("a bad value")) == ""
    assert failure_hint(ModuleNotFoundError("No module named 'nmmm.nothing'", name="nmmm.nothing")) == ""


def test_scale_tours_stay_under_their_scale_commands():
    """``nmmm ema gold-ruby`` and the other tours live in nmmm.demo.cli but keep their old command lines."""
    from nmmm.cli import cli as top

    for group, sub in (("ema", "gold-ruby"), ("layers", "hematite"), ("homogenize", "demo"), ("appearance", "demo")):
        r = CliRunner().invoke(top, [group, "--help"])
        assert r.exit_code == 0 and f"  {sub} " in r.output, (group, r.output)
        r = CliRunner().invoke(top, [group, sub, "--help"])
        assert r.exit_code == 0 and "Usage:" in r.output, (group, sub, r.output)
