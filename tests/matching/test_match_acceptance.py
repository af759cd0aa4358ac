"""Issue 17 acceptance, matching: synthetic targets made by nmmm from recipes of 2, 3 and 4 colourants.

The recovered spectrum is within ΔE00 ≤ 0.3 under D65 and the fractions within 5 % where they are
identifiable; with noise of 0.002 in reflectance, ΔE00 ≤ 0.5. The case: the shipped hematite tint at
8 µm over white (hiding incomplete), colourants added one by one — rutile, a black (n 1.9 + 0.6i,
60 nm), gold nanospheres (Johnson & Christy, 40 nm: a green-absorbing plasmon band).

"Identifiable": noise-free, every fraction is (the target is the model's own spectrum). At noise
0.002 the total amount of colourant at fixed ratios is weakly pinned by one spectrum of a film over
white: the linearised standard errors (Gauss–Newton covariance at the optimum, at the stated noise)
are above 5 % of every fraction, in 2, 3 and 4 colourants alike — and they are not an honest interval
there (the fractions fell up to 8.5 of them from the truth in 20 draws of n = 3: along the total the
film turns opaque and R stops changing). What the spectrum does pin is checked instead: the shares of
the total within 3 of their σ (max 2.4 seen in 40 draws), and the true total inside the reported 68 %
profile-likelihood interval (18 of 20 draws of n = 3, 8 of 10 of n = 2 and of n = 4).
The noise itself moves the target's colour by ΔE00 0.15–0.74 on this 16-wavelength grid, so "ΔE00 ≤
0.5 with noise" is checked as the spectral match against the true spectrum (max 0.34 seen in 15
draws) and the match against the measured colour where the noise leaves it reachable.
"""

import warnings

import numpy as np
import pytest

from nmmm.matching import RecipeModel, match_recipe
from nmmm.recipes.schema import example_path, read_toml, set_key

CASES = {
    2: (["pigments.0.fraction=0.005:0.08", "pigments.1.fraction=0.02:0.25"], [0.021, 0.15]),
    3: (["pigments.0.fraction=0.005:0.08", "pigments.1.fraction=0.02:0.25", "pigments.2.fraction=0:0.02"],
        [0.021, 0.15, 0.006]),
    4: (["pigments.0.fraction=0.005:0.08", "pigments.1.fraction=0.02:0.25", "pigments.2.fraction=0:0.02",
         "pigments.3.fraction=0:0.002"], [0.021, 0.15, 0.006, 0.0008]),
}
_MODELS = {}


def _model(n):
    if n not in _MODELS:
        raw, _, _ = read_toml(example_path("hematite_tint"))
        raw = set_key(raw, "film.thickness_nm", 8000.0)
        raw["compounds"]["black"] = {"n": 1.9, "k": 0.6}
        raw["compounds"]["gold"] = {"database": "main/Au/Johnson"}
        if n >= 3:
            raw["pigments"].append({"compound": "black", "fraction": 0.004, "diameter_nm": 60})
        if n >= 4:
            raw["pigments"].append({"compound": "gold", "fraction": 0.0005, "diameter_nm": 40})
        free, true = CASES[n]
        m = RecipeModel(raw, free)
        _MODELS[n] = (m, np.array(true), m.reflectance(np.array(true), "ad"))
    return _MODELS[n]


def _match(m, target, mode):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the identifiability warnings are checked in test_match.py
        res = match_recipe(m, target, mode=mode)
    return res, np.array([res.values[b.key] for b in m.bounds])


@pytest.mark.parametrize("mode", ["colorimetric", "spectral"])
@pytest.mark.parametrize("n", [2, 3, 4])
def test_noise_free_target_is_recovered(n, mode):
    m, true, target = _model(n)
    res, got = _match(m, target, mode)
    assert res.de00 <= 0.3
    np.testing.assert_allclose(got, true, rtol=0.05)  # noise-free, every fraction is identifiable
    assert res.de00 < 0.01 and sum(res.evaluations.values()) > 0


@pytest.mark.parametrize("mode", ["colorimetric", "spectral"])
def test_noise_free_target_with_a_colourant_absent_is_recovered(mode):
    """The black at 0 (its lower bound): both KM optima led the finish into another basin (ΔE00 0.075,
    hematite 0.0084 and rutile 0.062 for 0.021 and 0.15; scipy's trf from the box centre reaches the
    truth), so a finish short of stop_norm is also tried from the centre."""
    m, _, _ = _model(3)
    true = np.array([0.021, 0.15, 0.0])
    res, got = _match(m, m.reflectance(true, "ad"), mode)
    assert res.de00 < 0.01
    np.testing.assert_allclose(got[:2], true[:2], rtol=0.05)
    assert got[2] <= 1e-4 and "pigments.2.fraction=LO" in res.active_bounds


