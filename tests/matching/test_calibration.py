"""Calibration of a colourant on a synthetic dilution ladder (issue 17 item 5)."""

import numpy as np
import pytest

from nmmm.errors import InvalidInputError
from nmmm.matching.calibration import LadderSample, _Sample, _kk_delta_n, calibrate_colourant, write_calibrated_material
from nmmm.recipes.schema import example_path, read_toml, set_key

LADDER = {"masstone": (0.05, 0.0), "1:1": (0.04, 0.04), "1:4": (0.02, 0.08), "1:9": (0.01, 0.09),
          "1:2 (left out)": (0.03, 0.06)}
TRUE_K, TRUE_SIZE = 1.25, 1.15


@pytest.fixture(scope="module")
def ladder():
    """Hematite/rutile tints whose 'measurements' are the model with hematite's k x 1.25 (KK-consistent n)
    and 15 % larger grains, plus noise 0.002."""
    raw, _, _ = read_toml(example_path("hematite_tint"))
    rng = np.random.default_rng(5)
    out = []
    for name, (h, r) in LADDER.items():
        rr = set_key(set_key(raw, "pigments.0.fraction", h), "pigments.1.fraction", r)
        s = _Sample(LadderSample(name, rr, np.zeros(16)), "hematite")
        out.append(LadderSample(name, rr, s.reflectance(TRUE_K, TRUE_SIZE) + rng.normal(0, 0.002, 16)))
    return out


def test_recovers_the_injected_perturbation(ladder, tmp_path):
    res = calibrate_colourant(ladder, "hematite", left_out=("1:2 (left out)",))
    for key, true in (("k_scale", TRUE_K), ("size_scale", TRUE_SIZE)):
        assert abs(res.values[key] - true) <= 3 * res.standard_errors[key] + 1e-3, (key, res.values, res.standard_errors)
    assert res.de00_after["1:2 (left out)"] <= 1.0
    assert max(res.de00_before.values()) > 3  # the uncorrected hematite is visibly wrong
    assert all(res.de00_after[k] < res.de00_before[k] for k in LADDER)
    p = write_calibrated_material(res, tmp_path / "hematite_calibrated.csv")
    from nmmm.materials.files import read_csv

    m = read_csv(p)
    np.testing.assert_allclose(m.nk(res.wavelength_nm), res.nk, atol=1e-5)


def test_kk_correction_is_the_transform_of_the_change():
    """Δn for a Lorentzian absorption band has the dispersive shape: above the band centre's
    wavelength n rises, below it falls (anomalous dispersion), and it is linear in s − 1."""
    w = np.arange(400.0, 701.0, 5.0)
    k = 0.3 / (1 + ((w - 550) / 30) ** 2)
    dn = _kk_delta_n(w, k)
    assert dn[w == 600][0] > 0 > dn[w == 500][0]


def test_more_unknowns_than_data_and_bad_names(ladder):
    with pytest.raises(InvalidInputError, match="left_out names"):
        calibrate_colourant(ladder, "hematite", left_out=("nope",))
    with pytest.raises(InvalidInputError, match="more unknowns than data"):
        calibrate_colourant(ladder, "hematite", left_out=tuple(LADDER))
    with pytest.raises(InvalidInputError, match="no compound"):
        calibrate_colourant(ladder[:1], "goethite")
    with pytest.raises(InvalidInputError, match="fit must name"):
        calibrate_colourant(ladder, "hematite", fit=("n_scale",))
