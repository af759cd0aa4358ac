"""Argyll .ti3 (CGATS with SPEC_<nm> fields, percent) and CxF3 MultiAngle (several BRDFAngles in one
ColorSpecification) read and written (issue 17 item 1)."""

from pathlib import Path

import numpy as np
import pytest

from nmmm.errors import DataFileError
from nmmm.matching import MeasuredSpectra, cxf_geometries, read_cgats, read_cxf, read_measured, write_cxf
from nmmm.matching.measured_files import canonical_geometry

# the layout Argyll's chartread writes (CTI3, KEYWORD declarations, quoted keyword values, SPEC_ fields in
# percent); 3 bands at 10 nm keep it short; the values are hand-made
TI3 = """CTI3

DESCRIPTOR "Argyll Calibration Target chart information 3"
ORIGINATOR "Argyll chartread"
CREATED "Wed Dec 02 10:00:00 2026"
KEYWORD "DEVICE_CLASS"
DEVICE_CLASS "OUTPUT"
KEYWORD "COLOR_REP"
COLOR_REP "RGB_XYZ"
KEYWORD "SPECTRAL_BANDS"
SPECTRAL_BANDS "3"
KEYWORD "SPECTRAL_START_NM"
SPECTRAL_START_NM "400.000000"
KEYWORD "SPECTRAL_END_NM"
SPECTRAL_END_NM "420.000000"
KEYWORD "SAMPLE_LOC"
NUMBER_OF_FIELDS 11
BEGIN_DATA_FORMAT
SAMPLE_ID SAMPLE_LOC RGB_R RGB_G RGB_B XYZ_X XYZ_Y XYZ_Z SPEC_400 SPEC_410 SPEC_420
END_DATA_FORMAT

NUMBER_OF_SETS 2
BEGIN_DATA
1 "A1" 100.00 100.00 100.00 88.10 91.20 76.50 85.20 86.70 87.90
2 "A2" 0.00 0.00 0.00 0.39 0.41 0.36 0.61 0.58 0.55
END_DATA
"""


def _write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_argyll_ti3_spec_fields_read_as_percent(tmp_path):
    p = _write(tmp_path, "chart.ti3", TI3)
    s = read_measured(p)  # .ti3 goes to the CGATS reader
    np.testing.assert_array_equal(s.wavelength_nm, [400.0, 410.0, 420.0])
    np.testing.assert_allclose(s.reflectance, [[0.852, 0.867, 0.879], [0.0061, 0.0058, 0.0055]], rtol=1e-12)
    assert s.names == ("1", "2")
    # a dark-only chart is still percent (the format's unit), not factors near 0.6
    dark = TI3.replace('NUMBER_OF_SETS 2', 'NUMBER_OF_SETS 1').replace(
        '1 "A1" 100.00 100.00 100.00 88.10 91.20 76.50 85.20 86.70 87.90\n', "")
    with pytest.warns(UserWarning, match=r"read as percent \(the CTI3 format's unit.*an almost black sample"):
        assert read_cgats(_write(tmp_path, "dark.ti3", dark)).reflectance[0, 0] == pytest.approx(0.0061)
    # SPECTRAL_NORM, where a file states it, wins
    fac = TI3.replace("NUMBER_OF_FIELDS", 'KEYWORD "SPECTRAL_NORM"\nSPECTRAL_NORM "1"\nNUMBER_OF_FIELDS').replace(
        "85.20 86.70 87.90", "0.852 0.867 0.879").replace("0.61 0.58 0.55", "0.0061 0.0058 0.0055")
    assert read_cgats(_write(tmp_path, "fac.ti3", fac)).reflectance[0, 1] == pytest.approx(0.867)


def test_ti3_holding_factors_is_said_not_silently_divided(tmp_path):
    """A CTI3 file without SPECTRAL_NORM whose SPEC_ values are factors (0-1, written by another tool):
    percent is the format's unit, so it is read as percent, but said (before: silently an almost black
    sample, 100× too dark); unit='fraction' reads it as written."""
    fac = TI3.replace("85.20 86.70 87.90", "0.852 0.867 0.879").replace("0.61 0.58 0.55", "0.0061 0.0058 0.0055")
    p = _write(tmp_path, "factors.ti3", fac)
    with pytest.warns(UserWarning, match=r"no value exceeds 1.5 \(the largest is 0.879 %\).*unit='fraction'"):
        read_cgats(p)
    np.testing.assert_allclose(read_cgats(p, unit="fraction").reflectance[0], [0.852, 0.867, 0.879])
    declared = fac.replace("NUMBER_OF_FIELDS", 'KEYWORD "SPECTRAL_NORM"\nSPECTRAL_NORM "100.000000"\nNUMBER_OF_FIELDS')
    with pytest.warns(UserWarning, match=r"read as percent \(SPECTRAL_NORM 100.000000\)"):
        read_cgats(_write(tmp_path, "declared.ti3", declared))


