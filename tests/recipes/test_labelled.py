"""Labelled results (issue 23 item 2): ``results.nc`` of ``nmmm run`` and the sweep cube open with
``xr.open_dataset`` with the dimensions, structured spectrum coordinates and CF units of
:mod:`nmmm.recipes.labelled`; ``_repr_html_`` of the main result objects returns HTML with an
embedded PNG (what Jupyter shows)."""

import base64
import re

import numpy as np
import pytest
import xarray as xr

from nmmm.recipes.labelled import spectrum_coordinates, sweep_to_xarray, units_of_key, write_sweep_cube
from nmmm.recipes.run import run_recipe

from .conftest import fast_raw

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _embedded_png(html: str) -> bytes:
    m = re.search(r'<img [^>]*src="data:image/png;base64,([A-Za-z0-9+/=]+)"', html)
    assert m, "no embedded PNG"
    data = base64.b64decode(m.group(1))
    assert data.startswith(PNG_MAGIC) and len(data) > 2000
    return data


@pytest.fixture(scope="module")
def hematite_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("hematite")
    return run_recipe(fast_raw("hematite_paint", step_nm=20.0), out, progress=False, report=False), out


def test_results_nc_of_a_paint_film(hematite_run):
    res, out = hematite_run
    with xr.open_dataset(out / "results.nc", engine="h5netcdf") as ds:
        assert ds["wavelength"].attrs["units"] == "nm"
        assert ds["wavelength"].attrs["standard_name"] == "radiation_wavelength"
        np.testing.assert_array_equal(ds["wavelength"].values, res.wavelength_nm)
        assert ds["spectra"].dims == ("spectrum", "wavelength") and ds["spectra"].attrs["units"] == "1"
        for c in ("kind", "substrate", "geometry"):
            assert ds[c].dims == ("spectrum",)
        primary = ds.attrs["primary_spectrum"]
        assert ds["kind"].values[primary] == "reflectance"
        assert ds["geometry"].values[primary].startswith("0°/d")
        # the spectra are the run's, structured: select by kind and substrate, not by free text
        np.testing.assert_array_equal(ds["spectra"].values[primary], res.spectra[res.primary])
        assert ds["lab"].dims == ("spectrum", "illuminant", "cielab")
        assert list(ds["cielab"].values) == ["L*", "a*", "b*"]
        L = float(ds["lab"].sel(illuminant="D65", cielab="L*").values[primary])
        assert L == pytest.approx(res.scalars["L_D65"], abs=1e-12)
        assert ds["L_D65"].attrs["units"] == "1" and float(ds["L_D65"]) == pytest.approx(res.scalars["L_D65"])
        for name in ds.variables:  # CF: every numeric variable states its units (strings need none)
            v = ds[name]
            if v.dtype.kind in "fc" and name not in ("thickness",):
                assert "units" in v.attrs, name
        assert ds.attrs["Conventions"].startswith("CF-")
    assert res.to_xarray()["spectra"].shape == (len(res.spectra), res.wavelength_nm.size)


def test_results_nc_of_a_flake_paint_has_the_aspecular_dimension(grey_metallic_run):
    _, res, out = grey_metallic_run
    with xr.open_dataset(out / "results.nc", engine="h5netcdf") as ds:
        assert ds["aspecular_angle"].attrs["units"] == "degree"
        assert list(ds["aspecular_angle"].values) == [r["aspecular_deg"] for r in res.multiangle]
        assert ds["reflectance_factor"].dims == ("aspecular_angle", "wavelength")
        rf = ds["reflectance_factor"].sel(aspecular_angle=45.0).values
        np.testing.assert_array_equal(rf, res.spectra["reflectance factor (aspecular 45°)"])
        assert ds["multiangle_lab"].dims == ("aspecular_angle", "cielab")


def test_spectrum_coordinates_from_labels():
    assert spectrum_coordinates("reflectance (black substrate)")["substrate"] == "black"
    c = spectrum_coordinates("transmittance ruby_glass (1 mm)")
    assert (c["kind"], c["compound_seen"], c["thickness_mm"]) == ("transmittance", "ruby_glass", 1.0)
    assert spectrum_coordinates("reflectance (45° incidence)")["geometry"] == "45° incidence, specular"
    assert spectrum_coordinates("something new")["kind"] == "something new"
    assert units_of_key("pigment.diameter_nm") == "nm" and units_of_key("pigment.fraction") == "1"
    assert units_of_key("viewing.illumination_deg") == "degree" and units_of_key("pigment.shape") is None


