"""The hematite paint demo (seed example 2)."""

import pytest


@pytest.mark.slow
def test_hematite_demo(tmp_path):
    from nmmm.demo.hematite import hematite_demo

    out = hematite_demo(tmp_path)
    assert all(p.endswith(".png") for p in out["figures"])
    L = [r["L_ad"] for r in out["tables"]["grain_size"]]
    # the painters' rule: beyond ~250 nm, bigger grains look darker
    assert L[2] > L[3] > L[4] > L[5]
