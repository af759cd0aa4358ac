"""The gold-ruby demo hook and its colour criterion (the plate model: tests/layers/test_thick_plate.py)."""

import numpy as np
import pytest

from nmmm.demo.gold_ruby import gold_ruby_demo, reads_red_purple, thickness_ranges


def test_red_purple_criterion_and_ranges():
    lab = np.array([[50, 40, -10], [50, 40, 40], [5, 40, 0], [60, 10, 0]])
    assert reads_red_purple(lab).tolist() == [True, False, False, False]
    assert thickness_ranges(np.arange(6.0), [0, 1, 1, 0, 1, 1]) == [(1.0, 2.0), (4.0, 5.0)]


@pytest.mark.slow  # ~15 s, mostly importing colour-science and matplotlib
def test_gold_ruby_demo(tmp_path):
    out = gold_ruby_demo(tmp_path)
    assert set(out) == {"title", "figures", "tables", "text"}
    for p in out["figures"]:
        assert (tmp_path / p.split("/")[-1]).stat().st_size > 1000
    s = out["tables"]["summary"]
    assert 520 <= s["plasmon_peak_nm"] <= 535
    assert s["L_5mm_D65"] < 1.0  # a 5 mm plate is nearly black at p = 0.0005
    assert "mm" in s["red_purple_D65_mm"] and "none" not in s["red_purple_D65_mm"]
    rods = out["tables"]["gold_rods"]
    assert [r["peak_long_nm"] for r in rods] == sorted(r["peak_long_nm"] for r in rods)