def test_ti3_header_disagreeing_with_its_fields_is_an_error(tmp_path):
    lost = TI3.replace("SPEC_420\n", "\n").replace(" 87.90\n", "\n").replace(" 0.55\n", "\n").replace(
        "NUMBER_OF_FIELDS 11", "NUMBER_OF_FIELDS 10")
    with pytest.raises(DataFileError, match="SPECTRAL_BANDS 3 but the fields give 2.*SPECTRAL_END_NM 420.000000 but"):
        read_cgats(_write(tmp_path, "lost.ti3", lost))


def test_ti3_without_spectra_says_so(tmp_path):
    xyz = TI3.replace(" SPEC_400 SPEC_410 SPEC_420", "").replace(" 85.20 86.70 87.90", "").replace(
        " 0.61 0.58 0.55", "").replace("NUMBER_OF_FIELDS 11", "NUMBER_OF_FIELDS 8")
    with pytest.raises(DataFileError, match="no spectral fields"):
        read_cgats(_write(tmp_path, "xyz.ti3", xyz))


ASPEC = ["45as-15", "45as15", "45as25", "45as45", "45as75", "45as110"]  # an MA98-style set


def _multi(w):
    return [MeasuredSpectra(w, np.stack([np.linspace(0.05, 0.6, w.size) / (k + 1), np.full(w.size, 0.8 - 0.1 * k)]),
                            ("silver", "white"), g) for k, g in enumerate(ASPEC)]


def test_cxf_multi_angle_written_as_one_multiangle_specification_and_read_back(tmp_path):
    w = np.arange(400.0, 701.0, 10.0)
    sets = _multi(w)
    p = write_cxf(tmp_path / "ma.cxf", sets)
    text = p.read_text()
    assert text.count("<cc:ColorSpecification ") == 1 and text.count("<cc:BRDFAngle ") == 6
    assert 'Notation="45as-15"' in text and 'Name="45as110"' in text
    assert cxf_geometries(p) == ASPEC
    with pytest.raises(DataFileError, match="6 geometries"):
        read_cxf(p)
    for k, g in enumerate(ASPEC):
        s = read_cxf(p, geometry=g)
        assert s.geometry == g and s.names == ("silver", "white")
        np.testing.assert_array_equal(s.wavelength_nm, w)
        np.testing.assert_allclose(s.reflectance, sets[k].reflectance, atol=5e-7)
    assert read_cxf(p, geometry="45 as 25").geometry == "45as25"  # spelt loosely: canonical_geometry
    assert canonical_geometry("45°as-15°") == "45as-15"


def _several_brdf_angles(names=('Name="45as15"', 'Name="45as45"')):
    a, b = names
    return ('<?xml version="1.0" encoding="UTF-8"?><cc:CxF xmlns:cc="http://colorexchangeformat.com/CxF3-core">'
            '<cc:Resources><cc:ObjectCollection><cc:Object ObjectType="Standard" Name="panel" Id="1"><cc:ColorValues>'
            f'<cc:ReflectanceSpectrum ColorSpecification="CS1" {a}>0.30 0.31 0.32</cc:ReflectanceSpectrum>'
            f'<cc:ReflectanceSpectrum ColorSpecification="CS1" {b}>0.10 0.11 0.12</cc:ReflectanceSpectrum>'
            '</cc:ColorValues></cc:Object></cc:ObjectCollection><cc:ColorSpecificationCollection>'
            '<cc:ColorSpecification Id="CS1"><cc:MeasurementSpec><cc:MeasurementType>Spectrum_Reflectance'
            '</cc:MeasurementType><cc:GeometryChoice><cc:MultiAngle>'
            '<cc:BRDFAngle Notation="45as15"><cc:IlluminationAngle>45</cc:IlluminationAngle><cc:Aspecular>15'
            '</cc:Aspecular></cc:BRDFAngle>'
            '<cc:BRDFAngle Notation="45as45"><cc:IlluminationAngle>45</cc:IlluminationAngle><cc:Aspecular>45'
            '</cc:Aspecular></cc:BRDFAngle>'
            '</cc:MultiAngle></cc:GeometryChoice><cc:WavelengthRange StartWL="400" Increment="10"/>'
            '</cc:MeasurementSpec></cc:ColorSpecification></cc:ColorSpecificationCollection></cc:Resources></cc:CxF>')


