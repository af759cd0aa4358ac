"""The real-paint-systems demo (issue 16 item 7): tint ladder, white's hiding, three-coat solid."""

import csv
import warnings

import numpy as np

from nmmm.demo.paint_systems import WHITE_PVCS, demo, rutile
from nmmm.recipes.figures import MissingAxisLabelWarning


def test_rutile_is_devore_1951():
    # the database's tabulation of DeVore (1951) (refractiveindex.info main/TiO2/Devore-o, -e), 450-700 nm
    from nmmm.materials import get, uniaxial_mean

    w = np.arange(450.0, 701.0, 50.0)
    ref = uniaxial_mean(get("main/TiO2/Devore-o"), get("main/TiO2/Devore-e")).nk(w)
    n = rutile().nk(w)
    assert np.max(np.abs(n - ref)) < 2e-3 and np.all(n.imag == 0)


def test_demo(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("error", MissingAxisLabelWarning)
        out = demo(tmp_path)
    assert set(out) >= {"title", "figures", "tables", "text"}
    assert len(out["figures"]) == 3
    for f in out["figures"]:
        assert (tmp_path / f.split("/")[-1]).stat().st_size > 1000
    tint = out["tables"]["Tint ladder (CIELAB, D65)"]
    L = [r["L"] for r in tint]
    assert [r["letdown (hematite:rutile)"] for r in tint] == ["masstone", "1:1", "1:4", "1:9"]
    assert all(a < b for a, b in zip(L, L[1:]))  # letting down with white lightens
    assert all(r["a"] > 5 for r in tint)  # and stays red
    white = out["tables"]["White paint hiding"]
    cr = [r["contrast ratio at 25 µm (1)"] for r in white]
    hid = [r["hiding thickness (µm)"] for r in white]
    assert [r["PVC (1)"] for r in white] == list(WHITE_PVCS)
    assert all(a < b for a, b in zip(cr, cr[1:]))  # contrast ratio rises with PVC
    assert all(a > b for a, b in zip(hid, hid[1:]))  # so the hiding thickness falls
    with open(tmp_path / "white_hiding.csv") as fh:
        assert len(list(csv.DictReader(fh))) == len(WHITE_PVCS)
    coats = {r["case"]: r for r in out["tables"]["Three-coat solid (CIELAB, D65)"]}
    sci = coats["full stack, adding-doubling, di:8"]["R at 650 nm (1)"]
    sce = coats["full stack, adding-doubling, de:8"]["R at 650 nm (1)"]
    # specular included - excluded = the clear coat's Fresnel reflectance at normal incidence, ((n-1)/(n+1))^2
    assert abs((sci - sce) - (0.52 / 2.52) ** 2) < 1e-3
