"""Measured spectra in and out: CGATS.17, CxF3, CSV (issue 17 item 1). Files are written here, by hand."""

import numpy as np
import pytest

from nmmm.errors import DataFileError
from nmmm.matching import (MeasuredSpectra, cxf_geometries, read_cgats, read_cxf, read_measured, read_spectra_csv,
                           write_cgats, write_cxf)

CGATS = """CGATS.17
ORIGINATOR "Test instrument"
MEASUREMENT_GEOMETRY "d:8"
NUMBER_OF_FIELDS 5
BEGIN_DATA_FORMAT
SAMPLE_ID SAMPLE_NAME SPECTRAL_NM400 SPECTRAL_NM410 SPECTRAL_NM420
END_DATA_FORMAT
NUMBER_OF_SETS 2
BEGIN_DATA
1 "red panel" 0.0512 0.0498 0.0501
2 "white tile" 0.8810 0.8902 0.8955
END_DATA
"""


def _write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def test_cgats_reads_hand_checked_values(tmp_path):
    s = read_cgats(_write(tmp_path, "a.txt", CGATS))
    np.testing.assert_array_equal(s.wavelength_nm, [400, 410, 420])
    assert s.names == ("red panel", "white tile")
    assert s.geometry == "d:8"
    assert s.reflectance[1, 2] == pytest.approx(0.8955)
    assert s.metadata["ORIGINATOR"] == "Test instrument"


def test_cgats_round_trip(tmp_path):
    w = np.arange(400.0, 701.0, 10.0)
    R = np.stack([0.1 + 0.6 * np.exp(-((w - c) / 50) ** 2) for c in (450, 550, 650)])
    s = MeasuredSpectra(w, R, ("blue", "green", "red"), "45:0")
    back = read_cgats(write_cgats(tmp_path / "out.cgats", s))
    np.testing.assert_allclose(back.reflectance, R, atol=5e-7)
    np.testing.assert_array_equal(back.wavelength_nm, w)
    assert back.names == s.names and back.geometry == "45:0"
    lines = (tmp_path / "out.cgats").read_text().splitlines()  # CGATS.17: a non-reserved keyword is declared first
    for key in ("SPECTRAL_NORM", "MEASUREMENT_GEOMETRY"):
        used = next(i for i, ln in enumerate(lines) if ln.startswith(key + " "))
        assert f'KEYWORD "{key}"' in lines[:used]
    assert "KEYWORD" not in back.metadata


def test_cgats_truncated(tmp_path):
    p = _write(tmp_path, "t.txt", CGATS.split("2 \"white")[0])
    with pytest.raises(DataFileError, match="truncated"):
        read_cgats(p)
    q = _write(tmp_path, "n.txt", CGATS.replace("NUMBER_OF_SETS 2", "NUMBER_OF_SETS 3"))
    with pytest.raises(DataFileError, match="NUMBER_OF_SETS says 3"):
        read_cgats(q)
    r = _write(tmp_path, "r.txt", CGATS.replace(" 0.0501\n", "\n"))
    with pytest.raises(DataFileError, match="4 values for 5 fields"):
        read_cgats(r)


def test_cgats_without_spectral_fields(tmp_path):
    text = CGATS.replace("SPECTRAL_NM400 SPECTRAL_NM410 SPECTRAL_NM420", "LAB_L LAB_A LAB_B")
    with pytest.raises(DataFileError, match="no spectral fields"):
        read_cgats(_write(tmp_path, "lab.txt", text))


def test_percent_is_detected_and_declared(tmp_path):
    text = CGATS.replace("0.0512 0.0498 0.0501", "5.12 4.98 5.01").replace("0.8810 0.8902 0.8955", "88.10 89.02 89.55")
    p = _write(tmp_path, "pc.txt", text)
    with pytest.raises(DataFileError, match="percent"):
        read_cgats(p)
    assert read_cgats(p, unit="percent").reflectance[1, 2] == pytest.approx(0.8955)
    q = _write(tmp_path, "norm.txt", text.replace("NUMBER_OF_FIELDS", "SPECTRAL_NORM 100\nNUMBER_OF_FIELDS"))
    assert read_cgats(q).reflectance[0, 0] == pytest.approx(0.0512)


