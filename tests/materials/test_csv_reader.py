"""materials.read_csv on pandas' reader (issue 23 item 5): the same materials as an independent
numpy.loadtxt of the same files, the same clean errors, and what the standard reader adds
(quoted cells, trailing comments, spaces in the header)."""

import numpy as np
import pytest

from nmmm.errors import DataFileError
from nmmm.materials.files import read_csv


def _write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


@pytest.mark.parametrize("seed", range(6))
def test_values_equal_an_independent_loadtxt(tmp_path, seed):
    rng = np.random.default_rng(seed)
    w = np.sort(rng.choice(np.arange(300, 2500), size=int(rng.integers(2, 300)), replace=False)).astype(float)
    n = rng.uniform(0.05, 5.0, w.size)
    k = rng.uniform(0.0, 8.0, w.size)
    unit, scale = (("wavelength_um", 1e-3), ("wavelength (nm)", 1.0), ("wl[µm]", 1e-3))[seed % 3]
    body = "\n".join(f"{a * scale:.9g}, {b:.9g},{c:.9g}" for a, b, c in zip(w, n, k))
    p = _write(tmp_path, "m.csv", f"# name: random {seed}\n# reference: generated\n{unit},n,k\n\n{body}\n")
    ref = np.loadtxt(p, delimiter=",", comments="#", skiprows=3)
    m = read_csv(p)
    assert m.name == f"random {seed}" and m.reference == "generated"
    np.testing.assert_allclose(m.nk(ref[:, 0] / scale), ref[:, 1] + 1j * ref[:, 2], rtol=1e-12)
    assert m.range_nm == pytest.approx((ref[0, 0] / scale, ref[-1, 0] / scale))


def test_standard_csv_quoting_trailing_comments_and_two_columns(tmp_path):
    p = _write(tmp_path, "q.csv", 'wavelength_nm,"n","k"\n"400",1.5,0.1  # measured\n# a note\n500,1.6,0.2\n')
    assert read_csv(p).nk(450.0) == pytest.approx(1.55 + 0.15j)
    p = _write(tmp_path, "nk.csv", "λ (nm), n\n400, 1.5\n500, 1.7\n")
    assert read_csv(p).nk(500.0) == pytest.approx(1.7)


@pytest.mark.parametrize("text, match", [
    ("", "empty file"),
    ("# only\n# comments\n", "empty file"),
    ("wavelength_nm,n,k\n400,1.5,0\n", "at least two data rows"),
    ("wavelength_nm,n,k\n400,1.5\n500,1.5,0\n", "line 2 has 2 values, expected 3"),
    ("wavelength_nm,n,k\n400,1.5,0\n500,x,0\n", r"line 3 \('500,x,0'\) is not numeric"),
    ("wavelength_nm,n,k\n400,1.5,0\n500,inf,0\n", "n is not finite at line 3"),
    ("wavelength_nm,n,k\n" + ",".join(["1"] * 70) + "\n", "more than 64 values"),
    ("wavelength_nm,n,k\n\"400,1.5,0\n500,1.5,0\n", "not numeric|unclosed quote"),
    ("wave_nm,n,k\n400,1.5,0\n500,1.5,0\n", "must declare the wavelength unit"),
    ("wavelength_mm,n,k\n400,1.5,0\n500,1.5,0\n", "must declare the wavelength unit"),
    ("wavelength_nm,k,n\n400,1.5,0\n500,1.5,0\n", "must be named 'n' and 'k'"),
])
def test_clean_errors(tmp_path, text, match):
    with pytest.raises(DataFileError, match=match):
        read_csv(_write(tmp_path, "bad.csv", text))


def test_no_regular_expressions_left_in_the_reader():
    import nmmm.materials.files as files

    assert not hasattr(files, "re")


def test_uncertainty_columns_are_read_and_checked(tmp_path):
    """The CSV nmmm ellipsometry writes (wavelength_nm,n,k,sigma_n,sigma_k) reads back with its uncertainties;
    a negative uncertainty or an unknown fourth column is refused, never dropped."""
    p = tmp_path / "m.csv"
    p.write_text("wavelength_nm,n,k,sigma_n,sigma_k\n400,1.5,0.01,0.002,0.001\n500,1.49,0.0,0.003,0.0005\n")
    m = read_csv(p)
    np.testing.assert_array_equal(m.uncertainty["sigma_n"], [0.002, 0.003])
    np.testing.assert_array_equal(m.uncertainty["sigma_k"], [0.001, 0.0005])
    np.testing.assert_allclose(m.nk([400.0, 500.0]), [1.5 + 0.01j, 1.49])
    p.write_text("wavelength_nm,n,k,sigma_n\n400,1.5,0.01,-0.002\n500,1.49,0.0,0.003\n")
    with pytest.raises(DataFileError, match=r"sigma_n must be a finite standard uncertainty >= 0; got -0.002 at line 2"):
        read_csv(p)
    p.write_text("wavelength_nm,n,k,T\n400,1.5,0.01,0.9\n500,1.49,0.0,0.9\n")
    with pytest.raises(DataFileError, match=r"column 4 \('T'\) is not one nmmm reads"):
        read_csv(p)
