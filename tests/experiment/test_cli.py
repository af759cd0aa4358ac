"""``nmmm experiment`` commands: stats, export, serve's refusal of bad input (the demo hook: tests/demo)."""

from __future__ import annotations

import csv
import json

import pytest

from nmmm.cli import main
from nmmm.experiment.simulation import simulate_responses, synthetic_pairs
from nmmm.experiment.pairs import load_pairs


@pytest.fixture(scope="module")
def simulated_db(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("sim")
    ps = load_pairs(synthetic_pairs(tmp, n_pairs=5, size_px=24, repetitions=2))
    return simulate_responses(ps, tmp / "r.sqlite", n_observers=12, mean_pc=0.7, rho=0.05, seed=1)


def test_stats_and_export_commands(simulated_db, tmp_path, capsys):
    assert main(["experiment", "stats", str(simulated_db), "--plot", str(tmp_path / "p.png"), "--delta", "0.1"]) == 0
    out = capsys.readouterr().out
    assert "12 observer(s)" in out and "Pooled (cluster-robust" in out and "TOST" in out
    assert (tmp_path / "p.png").stat().st_size > 10_000
    assert main(["experiment", "stats", str(simulated_db), "--json", "--pooling", "beta-binomial"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["pooled"]["method"] == "beta-binomial" and len(data["observers"]) == 12
    assert data["pooled"]["pc"] > 0.55   # simulated observers pick the photograph 70 % of the time
    assert main(["experiment", "export", str(simulated_db), "-o", str(tmp_path / "out.csv")]) == 0
    rows = list(csv.DictReader(open(tmp_path / "out.csv")))
    assert len(rows) == 12 * 10
    assert set(rows[0]) >= {"participant_id", "pair_id", "photo_position", "chosen_position", "correct", "rt_ms"}
    assert all(r["correct"] == str(int(r["photo_position"] == r["chosen_position"])) for r in rows)


def test_commands_refuse_bad_input(tmp_path, capsys, simulated_db):
    (tmp_path / "pairs.toml").write_text("[[pair]]\nrendered = 'a.png'\nphoto = 'b.png'\n")
    assert main(["experiment", "serve", str(tmp_path / "pairs.toml"), "--db", str(tmp_path / "x.sqlite")]) == 2
    err = capsys.readouterr().err
    assert "rendered image" in err and "not found" in err
    assert not (tmp_path / "x.sqlite").exists()   # nothing created for a bad experiment
    assert main(["experiment", "stats", str(tmp_path / "missing.sqlite")]) == 2
    assert "not found" in capsys.readouterr().err
    (tmp_path / "junk.sqlite").write_text("not a database" * 100)
    assert main(["experiment", "export", str(tmp_path / "junk.sqlite"), "-o", str(tmp_path / "o.csv")]) == 2
    assert "not an nmmm response database" in capsys.readouterr().err
    assert not (tmp_path / "o.csv").exists()   # nothing written for a bad database
    assert main(["experiment", "export", str(simulated_db), "-o", str(tmp_path / "no" / "o.csv")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert main(["experiment", "stats", str(simulated_db), "--plot", str(tmp_path / "no" / "p.png")]) == 2
    assert "does not exist" in capsys.readouterr().err