def test_cxf_multi_angle_round_trip_and_geometry_choice(tmp_path):
    w = np.arange(400.0, 701.0, 20.0)
    sets = [MeasuredSpectra(w, np.stack([np.full(w.size, 0.1 * (k + 1)), np.linspace(0.2, 0.5, w.size) / (k + 1)]),
                            ("flop", "face"), g) for k, g in enumerate(["45:-15", "45:15", "45:45"])]
    p = write_cxf(tmp_path / "ma.cxf", sets)
    assert cxf_geometries(p) == ["45:-15", "45:15", "45:45"]
    with pytest.raises(DataFileError, match="3 geometries"):
        read_cxf(p)  # mixed geometries: one has to be chosen
    s = read_cxf(p, geometry="45:15")
    np.testing.assert_array_equal(s.wavelength_nm, w)
    np.testing.assert_allclose(s.reflectance, sets[1].reflectance, atol=5e-7)
    assert s.names == ("flop", "face")
    with pytest.raises(DataFileError, match="no spectra at geometry"):
        read_cxf(p, geometry="45:110")


# The first two objects (of 144) of colour-cxf 0.1.1's own test file, colour_cxf/tests/resources/sample.cxf
# (X-Rite ColorPort "correctionset1", 2007; BSD-3-Clause), verbatim but for tabs -> two spaces; it is valid
# CxF3-core (SingleAngle Annular 45/0, 380 nm + 31 x 10 nm).
CXF_SPEC_EXAMPLE = """<?xml version="1.0" encoding="UTF-8"?>
<cc:CxF xmlns:cc="http://colorexchangeformat.com/CxF3-core" xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance">
  <cc:FileInformation>
    <cc:Creator>X-Rite, Inc.</cc:Creator>
    <cc:CreationDate>2007-06-14T00:00:00-08:00</cc:CreationDate>
    <cc:Description>ColorPort Custom Target: correctionset1</cc:Description>
    <cc:Tag Name="28178_TargetType" Value="CGATS.17"/>
  </cc:FileInformation>
  <cc:Resources>
    <cc:ObjectCollection>
      <cc:Object ObjectType="Target" Name="1" Id="1">
        <cc:CreationDate>2007-06-14T00:00:00-08:00</cc:CreationDate>
        <cc:ColorValues>
          <cc:ColorCIELab ColorSpecification="CS1">
            <cc:L>17.64167</cc:L>
            <cc:A>1.076669</cc:A>
            <cc:B>0.3338588</cc:B>
          </cc:ColorCIELab>
          <cc:ColorSRGB ColorSpecification="CS1">

            <cc:R>0</cc:R>
            <cc:G>0</cc:G>
            <cc:B>0</cc:B>
          </cc:ColorSRGB>
          <cc:ReflectanceSpectrum StartWL="380" ColorSpecification="CS1">0.0179408 0.0189865 0.0196141 0.0201604 0.0208783 0.0202765 0.0213902 0.0232448 0.0251621 0.0264493 0.0270566 0.0270034 0.026543 0.0255919 0.0244324 0.0238113 0.023676 0.0232761 0.0225849 0.0227898 0.0235763 0.0242324 0.0245493 0.024855 0.0254194 0.026301 0.0278601 0.0301097 0.0334874 0.0381948 0.0448929</cc:ReflectanceSpectrum>
        </cc:ColorValues>
      </cc:Object>
      <cc:Object ObjectType="Target" Name="2" Id="2">
        <cc:CreationDate>2007-06-14T00:00:00-08:00</cc:CreationDate>
        <cc:ColorValues>
          <cc:ColorCIELab ColorSpecification="CS1">
            <cc:L>47.83558</cc:L>
            <cc:A>63.29078</cc:A>
            <cc:B>36.27213</cc:B>
          </cc:ColorCIELab>
          <cc:ColorSRGB ColorSpecification="CS1">
            <cc:R>255</cc:R>
            <cc:G>0</cc:G>
            <cc:B>0</cc:B>
          </cc:ColorSRGB>
          <cc:ReflectanceSpectrum StartWL="380" ColorSpecification="CS1">0.0394959 0.041798 0.0431796 0.0443822 0.0390338 0.0363864 0.0401547 0.045801 0.0523042 0.0586208 0.0632642 0.0662882 0.0659939 0.0596725 0.0527806 0.0512717 0.0512901 0.0460535 0.040967 0.0456935 0.072808 0.1577058 0.3328304 0.5322706 0.6631728 0.735719 0.7882051 0.8269124 0.8502781 0.8555662 0.8545514</cc:ReflectanceSpectrum>
        </cc:ColorValues>
      </cc:Object>
    </cc:ObjectCollection>
    <cc:ColorSpecificationCollection>
      <cc:ColorSpecification Id="CS1">
        <cc:TristimulusSpec>
          <cc:Illuminant>D50</cc:Illuminant>
          <cc:Observer>2_Degree</cc:Observer>
          <cc:Method>E308_Table5</cc:Method>
        </cc:TristimulusSpec>
        <cc:MeasurementSpec>
          <cc:MeasurementType>Spectrum_Reflectance</cc:MeasurementType>
          <cc:GeometryChoice>
            <cc:SingleAngle>
                                <cc:SingleAngleConfiguration>Annular</cc:SingleAngleConfiguration>
              <cc:IlluminationAngle>45.0</cc:IlluminationAngle>
              <cc:MeasurementAngle>0.0</cc:MeasurementAngle>
            </cc:SingleAngle>
          </cc:GeometryChoice>
          <cc:WavelengthRange StartWL="380" Increment="10"/>
        </cc:MeasurementSpec>
      </cc:ColorSpecification>
    </cc:ColorSpecificationCollection>
  </cc:Resources>
</cc:CxF>
"""