def test_cxf_several_brdf_angles_in_one_specification_are_split_by_spectrum_name(tmp_path):
    p = _write(tmp_path, "two.cxf", _several_brdf_angles())
    assert cxf_geometries(p) == ["45as15", "45as45"]
    np.testing.assert_allclose(read_cxf(p, geometry="45as45").reflectance, [[0.10, 0.11, 0.12]])
    np.testing.assert_allclose(read_cxf(p, geometry="45as15").reflectance, [[0.30, 0.31, 0.32]])


def test_cxf_multi_angle_spectrum_without_or_with_a_wrong_name_is_an_error(tmp_path):
    with pytest.raises(DataFileError, match="has no Name; nmmm does not guess which angle"):
        read_cxf(_write(tmp_path, "a.cxf", _several_brdf_angles(("", 'Name="45as45"'))), geometry="45as45")
    with pytest.raises(DataFileError, match=r"Name '45as25' is none of the BRDFAngle Notations \['45as15', '45as45'\]"):
        read_cxf(_write(tmp_path, "b.cxf", _several_brdf_angles(('Name="45as25"', 'Name="45as45"'))), geometry="45as45")


def test_cxf_multi_angle_and_sphere_sets_in_one_file(tmp_path):
    w = np.arange(400.0, 701.0, 20.0)
    sets = _multi(w)[:3] + [MeasuredSpectra(w, np.full((2, w.size), 0.5), ("silver", "white"), "di:8")]
    p = write_cxf(tmp_path / "mix.cxf", sets)
    assert cxf_geometries(p) == ASPEC[:3] + ["di:8"]
    assert p.read_text().count("<cc:ColorSpecification ") == 2
    np.testing.assert_allclose(read_cxf(p, geometry="SCI").reflectance, 0.5)
    assert Path(p).stat().st_size > 0


def test_multi_angle_metallic_above_one_near_specular_is_read_as_factors(tmp_path):
    """A silver's near-specular 45as-15 factors reach 3-5 (L* ~170); in a multi-angle CxF3 file whose
    45as110 spectra stay below 1.5 they are factors, not percent (before: refused as percent, with no
    way to read them). Alone, such values are refused with the hint; unit='fraction' reads them."""
    w = np.arange(400.0, 701.0, 10.0)
    bright = [MeasuredSpectra(w, np.full((1, w.size), v), ("silver",), g)
              for v, g in ((3.5, "45as-15"), (2.2, "45as15"), (0.2, "45as110"))]
    p = write_cxf(tmp_path / "silver.cxf", bright)
    np.testing.assert_allclose(read_cxf(p, geometry="45as-15").reflectance, 3.5)
    np.testing.assert_allclose(read_cxf(p, geometry="45as110").reflectance, 0.2)
    alone = write_cxf(tmp_path / "alone.cxf", bright[:1])
    with pytest.raises(DataFileError, match="look like percent.*near-specular multi-angle.*CLI --fraction"):
        read_cxf(alone)
    np.testing.assert_allclose(read_cxf(alone, unit="fraction").reflectance, 3.5)
    percent = write_cxf(tmp_path / "pc.cxf", [MeasuredSpectra(w, np.full((1, w.size), 100 * v), ("silver",), g)
                                              for v, g in ((0.35, "45as-15"), (0.2, "45as110"))])
    with pytest.raises(DataFileError, match="look like percent"):  # percent at every angle: still refused
        read_cxf(percent, geometry="45as-15")


def test_match_cli_fraction_flag(tmp_path, capsys):
    from nmmm.cli import main
    from nmmm.recipes.schema import example_path

    fac = TI3.replace("85.20 86.70 87.90", "0.352 0.367 0.379").replace("0.61 0.58 0.55", "0.0061 0.0058 0.0055")
    p = _write(tmp_path, "factors.ti3", fac)
    args = ["match", str(p), str(example_path("hematite_tint")), "--vary", "pigments.0.fraction=0.005:0.08", "--no-progress"]
    assert main(args + ["--percent", "--fraction", "-o", str(tmp_path / "a")]) == 2
    assert "--percent and --fraction: give one" in capsys.readouterr().err
    rs = read_cgats(p, unit="fraction")
    assert rs.reflectance.max() == pytest.approx(0.379)
