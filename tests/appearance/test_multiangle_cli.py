"""The ``nmmm appearance`` commands (the demo hook: tests/demo/test_appearance.py)."""

import json

import numpy as np
from click.testing import CliRunner

from nmmm.appearance.cli import appearance


def test_multiangle_command_json():
    r = CliRunner().invoke(appearance, ["multiangle", "--paint", "solid", "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.output)
    assert [a["aspecular_deg"] for a in d["angles"]] == [-15.0, 15.0, 25.0, 45.0, 75.0, 110.0]
    assert abs(d["flop_index"]) < 1.0


def test_table_and_sparkle_commands(tmp_path):
    out = tmp_path / "t.csv"
    r = CliRunner().invoke(appearance, ["table", "--paint", "solid", "--out", str(out), "--n-theta-h", "4",
                                        "--n-theta-d", "4", "--n-phi-d", "2", "--step-nm", "100"])
    assert r.exit_code == 0, r.output
    assert out.exists()
    img = np.full((64, 64), 0.2)
    img[30:33, 30:33] = 2.0
    np.save(tmp_path / "img.npy", img)
    r = CliRunner().invoke(appearance, ["sparkle", str(tmp_path / "img.npy"), "--pixel-size-um", "10",
                                        "--encoding", "linear"])
    assert r.exit_code == 0, r.output
    assert json.loads(r.output)["n_sparkles"] == 1


def test_commands_refuse_bad_files(tmp_path, capsys):
    from nmmm.cli import main

    (tmp_path / "bad.png").write_text("not an image")
    assert main(["appearance", "sparkle", str(tmp_path / "bad.png"), "--pixel-size-um", "10"]) == 2
    assert "cannot read the image" in capsys.readouterr().err
    assert main(["appearance", "table", "--paint", "solid", "--out", str(tmp_path / "no" / "t.nc")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert main(["appearance", "table", "--paint", "solid", "--out", str(tmp_path / "t.txt")]) == 2
    assert "use .nc or .csv" in capsys.readouterr().err
