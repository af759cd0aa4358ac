"""Issue 21: ellipsometry files and fits that do not lie.

- a Woollam file with a NaN row or a line cut off mid-way (``E 660 70 26.600 1``, once read as
  Δ = 1°) is never silently accepted: the rows are left out with a warning naming the lines, and
  ``strict=True`` / ``--strict`` refuses the file;
- a 1.2 µm Cauchy film on Si fitted from a start 30 nm and 0.05 in A off: the local fit alone stops in the
  neighbouring interference order (reduced MSE in the hundreds, which the CLI now warns about and
  ``--strict`` turns into exit 2); the default thickness pre-scan finds the order (MSE ~ 1).
"""

import warnings

import numpy as np
import pytest
from click.testing import CliRunner

from nmmm.ellipsometry.cli import ellipsometry
from nmmm.ellipsometry.data import read_data
from nmmm.errors import DataFileError

HEADER = "test film\nVASEmethod[EllipsometerType=4]\nnm\n"
GOOD = [f"E {w} 70 {26 + 0.01 * i:.3f} {120 + 0.5 * i:.3f} 0.01 0.05" for i, w in enumerate(range(600, 700, 20))]


def _write(tmp_path, lines, name="w.dat", newline=True):
    p = tmp_path / name
    p.write_text(HEADER + "\n".join(lines) + ("\n" if newline else ""))
    return p


