"""The 2AFC validation demo on simulated observers."""

from nmmm.demo.experiment import demo
from nmmm.experiment.stats import critical_count


def test_demo_hook(tmp_path):
    summary = demo(tmp_path)
    assert set(summary) >= {"title", "figures", "tables", "text"}
    assert all((tmp_path / "experiment_2afc.png").exists() for _ in summary["figures"])
    table = summary["tables"]["experiment_summary"]
    assert table["observers"] == 40 and table["trials per observer"] == 20
    assert table["critical count (one-sided, alpha 0.05)"] == critical_count(20) == 15
    assert (tmp_path / "experiment_responses.csv").exists()
