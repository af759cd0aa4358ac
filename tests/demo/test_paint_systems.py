"""The real-paint-systems demo (issue 16 item 7): tint ladder, white's hiding, three-coat solid."""

import csv
import warnings

import numpy as np

from nmmm.demo.paint_systems import WHITE_PVCS, demo, rutile
from nmmm.recipes.figures import MissingAxisLabelWarning


def test_rutile_is_measured_over_the_grid():
    # measured n and k of Siefke et al. 2016 (refractiveindex.info main/TiO2/Siefke) over 380-780 nm,
    # not DeVore's Sellmeier (fitted from 430 nm) extrapolated with k = 0: no out-of-range wavelengths
    from nmmm.materials import get

    w = np.arange(380.0, 781.0, 10.0)
    n = rutile().nk(w)
    assert np.array_equal(n, get("main/TiO2/Siefke").nk(w))
    assert rutile().range_nm[0] <= 380 and rutile().range_nm[1] >= 780
    assert n.imag[0] > 1e-3 and np.all(n.imag[w <= 410] > 0)  # absorbs towards the band edge
    assert np.all(np.diff(n.real) < 0)  # normal dispersion, no steep rise at 410 nm


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
    assert all("spreading rate (m²/L of dry film)" in r for r in white)
    with open(tmp_path / "white_hiding.csv") as fh:
        assert len(list(csv.DictReader(fh))) == len(WHITE_PVCS)
    coats = {r["case"]: r for r in out["tables"]["Three-coat solid (CIELAB, D65)"]}
    sci = coats["full stack, adding-doubling, di:8"]["R at 650 nm (1)"]
    sce = coats["full stack, adding-doubling, de:8"]["R at 650 nm (1)"]
    # specular included - excluded = the clear coat's Fresnel reflectance at normal incidence, ((n-1)/(n+1))^2
    assert abs((sci - sce) - (0.52 / 2.52) ** 2) < 1e-3


def test_white_contrast_against_pvc_is_not_saturated():
    # the contrast ratio against PVC is drawn at a thickness thin enough to show crowding: at 10 um
    # every PVC above 15 % gave CR > 0.97 and the two curves were one
    from nmmm.demo.paint_systems import PVC_SERIES, PVC_SERIES_UM, _white

    _, _, series = _white(np.arange(400.0, 701.0, 50.0), rutile())
    indep, crowd = np.asarray(series[False]), np.asarray(series[True])
    assert PVC_SERIES_UM <= 3.0 and indep.max() < 0.95
    assert np.all(np.diff(indep) > 0)
    high = np.asarray(PVC_SERIES) >= 0.2
    assert np.all(indep[high] - crowd[high] > 0.03)  # crowding lowers the scattering per pigment


def test_three_coat_grains_are_lognormal(monkeypatch):
    # monodisperse spheres leave Mie ripples: the basecoat and primer pigments carry a size spread
    import nmmm.layers.pigment_mixture as pm
    from nmmm.demo.hematite import hematite
    from nmmm.demo.paint_systems import _three_coat

    seen, component = [], pm.Component
    monkeypatch.setattr(pm, "Component", lambda *a, **k: seen.append(component(*a, **k)) or seen[-1])
    _three_coat(np.arange(400.0, 701.0, 100.0), hematite(), rutile())
    assert [c.name for c in seen] == ["hematite", "rutile", "black"]
    assert all(c.distribution.diameter_nm.size > 1 and np.ptp(c.distribution.diameter_nm) > 0 for c in seen)
