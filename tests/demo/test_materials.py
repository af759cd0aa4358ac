"""The materials tour: the seed's compounds plotted and tabulated."""

import numpy as np
import pytest


def _malitson(w_nm):
    """Fused silica, Malitson, JOSA 55, 1205 (1965), eq. (1) with his published coefficients."""
    l2 = (np.asarray(w_nm) / 1000.0) ** 2
    B, C = (0.6961663, 0.4079426, 0.8974794), (0.0684043, 0.1162414, 9.896161)
    return np.sqrt(1 + sum(b * l2 / (l2 - c * c) for b, c in zip(B, C)))


def test_demo_hook(tmp_path):
    from nmmm.demo.materials import demo

    s = demo(tmp_path)
    assert set(s) >= {"title", "figures", "tables", "text"}
    for f in s["figures"]:
        assert (tmp_path / str(f).split("/")[-1]).stat().st_size > 10_000
    rows = {r["compound"]: r for r in s["tables"]["compounds"]}
    assert rows["silica"]["n_550nm"] == pytest.approx(_malitson(550.0), abs=1e-4)  # rounded to 4 decimals
    assert rows["silica"]["k_550nm"] == 0