def _noisy_checks(n, mode, seed):
    """Noise 0.002 on the target. The true recipe is a candidate the fit could return, so the match
    must be at least as close to the measured (noisy) target as the true recipe is (ΔE00 colorimetric,
    spectral RMS spectral; a small slack for the stopping rule); a spectral (isomeric) match must
    recover the true spectrum to ΔE00 ≤ 0.5; and where the noise itself moves the colour by less than
    0.45, the match is within 0.5 of the measured colour."""
    from nmmm.colour import delta_e2000, spectra_to_lab

    m, true, target = _model(n)
    w = m.wavelength_nm
    noisy = np.clip(target + np.random.default_rng(seed).normal(0, 0.002, target.size), 0, 1)
    res, got = _match(m, noisy, mode)
    lab_true, lab_noisy = spectra_to_lab(w, target), spectra_to_lab(w, noisy)
    noise_de = float(delta_e2000(lab_true, lab_noisy))
    to_true = float(delta_e2000(lab_true, res.lab))
    print(f"AUDIT n={n} {mode} seed={seed} noise dE00 {noise_de:.3f} match-measured {res.de00:.3f} match-true {to_true:.3f} "
          f"fraction errors {np.round(got / true - 1, 3)}")
    if mode == "colorimetric":
        assert res.de00 <= noise_de + 0.02, (res.de00, noise_de)
    else:
        assert res.spectral_rms <= 1.001 * float(np.sqrt(np.mean((target - noisy) ** 2))) + 1e-6
        assert to_true <= 0.5, (n, seed, to_true)
        se = np.array([res.standard_errors[b.key] for b in m.bounds])
        # the fractions' reported standard errors at this noise: the total amount is not pinned to 5 %
        assert np.all(se > 0.05 * true), se / true
        share, share_se = np.array([res.shares[b.key] for b in m.bounds]).T
        assert np.all(np.abs(share - true / true.sum()) <= 3 * share_se), (share - true / true.sum()) / share_se
        t = res.total
        assert t["low"] <= got.sum() <= t["high"] and t["low"] >= 0.99 * sum(b.lo for b in m.bounds)
    if noise_de < 0.45:
        assert res.de00 <= 0.5, (n, mode, seed, res.de00)
    return res, true


@pytest.mark.parametrize("mode", ["colorimetric", "spectral"])
@pytest.mark.parametrize("n", [2, 3, 4])
def test_noisy_target_matches_within_half_a_unit(n, mode):
    res, true = _noisy_checks(n, mode, seed=7)
    if mode == "spectral":  # this draw's true total lies in the 68 % profile interval (coverage: the slow test)
        assert res.total["low"] <= true.sum() <= res.total["high"], (res.total, true.sum())


@pytest.mark.slow
def test_total_interval_covers_the_true_total():
    """The 68 % profile interval of the total holds the true total in most of 10 noise draws (seen 9 of
    10), where the linearised σ of the fractions would miss it by up to 8.5 σ (seed 6)."""
    m, true, target = _model(3)
    hits, worst = 0, 0.0
    for seed in range(10):
        noisy = np.clip(target + np.random.default_rng(seed).normal(0, 0.002, target.size), 0, 1)
        res, got = _match(m, noisy, "spectral")
        hits += res.total["low"] <= true.sum() <= res.total["high"]
        se = np.array([res.standard_errors[b.key] for b in m.bounds])
        worst = max(worst, float(np.max(np.abs(got - true) / se)))
    assert hits >= 7, hits
    assert worst > 5  # the linearised σ is not an interval here: why the profile interval exists


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("mode", ["colorimetric", "spectral"])
@pytest.mark.parametrize("n", [2, 3, 4])
def test_noisy_target_matches_within_half_a_unit_many_seeds(n, mode, seed):
    _noisy_checks(n, mode, seed)



def test_shares_and_total_interval_reach_the_result_files(tmp_path):
    """match.json and report.md carry the shares (±σ) and the total's 68 % profile interval beside the
    linearised σ, so a user reads what the spectrum pins."""
    import json
    import re

    from nmmm.matching.outputs import write_match_outputs

    m, true, target = _model(2)
    noisy = np.clip(target + np.random.default_rng(7).normal(0, 0.002, target.size), 0, 1)
    res, _ = _match(m, noisy, "spectral")
    files = write_match_outputs(res, tmp_path / "o", "noisy", plots=False)
    got = json.loads(files["json"].read_text())
    assert set(got["shares"]) == {b.key for b in m.bounds} and got["noise"] == 0.002
    assert got["total"]["low"] <= sum(res.values.values()) <= got["total"]["high"]
    assert any(re.search(r"68 % profile interval; (both ends are|its (lower|upper) end is) at the --vary bounds", w)
               for w in res.warnings) == (got["total"]["low_at_bound"] or got["total"]["high_at_bound"])
    report = files["report"].read_text()
    assert "σ linearised (noise 0.002)" in report and "68 % profile interval" in report
