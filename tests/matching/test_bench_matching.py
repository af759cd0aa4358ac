"""benchmarks/bench_matching.py runs and both fits match (issue 17 Speed); times are measured there, not asserted."""

import importlib.util
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_matching.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_matching", BENCH)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("mode", ["colorimetric", "spectral"])
def test_both_fits_reach_the_target_and_counts_are_reported(bench, mode):
    out = bench.benchmark(repeat=1, step_nm=20.0, mode=mode)
    for who in ("nmmm", "plain", "plain-stopped"):
        med = out["median"][who]
        assert med["de00"] < 0.3 and med["evaluations"] > 0 and med["wall_s"] > 0, (who, med)
        assert "ad" in out["last"][who]["by_solver"]
    assert "km" not in out["last"]["plain"]["by_solver"]  # the plain fit calls the adding-doubling model only
    assert set(out["ratio"]) == set(out["ratio_stopped"]) == {"wall_s", "evaluations", "ad_evaluations", "de00"}
    assert out["last"]["plain"]["values"] == pytest.approx(list(bench.TRUE), rel=0.05)  # same target, same bounds


def test_command_line_prints_the_table(bench, capsys):
    bench.main(["--repeat", "1", "--mode", "spectral"])
    said = capsys.readouterr().out
    assert "nmmm match_recipe" in said and "plain least_squares" in said and "ratio plain / nmmm" in said
    assert "ratio stopped / nmmm" in said and "AD evals" in said


def test_four_colourant_case_runs(bench):
    out = bench.benchmark(repeat=1, step_nm=20.0, mode="spectral", colourants=4)
    assert out["case"].startswith("4-colourant") and len(out["true"]) == 4
    for who in ("nmmm", "plain", "plain-stopped"):
        assert out["median"][who]["de00"] < 0.3, who
        assert len(out["last"][who]["values"]) == 4