def test_cxf_in_the_specifications_layout(tmp_path):
    s = read_cxf(_write(tmp_path, "spec.cxf", CXF_SPEC_EXAMPLE))
    np.testing.assert_array_equal(s.wavelength_nm, np.arange(380.0, 681.0, 10.0))
    assert s.names == ("1", "2") and s.geometry == "45a:0"
    np.testing.assert_allclose(s.reflectance[0, :3], [0.0179408, 0.0189865, 0.0196141])
    np.testing.assert_allclose(s.reflectance[1, -1], 0.8545514)


def test_cxf_truncated_and_empty(tmp_path):
    with pytest.raises(DataFileError, match="truncated"):
        read_cxf(_write(tmp_path, "t.cxf", CXF_SPEC_EXAMPLE[:400]))
    no_spec = CXF_SPEC_EXAMPLE.replace("ReflectanceSpectrum", "ColorCIELab")
    with pytest.raises(DataFileError, match="no ReflectanceSpectrum"):
        read_cxf(_write(tmp_path, "e.cxf", no_spec))


def test_csv_several_samples(tmp_path):
    p = _write(tmp_path, "s.csv", "wavelength_nm,batch 1,batch 2\n400,0.10,0.11\n500,0.20,0.21\n600,0.30,0.31\n")
    s = read_spectra_csv(p)
    assert s.names == ("batch 1", "batch 2")
    np.testing.assert_allclose(s.spectrum("batch 2"), [0.11, 0.21, 0.31])
    np.testing.assert_allclose(s.on_grid([450.0, 550.0])[0], [0.15, 0.25])
    with pytest.raises(DataFileError, match="percent"):
        read_spectra_csv(_write(tmp_path, "p.csv", "wavelength_nm,reflectance\n400,10\n500,20\n600,30\n"))
    with pytest.raises(DataFileError, match="truncated row"):
        read_spectra_csv(_write(tmp_path, "t.csv", "wavelength_nm,a,b\n400,0.1,0.1\n500,0.2\n600,0.3,0.3\n"))
    assert read_measured(p).names == s.names
    assert read_measured(_write(tmp_path, "c.cgats", CGATS)).names == ("red panel", "white tile")


def _cxf_with_geometry(geometry_xml: str, objects=(("panel", "CS1"),)) -> str:
    """A CxF3 file with one ColorSpecification whose GeometryChoice is ``geometry_xml``."""
    values = "0.10 0.11 0.12 0.13"
    objs = "".join(f'<cc:Object ObjectType="Standard" Name="{n}" Id="{i}"><cc:CreationDate>2026-01-01T00:00:00Z'
                   f'</cc:CreationDate><cc:ColorValues><cc:ReflectanceSpectrum ColorSpecification="{cs}" StartWL="400">'
                   f'{values}</cc:ReflectanceSpectrum></cc:ColorValues></cc:Object>' for i, (n, cs) in enumerate(objects, 1))
    return ('<?xml version="1.0" encoding="UTF-8"?><cc:CxF xmlns:cc="http://colorexchangeformat.com/CxF3-core">'
            f'<cc:Resources><cc:ObjectCollection>{objs}</cc:ObjectCollection><cc:ColorSpecificationCollection>'
            '<cc:ColorSpecification Id="CS1"><cc:MeasurementSpec><cc:MeasurementType>Spectrum_Reflectance'
            f'</cc:MeasurementType><cc:GeometryChoice>{geometry_xml}</cc:GeometryChoice>'
            '<cc:WavelengthRange StartWL="400" Increment="10"/></cc:MeasurementSpec></cc:ColorSpecification>'
            '</cc:ColorSpecificationCollection></cc:Resources></cc:CxF>')


