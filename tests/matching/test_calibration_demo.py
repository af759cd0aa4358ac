"""The calibration section of ``nmmm demo`` (issue 17 item 6, calibration part)."""

from nmmm.demo import sections
from nmmm.demo.matching import NEW_TINT, PERTURBATION, calibration_demo


def test_calibration_demo(tmp_path):
    assert ("Calibration: a colourant calibrated from a measured ladder, physical and empirical (nmmm.matching)",
            "nmmm.demo.matching:calibration_demo") in sections.HOOKS
    r = calibration_demo(tmp_path)
    for name in ("calibration.png", "calibration.csv", "hematite_calibrated.csv"):
        assert (tmp_path / name).is_file(), name
    params = {p["parameter"]: p for p in r["tables"]["Calibrated parameters"]}
    assert set(params) == set(PERTURBATION)
    for p in params.values():  # the injected perturbation, recovered within its reported uncertainty
        assert abs(p["calibrated"] - p["injected"]) <= 3 * p["standard error"] + 1e-4, p
    rows = {row["sample"]: row for row in r["tables"]["ΔE00 per sample (D65)"]}
    new = rows[NEW_TINT[0]]
    assert new["role"] == "not in the ladder"
    assert new["ΔE00 physical"] <= 1.0 < new["ΔE00 uncalibrated"]
    left = rows["1:2 (left out)"]
    assert left["role"] == "left out" and left["ΔE00 physical"] <= 1.0 and "ΔE00 empirical (K/S)" in left
    assert "not in the ladder) was never fitted" in r["text"][1]
    assert any("The empirical fit warns" in t and "contrast pair" in t for t in r["text"])  # its 60 µm films all hide
