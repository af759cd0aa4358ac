"""The physical-fidelity demo (issue 24): hematite colour sensitivity and the gold size series."""

import warnings

import numpy as np

from nmmm.demo.sensitivity import demo
from nmmm.recipes.figures import MissingAxisLabelWarning


def test_demo_tables_and_sources(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("error", MissingAxisLabelWarning)
        out = demo(tmp_path)
    assert set(out) >= {"title", "figures", "tables", "text"}
    assert (tmp_path / "gold_size_series.png").stat().st_size > 1000
    sens = out["tables"]["Hematite: CIELAB and ΔE00 per modelling choice"]
    assert [r["choice"] for r in sens] == ["baseline", "optical constants", "optical constants", "shape equivalence",
                                           "shape equivalence", "packing"]
    assert sens[0]["masstone dE00"] == 0 and sens[0]["1:4 tint dE00"] == 0
    # the (2o + e)/3 mean lies between the ordinary and extraordinary rays in lightness and chroma
    base, o, e = sens[0], sens[1], sens[2]
    for key in ("masstone L*", "masstone C*ab"):
        assert min(o[key], e[key]) <= base[key] <= max(o[key], e[key])
    assert all(r["masstone a*"] > 10 for r in sens)  # every variant stays a red
    assert all(r["1:4 tint L*"] > r["masstone L*"] for r in sens)  # the rutile tint is lighter
    gold = out["tables"]["Gold colloids in water: size series against Haiss et al. 2007"]
    five = {r["size damping"]: r for r in gold if r["diameter (nm)"] == 5.0}
    # Haiss et al. 2007 eq. 11 (measured): bulk gold reads 5 nm as ~37 nm, damped as ~8 nm
    assert five["none (bulk)"]["diameter read by eq. 11 (nm)"] > 30
    assert five["A = 1"]["diameter read by eq. 11 (nm)"] < 9
    text = " ".join(out["text"])
    assert "Haiss" in text and "Querry" in text and "not" in text  # sources, and what is not shipped
    assert np.isfinite([r["masstone L*"] for r in sens]).all()
