"""``nmmm render plate OUTPUT``: the forms of OUTPUT a user types (issue 14: ``nmmm render plate
out/`` rendered for 15 s and then died with ``ValueError: unknown file extension``)."""

from __future__ import annotations

import pytest

from nmmm.cli import main

SMALL = ["--width", "32", "--height", "24", "--cells", "40", "30"]


@pytest.mark.parametrize("given,written", [
    ("out/", "out/plate"),               # a folder: plate.* inside it
    ("out/p.png", "out/p"),              # a file name with the suffix of one of the outputs
    ("out/deep/er/p.exr", "out/deep/er/p"),  # missing parents are created
    ("p", "p"),                          # a plain stem
])
def test_render_plate_output_forms(given, written, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    if given.endswith("/"):
        (tmp_path / given).mkdir()
    assert main(["render", "plate", given, *SMALL]) == 0, capsys.readouterr().err
    for suffix in (".exr", ".png"):
        assert (tmp_path / f"{written}{suffix}").is_file(), sorted(p.name for p in tmp_path.rglob("*"))
    assert not list(tmp_path.rglob("*.png.png")) and not list(tmp_path.rglob(".png"))


def test_render_plate_folder_that_does_not_exist_yet(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["render", "plate", "new/", *SMALL]) == 0
    assert (tmp_path / "new" / "plate.png").is_file() and (tmp_path / "new" / "plate.exr").is_file()
