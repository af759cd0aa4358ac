"""Data files: plain CSV, J. A. Woollam ASCII (checked against pyElli's reader), Material output."""

import numpy as np
import pytest

from nmmm.ellipsometry.data import (EllipsometryData, read_csv, read_data, read_woollam, write_csv,
                                    write_material_csv)
from nmmm.errors import DataFileError, InvalidInputError

elli = pytest.importorskip("elli")

WL = np.array([400.0, 500.0, 600.0])
PSI = np.array([[20.5, 30.25, 40.125], [21.5, 31.25, 41.125]])  # angle x wavelength
DELTA = np.array([[100.5, 120.25, 140.125], [101.5, 121.25, 141.125]])
ANG = [65.0, 70.0]


def _wvase_text(unit="nm", tagged=False, scale=1.0):
    lines = ["My sample", "VASEmethod[EllipsometerType=4, Data Type=Psi/Delta]", unit]
    for j, a in enumerate(ANG):
        for i, w in enumerate(WL):
            fields = [f"{w * scale:.6f}", f"{a:.6f}", f"{PSI[j, i]:.6f}", f"{DELTA[j, i]:.6f}", "0.010000", "0.050000"]
            lines.append(("E\t" if tagged else "") + "\t".join(fields))
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("tagged", [False, True])
def test_woollam_matches_pyelli_reader(tmp_path, tagged):
    """WVASE tabular and CompleteEASE ('E' tagged) exports: same values as elli.importer.woollam."""
    from elli.importer.woollam import read_woollam_psi_delta

    p = tmp_path / "sample.dat"
    p.write_text(_wvase_text(tagged=tagged))
    ref = read_woollam_psi_delta(str(p))
    d = read_woollam(p)
    assert len(d) == len(ref) == 6
    for a, w, psi, delta in zip(d.angle_deg, d.wavelength_nm, d.psi_deg, d.delta_deg):
        row = ref.loc[(a, w)]
        assert row["Ψ"] == pytest.approx(psi) and row["Δ"] == pytest.approx(delta)
    np.testing.assert_allclose(d.sigma_psi_deg, 0.01)
    np.testing.assert_allclose(d.sigma_delta_deg, 0.05)
    assert d.name == "My sample"


def test_woollam_units_and_other_tags(tmp_path):
    p = tmp_path / "ev.dat"
    text = _wvase_text(unit="eV", tagged=True, scale=1.0)
    # replace wavelengths by photon energies (eV) and add a transmission line that must be skipped
    for w in WL:
        text = text.replace(f"E\t{w:.6f}", f"E\t{1239.841984 / w:.6f}")
    text += "T\t2.000000\t0.000000\t0.500000\t0.000000\t0.010000\t0.010000\n"
    p.write_text(text)
    d = read_woollam(p)
    np.testing.assert_allclose(np.unique(d.wavelength_nm), WL, rtol=1e-6)
    assert d.metadata["skipped_lines"] == {"T": 1}
    with pytest.raises(DataFileError, match="TRIG"):
        q = tmp_path / "trig.dat"
        q.write_text("sample\nnm TRIG\n400.0\t65.0\t0.3\t0.5\t0.01\t0.01\n")
        read_woollam(q)
    with pytest.raises(DataFileError, match="unit"):
        q = tmp_path / "nounit.dat"
        q.write_text("sample\n400.0\t65.0\t20.0\t100.0\t0.01\t0.01\n")
        read_woollam(q)


def test_csv_round_trip_and_aliases(tmp_path):
    d = EllipsometryData(np.repeat(WL, 2), np.tile(ANG, 3), PSI.T.ravel(), DELTA.T.ravel(), 0.02, 0.1, name="x")
    back = read_csv(write_csv(d, tmp_path / "d.csv"))
    for attr in ("wavelength_nm", "angle_deg", "psi_deg", "delta_deg", "sigma_psi_deg", "sigma_delta_deg"):
        np.testing.assert_allclose(getattr(back, attr), getattr(d, attr))
    p = tmp_path / "alias.csv"
    p.write_text("# comment\nWavelength (nm), AOI, Psi, Delta\n500, 70, 30, 120\n600, 70, 31, 121\n")
    d2 = read_data(p)
    assert not d2.has_sigma and d2.angle_deg.tolist() == [70.0, 70.0]
    p.write_text("energy_ev,angle_deg,psi_deg,delta_deg\n2.0,70,30,120\n")
    assert read_csv(p).wavelength_nm[0] == pytest.approx(619.920992)


def test_csv_errors(tmp_path):
    p = tmp_path / "bad.csv"
    p.write_text("wavelength_nm,angle_deg,psi_deg\n500,70,30\n")
    with pytest.raises(DataFileError, match="missing column.*delta_deg"):
        read_csv(p)
    p.write_text("wavelength_nm,angle_deg,psi_deg,delta_deg\n500,70,95,120\n")
    with pytest.raises(InvalidInputError, match=r"psi_deg must lie in \[0, 90\]"):
        read_csv(p)
    p.write_text("wavelength_nm,angle_deg,psi_deg,delta_deg\n# note\n500,70,30,120\n600,70,-1,120\n")
    with pytest.raises(InvalidInputError, match=r"data row 3: psi_deg must lie in \[0, 90\].*got -1"):
        read_csv(p)
    p.write_text("wavelength_nm,angle_deg,psi_deg,delta_deg\n500,70,abc,120\n")
    with pytest.raises(DataFileError, match="row 2"):
        read_csv(p)
    p.write_text("wavelength_nm,angle_deg,psi_deg,delta_deg,sigma_psi_deg\n500,70,30,120,0.01\n")
    with pytest.raises(DataFileError, match="no sigma_delta_deg"):
        read_csv(p)
    with pytest.raises(DataFileError, match="not found"):
        read_csv(tmp_path / "missing.csv")
    with pytest.raises(InvalidInputError, match="angle"):
        EllipsometryData([500.0], 95.0, 30.0, 100.0)


def test_material_file_loads_with_nmmm_materials(tmp_path):
    """The fitted constants file is a Material file of nmmm.materials.read_csv."""
    from nmmm.materials import read_csv as read_material

    w = np.array([400.0, 500.0, 700.0])
    nk = np.array([1.6 + 0.01j, 1.58 + 0.0j, 1.56 + 0.002j])
    p = write_material_csv(tmp_path / "m.csv", w[::-1], nk[::-1], name="epoxy fit", reference="test",
                           sigma_n=[1e-3] * 3, sigma_k=[2e-3] * 3)
    m = read_material(p)
    np.testing.assert_allclose(m.nk(w), nk)
    assert m.name == "epoxy fit"
