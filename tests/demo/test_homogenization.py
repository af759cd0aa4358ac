"""The demo hook: runs, writes its files, and its FFT values respect the bounds it plots."""

import pytest


@pytest.mark.slow
def test_demo_writes_figures_and_respects_bounds(tmp_path):
    from pathlib import Path

    from nmmm.demo.homogenization import demo

    out = demo(tmp_path)
    assert set(out) >= {"title", "figures", "tables", "text"}
    for f in out["figures"]:
        assert Path(f).exists()
    rows = out["tables"]["hematite"]
    assert all(r["inside_hs"] for r in rows)
    # dilute hematite: the FFT lies within a few % of Maxwell Garnett (Maxwell Garnett 1904)
    for r in rows:
        assert abs(r["eps_fft"] / r["eps_mg"] - 1) < 0.05