@pytest.mark.parametrize("xml, geometry", [
    ("<cc:SphereGeometry>Specular_Included</cc:SphereGeometry>", "di:8"),
    ("<cc:SphereGeometry>Specular_Excluded</cc:SphereGeometry>", "de:8"),
    ("<cc:SingleAngle><cc:SingleAngleConfiguration>Annular</cc:SingleAngleConfiguration><cc:IlluminationAngle>45"
     "</cc:IlluminationAngle><cc:MeasurementAngle>0</cc:MeasurementAngle></cc:SingleAngle>", "45a:0"),
    ("<cc:SingleAngle><cc:SingleAngleConfiguration>Annular</cc:SingleAngleConfiguration><cc:IlluminationAngle>0"
     "</cc:IlluminationAngle><cc:MeasurementAngle>45</cc:MeasurementAngle></cc:SingleAngle>", "0:45a"),
    ("<cc:SingleAngle><cc:SingleAngleConfiguration>Uniplanar</cc:SingleAngleConfiguration><cc:IlluminationAngle>45"
     "</cc:IlluminationAngle><cc:MeasurementAngle>0</cc:MeasurementAngle></cc:SingleAngle>", "45:0"),
    ("<cc:MultiAngle><cc:BRDFAngle><cc:IlluminationAngle>45</cc:IlluminationAngle><cc:Aspecular>15</cc:Aspecular>"
     "<cc:Notation>45as15</cc:Notation></cc:BRDFAngle></cc:MultiAngle>", "45as15"),
    ("<cc:UnknownGeometry>d:8 (instrument X)</cc:UnknownGeometry>", "d:8 (instrument X)"),
])
def test_cxf_geometry_choice_of_the_cxf3_core_schema(tmp_path, xml, geometry):
    p = _write(tmp_path, "g.cxf", _cxf_with_geometry(xml))
    assert cxf_geometries(p) == [geometry]
    assert read_cxf(p).geometry == geometry
    with pytest.raises(DataFileError, match="emissive"):
        read_cxf(_write(tmp_path, "e.cxf", _cxf_with_geometry("<cc:EmissiveMode>Ambient</cc:EmissiveMode>")))


def test_cxf_sci_and_sce_of_one_panel_are_two_geometries(tmp_path):
    """Reviewer's file: one object with a Specular_Included and a Specular_Excluded spectrum. Before,
    both were 'no geometry' and the SCI reading was silently taken; now a geometry must be chosen."""
    text = _cxf_with_geometry("<cc:SphereGeometry>Specular_Included</cc:SphereGeometry>")
    sce = text.replace('Id="CS1"', 'Id="CS2"').split("<cc:ColorSpecification ")[1].split("</cc:ColorSpecificationCollection>")[0]
    text = text.replace("</cc:ColorSpecificationCollection>", "<cc:ColorSpecification " + sce.replace(
        "Specular_Included", "Specular_Excluded") + "</cc:ColorSpecificationCollection>")
    text = text.replace("</cc:ReflectanceSpectrum>", '</cc:ReflectanceSpectrum><cc:ReflectanceSpectrum '
                        'ColorSpecification="CS2" StartWL="400">0.06 0.07 0.08 0.09</cc:ReflectanceSpectrum>')
    p = _write(tmp_path, "sci_sce.cxf", text)
    assert cxf_geometries(p) == ["di:8", "de:8"]
    with pytest.raises(DataFileError, match="2 geometries"):
        read_cxf(p)
    np.testing.assert_allclose(read_cxf(p, geometry="de:8").reflectance[0], [0.06, 0.07, 0.08, 0.09])
    np.testing.assert_allclose(read_cxf(p, geometry="di:8").reflectance[0], [0.10, 0.11, 0.12, 0.13])