def test_clean_woollam_file_has_a_clean_scan(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        d = read_data(_write(tmp_path, GOOD))
    assert len(d) == 5 and d.metadata["scan"].clean
    assert "no problems found" in d.metadata["scan"].summary()


@pytest.mark.parametrize("bad, what, line", [
    ("E 650 70 nan nan 0.01 0.05", "NaN", 9),
    ("E 650 70 26.600 1", "truncated", 9),
    ("E 650 70 26.6 NaN 0.01 0.05", "NaN", 9),
    ("E 650 70 inf 120 0.01 0.05", "NaN", 9),
])
def test_nan_and_truncated_woollam_rows_are_named_never_silent(tmp_path, bad, what, line):
    p = _write(tmp_path, GOOD + [bad], newline=False)
    with pytest.warns(UserWarning, match=rf"{what}.*line {line}"):
        d = read_data(p)
    assert len(d) == 5 and 650.0 not in d.wavelength_nm  # the truncated Delta = 1 deg is not data
    assert not d.metadata["scan"].clean
    with pytest.raises(DataFileError, match=rf"{what}.*line {line}.*strict"):
        read_data(p, strict=True)


GOOD4 = [ln.rsplit(" ", 2)[0] for ln in GOOD]  # no sigma columns: a cut last line keeps 4 numbers


def test_four_column_last_line_cut_mid_number_is_named(tmp_path):
    """``E 700 70 26.600 1`` with no final newline in a file without sigma columns: as many numbers
    as the other lines, but Delta '1' is the start of a number cut off."""
    p = _write(tmp_path, GOOD4 + ["E 700 70 26.600 1"], newline=False)
    with pytest.warns(UserWarning, match="last line 9 left out.*newline"):
        d = read_data(p)
    assert len(d) == 5 and 700.0 not in d.wavelength_nm
    assert d.metadata["scan"].dropped_cut == (9,)
    with pytest.raises(DataFileError, match="last line 9.*strict"):
        read_data(p, strict=True)
    # the same line ended by a newline was written whole: read as data, no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(read_data(_write(tmp_path, GOOD4 + ["E 700 70 26.600 1"], name="nl.dat"))) == 6
        # an unterminated last line whose numbers are as long as the others' is whole
        assert len(read_data(_write(tmp_path, GOOD4 + ["E 700 70 26.600 121.000"], name="ok.dat",
                                    newline=False))) == 6


def test_nan_row_first_is_not_taken_for_a_header(tmp_path):
    p = _write(tmp_path, ["E 580 70 nan nan 0.01 0.05"] + GOOD)
    with pytest.warns(UserWarning, match="NaN.*line 4"):
        d = read_data(p)
    assert len(d) == 5


def test_repeated_and_unsorted_points_warn_and_strict_refuses(tmp_path):
    p = _write(tmp_path, [GOOD[2], GOOD[0], GOOD[4], GOOD[0]])
    with pytest.warns(UserWarning, match="1 repeated.*out of order at angle"):
        read_data(p)
    with pytest.raises(DataFileError, match="repeated"):
        read_data(p, strict=True)


def test_csv_empty_cell_and_short_last_row(tmp_path):
    p = tmp_path / "d.csv"
    p.write_text("wavelength_nm,angle_deg,psi_deg,delta_deg\n400,70,20,120\n410,70,,121\n420,70,21,122\n430,70,2\n")
    with pytest.warns(UserWarning, match="NaN.*line 3.*truncated.*line 5"):
        d = read_data(p)
    assert list(d.wavelength_nm) == [400.0, 420.0]
    with pytest.raises(DataFileError):
        read_data(p, strict=True)
    p.write_bytes(b"\xff\xfe\x00w\x00a\x00v")
    with pytest.raises(DataFileError, match="not UTF-8"):
        read_data(p)


MODEL = """
name = "Cauchy film on Si"
[substrate]
material = "main/Si/Green-2008"
[[layers]]
name = "film"
thickness_nm = {value = %s, min = 1000, max = 1400}
model = "cauchy"
A = {value = %s, min = 1.3, max = 1.9}
B_um2 = {value = 0.006, min = -0.05, max = 0.1}
"""


@pytest.fixture(scope="module")
def thick_film(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("thick")
    truth, start = tmp / "truth.toml", tmp / "start.toml"
    truth.write_text(MODEL % (1200.0, 1.55))
    start.write_text(MODEL % (1230.0, 1.60))
    data = tmp / "data.csv"
    r = CliRunner().invoke(ellipsometry, ["simulate", "--model", str(truth), "--wavelengths", "300:1000:5",
                                          "--angles", "65,75", "--sigma-psi", "0.02", "--sigma-delta", "0.05",
                                          "--seed", "5", "-o", str(data)])
    assert r.exit_code == 0, r.output
    return tmp, data, start


def _mse(output):
    import re

    return float(re.search(r"MSE = ([0-9.eE+-]+)", output).group(1))


def test_local_fit_alone_is_flagged_and_strict_exits_nonzero(thick_film):
    tmp, data, start = thick_film
    r = CliRunner().invoke(ellipsometry, ["fit", str(data), "--model", str(start), "-o", str(tmp / "a"),
                                          "--no-plot", "--no-prescan"])
    assert r.exit_code == 0, r.output
    assert _mse(r.output) > 10 and "reduced MSE" in r.output and "--strict" in r.output
    r = CliRunner().invoke(ellipsometry, ["fit", str(data), "--model", str(start), "-o", str(tmp / "b"),
                                          "--no-plot", "--no-prescan", "--strict"])
    assert r.exit_code != 0 and "above 10" in str(r.exception)


def test_prescan_finds_the_interference_order(thick_film):
    tmp, data, start = thick_film
    r = CliRunner().invoke(ellipsometry, ["fit", str(data), "--model", str(start), "-o", str(tmp / "c"),
                                          "--no-plot", "--strict"])
    assert r.exit_code == 0, r.output
    assert "pre-scan film.thickness_nm" in r.output
    assert _mse(r.output) < 2
    import re

    t = float(re.search(r"film\.thickness_nm\s*=?\s*([0-9.]+)", r.output).group(1))
    assert t == pytest.approx(1200.0, abs=1.0)


def test_prescan_reports_its_real_sampling_and_warns_when_capped():
    """The pre-scan line gives the sampling the grid really has (not the 8 asked when max_points
    caps the grid), warns below 2 per interference period, and the coherent-layer warning of
    Stack.rt (thick layers of the grid) does not leak out of the scan."""
    import re
    import tomllib

    from nmmm.ellipsometry.data import EllipsometryData
    from nmmm.ellipsometry.fit_start import thickness_prescan
    from nmmm.ellipsometry.model import EllipsometryModel

    wide = MODEL.replace("max = 1400", "max = 4000")  # n d up to ~6400 nm: Stack.rt warns on a 50 nm grid
    truth = EllipsometryModel.from_dict(tomllib.loads(wide % (1200.0, 1.55)))
    start = EllipsometryModel.from_dict(tomllib.loads(wide % (1230.0, 1.60)))
    data = EllipsometryData.from_model(truth.build(), np.arange(300.0, 1001.0, 50.0), [70.0], 0.02, 0.05,
                                       noise_seed=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _, lines = thickness_prescan(start, data)
    first = lines[0]
    per = float(re.search(r"([0-9.]+) per interference period", first).group(1))
    assert per == pytest.approx(8, rel=0.05)
    with pytest.warns(UserWarning, match=r"only 0\.[0-9]+ times \(< 2\)") as rec:
        _, lines = thickness_prescan(start, data, max_points=4)
    assert not any("is coherent but" in str(r.message) for r in rec)
    per_capped = float(re.search(r"([0-9.]+) per interference period", lines[0]).group(1))
    assert per_capped < 2 and "8 per" not in lines[0]
    # same range, 3 intervals instead of N - 1: the sampling scales with the number of intervals
    n_full = int(re.search(r"(\d+) thicknesses", first).group(1))
    assert per_capped == pytest.approx(per * 3 / (n_full - 1), rel=0.02)
