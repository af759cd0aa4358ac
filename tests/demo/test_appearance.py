"""The appearance tour: multi-angle colour, colour travel, BRDFs, sparkle, BRDF table."""

import pytest


@pytest.mark.slow
def test_demo_hook(tmp_path):
    from nmmm.demo.appearance import demo

    r = demo(tmp_path)
    assert set(r) == {"title", "figures", "tables", "text"}
    assert all((tmp_path / p).exists() or __import__("os").path.exists(p) for p in r["figures"])
    assert (tmp_path / "grey_metallic_brdf_table.nc").exists()
    assert "flop index" in r["text"]