def test_cxf_duplicate_sample_names_within_one_geometry_refused(tmp_path):
    text = _cxf_with_geometry("<cc:SphereGeometry>Specular_Included</cc:SphereGeometry>",
                              objects=(("panel", "CS1"), ("panel", "CS1")))
    with pytest.raises(DataFileError, match=r"\['panel'\] appear more than once at geometry 'di:8'"):
        read_cxf(_write(tmp_path, "dup.cxf", text))


def test_cxf_without_increment_is_an_error_naming_the_object(tmp_path):
    """Before, a missing Increment was silently taken as 10 nm."""
    text = _cxf_with_geometry("<cc:SphereGeometry>Specular_Included</cc:SphereGeometry>",
                              objects=(("red panel", "CS1"),)).replace(' Increment="10"', "")
    with pytest.raises(DataFileError, match=r"object 'red panel': no wavelength Increment"):
        read_cxf(_write(tmp_path, "noinc.cxf", text))


def test_percent_asked_for_factors_is_a_conflict_not_a_division(tmp_path):
    """--percent on a file declared SPECTRAL_NORM 1, or whose values never exceed 1.5, is refused
    (before, it divided factors by 100 and matched an almost black target)."""
    declared = _write(tmp_path, "n1.txt", CGATS.replace("NUMBER_OF_FIELDS", "SPECTRAL_NORM 1\nNUMBER_OF_FIELDS"))
    with pytest.raises(DataFileError, match="says SPECTRAL_NORM 1"):
        read_cgats(declared, unit="percent")
    with pytest.raises(DataFileError, match=r"no value exceeds 1.5 \(the largest is 0.8955\)"):
        read_cgats(_write(tmp_path, "f.txt", CGATS), unit="percent")
    with pytest.raises(DataFileError, match="drop --percent"):
        read_spectra_csv(_write(tmp_path, "f.csv", "wavelength_nm,a\n400,0.1\n500,0.2\n"), unit="percent")


@pytest.mark.parametrize("spelling, canonical", [
    ("45/0", "45:0"), ("45°/0°", "45:0"), ("45:0", "45:0"), ("45a:0", "45a:0"), ("45c/0", "45a:0"), ("0/45a", "0:45a"),
    ("SCI", "di:8"), ("d/8:i", "di:8"), ("d:8i", "di:8"), ("SCE", "de:8"), ("d/8:e", "de:8"), ("d/8", "d:8"),
    ("  de:8 ", "de:8"), (None, None)])
def test_canonical_geometry(spelling, canonical):
    from nmmm.matching.measured_files import canonical_geometry

    assert canonical_geometry(spelling) == canonical


def test_geometry_mismatch_words_per_case():
    from nmmm.matching.measured_files import geometry_mismatch

    assert geometry_mismatch("SCE", "de:8") is None and geometry_mismatch("d/8:i", "di:8") is None
    assert geometry_mismatch("0:45a", "45a:0") is None and geometry_mismatch(None, "de:8") is None
    sci = geometry_mismatch("SCI", "de:8")
    assert "specular component included (SCI)" in sci and "the target reads lighter" in sci
    assert 'geometry = "di:8"' in sci
    assert "the prediction reads lighter" in geometry_mismatch("de:8", "di:8")
    assert "SCI/SCE setting" in geometry_mismatch("d/8", "de:8")
    assert "uniplanar, or annular not said" in geometry_mismatch("45/0", "45a:0")
    assert "not comparable" in geometry_mismatch("45a:0", "de:8") and 'geometry = "45a:0"' in geometry_mismatch("45a:0", "de:8")
    assert "differ only by the 0° / 8° incidence" in geometry_mismatch("0:d", "di:8")
    assert "not one nmmm predicts" in geometry_mismatch("45as15", "45a:0")


def test_geometry_choice_and_file_geometry_compare_canonically(tmp_path):
    w = np.arange(400.0, 501.0, 20.0)
    sets = [MeasuredSpectra(w, np.full((1, w.size), v), ("panel",), g) for v, g in ((0.3, "di:8"), (0.2, "de:8"))]
    p = write_cxf(tmp_path / "sphere.cxf", sets)
    assert read_cxf(p, geometry="SCE").reflectance[0, 0] == pytest.approx(0.2)
    assert read_measured(write_cgats(tmp_path / "s.cgats", sets[0]), geometry="SCI").geometry == "di:8"
