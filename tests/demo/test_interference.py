"""The interference-pigment demo (seed example 4)."""

from nmmm.demo.interference import demo


def test_demo(tmp_path):
    out = demo(tmp_path)
    assert set(out) >= {"title", "figures", "tables", "text"}
    for f in out["figures"]:
        assert (tmp_path / f.split("/")[-1]).stat().st_size > 1000
