"""`nmmm demo --no-progress` reaches the package hooks that draw progress bars."""

import pytest
from click.testing import CliRunner

from nmmm.demo import runner as demo_mod
from nmmm.demo import sections


def _hooks(monkeypatch):
    calls = {}

    def with_bar(output_dir, progress: bool = True):
        from tqdm import tqdm

        calls["with_bar"] = progress
        for _ in tqdm(range(3), desc="fake hook bar", disable=not progress):
            pass
        return {"title": "with bar", "figures": [], "tables": {}, "text": "ok"}

    def without_bar(output_dir):
        calls["without_bar"] = True
        return {"title": "without bar", "figures": [], "tables": {}, "text": "ok"}

    monkeypatch.setattr(demo_mod, "_test_with_bar", with_bar, raising=False)
    monkeypatch.setattr(demo_mod, "_test_without_bar", without_bar, raising=False)
    monkeypatch.setattr(sections, "RECIPE_SECTIONS", ())
    monkeypatch.setattr(sections, "HOOKS", (("With a bar", "nmmm.demo.runner:_test_with_bar"),
                                            ("Without a bar", "nmmm.demo.runner:_test_without_bar")))
    return calls


@pytest.mark.parametrize("progress", [False, True])
def test_demo_passes_its_progress_flag_to_hooks_that_take_it(tmp_path, monkeypatch, capfd, progress):
    calls = _hooks(monkeypatch)
    report, failed, skipped = demo_mod.run_demo(tmp_path, progress=progress)
    assert failed == [] and skipped == []
    assert calls == {"with_bar": progress, "without_bar": True}  # the old signature still works
    err = capfd.readouterr().err
    assert ("fake hook bar" in err) is progress


def test_cli_no_progress_hides_hook_bars(tmp_path, monkeypatch):
    from nmmm.demo import cli

    calls = _hooks(monkeypatch)
    r = CliRunner().invoke(cli.demo, ["-o", str(tmp_path), "--no-progress"])
    assert r.exit_code == 0, r.output
    assert calls["with_bar"] is False
    assert "fake hook bar" not in r.output + (r.stderr if r.stderr_bytes is not None else "")


def test_package_hooks_that_draw_bars_take_progress():
    from nmmm.demo.hematite import hematite_demo

    assert demo_mod._accepts_progress(hematite_demo)
    assert not demo_mod._accepts_progress(lambda output_dir: None)