def _fake_sweep_df(fracs, diams, wl):
    import pandas as pd

    rows = []
    for f in fracs:
        for d in diams:
            rows.append({"param:pigment.fraction": f, "param:pigment.diameter_nm": d, "L_D65": 100 * f + d / 10,
                         "primary": "reflectance (substrate 0.8)", "wavelength_nm": list(wl),
                         "spectrum": list(f * wl / wl.max()), "physics_s": 0.1, "point_id": f"{f}-{d}"})
    return pd.DataFrame(rows[:-1])  # the last point not finished yet


def test_sweep_cube_netcdf_and_zarr(tmp_path):
    wl = np.arange(400.0, 701.0, 50.0)
    fracs, diams = [0.05, 0.07, 0.1], [100.0, 250.0]
    df = _fake_sweep_df(fracs, diams, wl)
    varies = [("pigment.fraction", fracs), ("pigment.diameter_nm", diams)]
    files = write_sweep_cube(df, varies, tmp_path, zarr_min_points=6)
    with xr.open_dataset(files["netcdf"], engine="h5netcdf") as ds:
        assert ds["spectrum"].dims == ("pigment.fraction", "pigment.diameter_nm", "wavelength")
        assert ds["pigment.diameter_nm"].attrs["units"] == "nm" and ds["pigment.fraction"].attrs["units"] == "1"
        assert ds["wavelength"].attrs["units"] == "nm"
        assert float(ds["L_D65"].sel({"pigment.fraction": 0.07, "pigment.diameter_nm": 250.0})) == pytest.approx(32.0)
        assert np.isnan(ds["L_D65"].values[-1, -1])  # not computed: NaN, not a wrong value
        np.testing.assert_allclose(ds["spectrum"].values[2, 0], 0.1 * wl / 700.0)
        assert ds["spectrum"].attrs["kind"] == "reflectance" and ds["spectrum"].attrs["substrate"] == "0.8"
    pytest.importorskip("zarr")
    with xr.open_dataset(files["zarr"], engine="zarr") as z:
        assert z["spectrum"].shape == (3, 2, wl.size)
        np.testing.assert_allclose(z["L_D65"].values, sweep_to_xarray(df, varies)["L_D65"].values)


def test_sweep_writes_the_cube(tmp_path):
    from nmmm.recipes.sweep import sweep

    raw = fast_raw("gold_ruby_glass", step_nm=40.0)
    sweep(raw, ["levels.0.inclusions.0.fraction=0.0002,0.0005"], tmp_path, serial=True, progress=False, plots=False)
    with xr.open_dataset(tmp_path / "results.nc", engine="h5netcdf") as ds:
        assert ds["spectrum"].dims == ("levels.0.inclusions.0.fraction", "wavelength")
        assert ds["levels.0.inclusions.0.fraction"].attrs["units"] == "1"
        assert ds["spectrum"].attrs["kind"] == "transmittance"
        assert not np.isnan(ds["spectrum"].values).any()


def test_repr_html_embeds_a_plot(hematite_run):
    from nmmm.layers.mie_scattering import mie
    from nmmm.materials import Cauchy, get

    res, _ = hematite_run
    html = res._repr_html_()
    _embedded_png(html)
    assert "L*" in html and res.recipe.name in html
    html = get("main/Fe2O3/Querry-o")._repr_html_()
    _embedded_png(html)
    assert "210–45454.5 nm" in html.replace("&ndash;", "–") and "Querry" in html
    _embedded_png(Cauchy(1.5, 4000.0)._repr_html_() if _cauchy_ok() else get("main/SiO2/Malitson")._repr_html_())
    w = np.linspace(400, 700, 31)
    html = mie(2.9 + 0.3j, 1.5, 250.0, w)._repr_html_()
    _embedded_png(html)
    assert "Q_ext" in html and "400–700 nm" in html
    assert "<img" not in mie(1.5 + 0.01j, 1.33, 100.0, 550.0)._repr_html_()  # one point: a table


def _cauchy_ok():
    import inspect

    from nmmm.materials import Cauchy

    try:
        inspect.signature(Cauchy).bind(1.5, 4000.0)
        return True
    except TypeError:
        return False
