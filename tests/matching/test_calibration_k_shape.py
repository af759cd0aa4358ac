"""Calibration with a smooth, Kramers–Kronig-consistent change of k(λ) (issue 17 item 5, acceptance)."""

import numpy as np
import pytest

from nmmm.errors import InvalidInputError
from nmmm.matching.calibration import LadderSample, _Sample, calibrate_colourant, write_calibrated_material
from nmmm.matching.k_correction import corrected_nk, k_correction_factor
from nmmm.recipes.schema import example_path, read_toml, set_key

LADDER = {"masstone": (0.05, 0.0), "1:1": (0.04, 0.04), "1:4": (0.02, 0.08), "1:9": (0.01, 0.09),
          "1:2 (left out)": (0.03, 0.06)}
#: the injected perturbation: k x 1.2 with a tilt and a bow of ln k, grains 10 % larger
TRUE = {"k_scale": 1.2, "k_legendre_1": 0.15, "k_legendre_2": -0.10, "size_scale": 1.10}
NOISE = 0.002
CLEAN = {}  # noise-free spectra of the ladder, by sample


def _raw(h, r):
    raw, _, _ = read_toml(example_path("hematite_tint"))
    return set_key(set_key(raw, "pigments.0.fraction", h), "pigments.1.fraction", r)


@pytest.fixture(scope="module")
def ladder():
    rng = np.random.default_rng(17)
    out = []
    for name, (h, r) in LADDER.items():
        rr = _raw(h, r)
        s = _Sample(LadderSample(name, rr, np.zeros(16)), "hematite")
        clean = CLEAN[name] = s.reflectance(TRUE["k_scale"], TRUE["size_scale"], (TRUE["k_legendre_1"], TRUE["k_legendre_2"]))
        out.append(LadderSample(name, rr, clean + rng.normal(0, NOISE, clean.size)))
    return out


@pytest.fixture(scope="module")
def result(ladder):
    return calibrate_colourant(ladder, "hematite", fit=tuple(TRUE), left_out=("1:2 (left out)",))


def test_recovers_the_injected_smooth_k_change_and_size_within_its_uncertainty(result):
    for key, true in TRUE.items():
        se = result.standard_errors[key]
        assert 0 < se < 0.05, (key, se)  # a usable uncertainty, not a vacuous one
        assert abs(result.values[key] - true) <= 3 * se, (key, result.values[key], true, se)
    assert result.de00_after["1:2 (left out)"] <= 1.0
    # and against the noise-free truth (what the measured value's own noise cannot blur)
    from nmmm.colour import delta_e2000, spectra_to_lab

    w = result.wavelength_nm
    truth = spectra_to_lab(w, CLEAN["1:2 (left out)"], "D65")
    assert float(delta_e2000(truth, spectra_to_lab(w, result.predicted["1:2 (left out)"], "D65"))) <= 0.5
    assert max(result.de00_before.values()) > 3  # the uncorrected hematite is visibly wrong
    # the recovered k(λ) follows the injected one within the propagated uncertainty (3 σ of ln k)
    w = result.wavelength_nm
    k0 = result.base_material.nk(w).imag
    true_k = k0 * k_correction_factor(w, result.window_nm, TRUE["k_scale"], (TRUE["k_legendre_1"], TRUE["k_legendre_2"]))
    x = np.clip(2 * (w - w[0]) / (w[-1] - w[0]) - 1, -1, 1)
    # d ln k / d(params) for (k_scale, c1, c2): 1/s, P1, P2
    J = np.stack([np.full_like(x, 1 / result.values["k_scale"]), x, 0.5 * (3 * x**2 - 1)], axis=1)
    cov = result.covariance[:3, :3]
    sig = np.sqrt(np.einsum("ij,jk,ik->i", J, cov, J))
    assert np.all(np.abs(np.log(result.nk.imag / true_k)) <= 3 * sig + 1e-12)


def test_the_calibrated_material_file_is_read_back_and_kramers_kronig_consistent(result, tmp_path):
    from nmmm.materials.files import read_csv

    p = write_calibrated_material(result, tmp_path / "hematite_calibrated.csv", step_nm=5, source="ladder.toml")
    text = p.read_text(encoding="utf-8")
    assert "Kramers-Kronig" in text and "k_legendre_1 =" in text and "left out: 1:2 (left out)" in text
    m = read_csv(p)
    np.testing.assert_allclose(m.nk(result.wavelength_nm), result.nk, atol=2e-4)  # 5 nm file vs the 20 nm fit grid
    assert m.wavelength_nm[0] == 400 and m.wavelength_nm[-1] == 700 and np.allclose(np.diff(m.wavelength_nm), 5)


