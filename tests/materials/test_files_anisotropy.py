"""User files and uniaxial crystals."""

import numpy as np
import pytest

import nmmm
from nmmm.materials import (DiagonalTensorMaterial, get, read_csv, read_yaml, uniaxial, uniaxial_mean,
                            write_csv, Constant)


def test_csv_units_from_header(tmp_path):
    p = tmp_path / "x.csv"
    p.write_text("# reference: test data\nwavelength_um,n,k\n0.4,1.5,0.0\n0.8,1.4,0.1\n")
    m = read_csv(p)
    assert m.range_nm == (400.0, 800.0)
    assert m.nk(600.0) == pytest.approx(1.45 + 0.05j)  # linear interpolation
    assert m.reference == "test data"


def test_csv_round_trip(tmp_path):
    au = get("main/Au/Johnson")
    w = np.linspace(400, 800, 41)
    m = read_csv(write_csv(au, tmp_path / "au.csv", w))
    np.testing.assert_allclose(m.nk(w), au.nk(w), rtol=1e-7)


@pytest.mark.parametrize("body, match", [
    ("wavelength,n,k\n400,1.5,0\n", "unit"),
    ("wavelength_nm,n,k\n400,1.5,0\n500,1.5,-0.1\n", "line 3"),
    ("wavelength_nm,n,k\n400,1.5,0\n500,1.5,0\n450,1.5,0\n", "line 4"),
    ("wavelength_nm,n,k\n400,1.5,0\n500,abc,0\n", "line 3"),
    ("wavelength_nm,n,k\n400,1.5,0\n500,nan,0\n", "line 3"),
])
def test_csv_errors_name_the_row(tmp_path, body, match):
    p = tmp_path / "bad.csv"
    p.write_text(body)
    with pytest.raises(nmmm.DataFileError, match=match):
        read_csv(p)


def test_missing_file_names_the_path(tmp_path):
    with pytest.raises(nmmm.DataFileError, match="nope.csv"):
        read_csv(tmp_path / "nope.csv")


def test_yaml_formula_and_tabulated(tmp_path):
    # Malitson's Sellmeier coefficients in refractiveindex.info's formula 1 layout
    p = tmp_path / "silica.yml"
    p.write_text("""REFERENCES: "I. H. Malitson, JOSA 55, 1205 (1965)"
DATA:
  - type: formula 1
    wavelength_range: 0.21 6.7
    coefficients: 0 0.6961663 0.0684043 0.4079426 0.1162414 0.8974794 9.896161
  - type: tabulated k
    data: |
        0.3 0.0
        0.9 0.002
""")
    m = read_yaml(p)
    assert m.range_nm == pytest.approx((300.0, 900.0))
    assert m.nk(587.5618).real == pytest.approx(1.458464, abs=2e-6)
    assert m.nk(600.0).imag == pytest.approx(0.001)


@pytest.mark.parametrize("body, match", [
    ("        0.4 1.5 0.0\n        0.5 nan 0.1\n", "row 2 has a NaN"),
    ("        0.4 1.5 0.0\n        0.5 1.5 -0.1\n", "k < 0 at tabulated nk row 2"),
    ("        0.4 1.5 0.0\n        0.6 1.5 0.0\n        0.5 1.5 0.0\n", "row 3"),
])
def test_yaml_table_errors_name_the_row(tmp_path, body, match):
    p = tmp_path / "bad.yml"
    p.write_text("DATA:\n  - type: tabulated nk\n    data: |\n" + body)
    with pytest.raises(nmmm.DataFileError, match=match):
        read_yaml(p)
    p.write_text("DATA:\n  - type: formula 99\n    wavelength_range: 0.3 1\n    coefficients: 1 2\n")
    with pytest.raises(nmmm.DataFileError, match=r"bad\.yml.*formula 99"):
        read_yaml(p)


def test_uniaxial_mean_of_hematite():
    o, e = get("main/Fe2O3/Querry-o"), get("main/Fe2O3/Querry-e")
    h = uniaxial_mean(o, e)
    w = np.array([450.0, 550.0, 650.0])
    np.testing.assert_allclose(h.eps(w), (2 * o.eps(w) + e.eps(w)) / 3)
    assert h.range_nm == (max(o.range_nm[0], e.range_nm[0]), min(o.range_nm[1], e.range_nm[1]))
    crystal = uniaxial(o, e)
    assert crystal.eps_tensor(w).shape == (3, 3)
    np.testing.assert_allclose(crystal.eps_tensor(w)[:, 2], e.eps(w))


def test_diagonal_tensor_mean_is_trace_over_three():
    t = DiagonalTensorMaterial(Constant(eps=2.0), Constant(eps=3.0), Constant(eps=-10 + 1j))
    assert t.mean().eps(500.0) == pytest.approx((2 + 3 - 10 + 1j) / 3)


def test_uniaxial_mean_accepts_keys_and_constants_and_rejects_the_rest():
    o, e = get("main/Fe2O3/Querry-o"), get("main/Fe2O3/Querry-e")
    by_key = uniaxial_mean("main/Fe2O3/Querry-o", "main/Fe2O3/Querry-e")
    np.testing.assert_allclose(by_key.eps(550.0), (2 * o.eps(550.0) + e.eps(550.0)) / 3)
    assert uniaxial_mean(2.0, 2.2 + 0.1j).eps(500.0) == pytest.approx((2 * 4.0 + (2.2 + 0.1j) ** 2) / 3)
    with pytest.raises(nmmm.InvalidInputError, match="extraordinary"):
        uniaxial_mean(o, None)
    with pytest.raises(nmmm.InvalidInputError, match="k < 0"):
        uniaxial_mean(1.5 - 0.1j, e)