def test_corrected_nk_of_a_causal_material_stays_causal_and_k_alone_does_not():
    """An independent check: nmmm.materials.kk_consistency of a Lorentz oscillator whose k got the
    smooth correction — with the KK change of n it stays consistent; with n left alone it does not."""
    from nmmm.materials import Lorentz, TabulatedMaterial, kk_consistency

    w = np.linspace(250, 2000, 800)
    base = Lorentz(oscillators=[(6.0, 2.4, 0.5)], eps_inf=2.0, range_nm=(250, 2000))
    nk0 = base.nk(w)
    nk = corrected_nk(w, nk0, (400, 700), 1.3, (0.2, -0.1))
    good = TabulatedMaterial("corrected", w, nk.real, nk.imag)
    broken = TabulatedMaterial("k only", w, nk0.real, nk.imag)
    assert kk_consistency(base).consistent(0.01)
    assert kk_consistency(good).consistent(0.01), str(kk_consistency(good))
    assert not kk_consistency(broken).consistent(0.01)


def test_a_ladder_the_fit_cannot_use_is_refused(ladder):
    # more unknowns than data: one fitted sample of 16 values cannot fix 17 parameters — and 5 from none
    with pytest.raises(InvalidInputError, match="more unknowns than data"):
        calibrate_colourant(ladder, "hematite", fit=tuple(TRUE), left_out=tuple(LADDER))
    # a sample whose recipe defines the calibrated compound differently
    other = set_key(_raw(0.02, 0.08), "compounds.hematite", {"n": 3.0, "k": 0.1})
    odd = LadderSample("odd", other, ladder[0].reflectance)
    with pytest.raises(InvalidInputError, match="defines 'hematite' differently"):
        calibrate_colourant(ladder[:2] + [odd], "hematite")
    # no fitted sample contains the compound
    white = LadderSample("white", _raw(0.0, 0.1), ladder[0].reflectance)
    with pytest.raises(InvalidInputError, match="no fitted sample contains"):
        calibrate_colourant([white, ladder[1]], "hematite", left_out=(ladder[1].name,))
    with pytest.raises(InvalidInputError, match="each once"):
        calibrate_colourant(ladder, "hematite", fit=("k_scale", "k_scale"))


def test_a_ladder_that_fixes_the_values_poorly_says_so(ladder):
    """A masstone alone cannot tell more absorption from bigger grains: the values come with a warning."""
    from nmmm.matching.recipe_match import IdentifiabilityWarning

    with pytest.warns(IdentifiabilityWarning, match="correlated"):
        res = calibrate_colourant(ladder[:1], "hematite", fit=("k_scale", "k_legendre_1", "size_scale"))
    assert any("k_scale and size_scale are correlated" in n for n in res.warnings), res.warnings


def test_the_calibrated_compound_is_not_extrapolated_outside_the_window():
    """Outside the ladder's grid nothing fixes k: calibrated_nk refuses it (asking for 300 nm as
    well once moved n at 500 nm by 0.03); inside, a wavelength's value does not depend on the others."""
    from nmmm.materials import Lorentz
    from nmmm.matching.calibration import CalibrationResult

    base = Lorentz(oscillators=[(6.0, 2.4, 0.5)], eps_inf=2.0, range_nm=(250, 2000))
    res = CalibrationResult("x", {"k_scale": 1.25, "k_legendre_1": 0.2}, {}, {}, {}, (), 0, 0.0, window_nm=(400.0, 700.0),
                            base_material=base)
    with pytest.raises(InvalidInputError, match="outside the calibration window 400-700 nm"):
        res.calibrated_nk([300.0, 500.0])
    one = res.calibrated_nk([500.0])
    np.testing.assert_allclose(res.calibrated_nk([400.0, 500.0, 700.0])[1], one[0], rtol=1e-12)
    k0 = base.nk(np.array([500.0])).imag
    np.testing.assert_allclose(one.imag, k0 * k_correction_factor([500.0], (400, 700), 1.25, (0.2,)), rtol=1e-12)


def test_a_value_stopped_at_its_bound_is_said(ladder):
    """The injected k_scale is 1.2: bounded to at most 1.1 the fit stops there, and its standard error
    (from the Jacobian at the bound) would look like a measurement — the result says it is not."""
    from nmmm.matching.recipe_match import IdentifiabilityWarning

    with pytest.warns(IdentifiabilityWarning, match=r"k_scale = 1.1 stopped at its bound \[0.5, 1.1\]"):
        res = calibrate_colourant(ladder[:4], "hematite", fit=("k_scale", "size_scale"), bounds={"k_scale": (0.5, 1.1)})
    assert res.values["k_scale"] == pytest.approx(1.1) and any("stopped at its bound" in n for n in res.warnings)
