"""2AFC statistics against textbook values and independent computations."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize, special, stats

from nmmm.errors import InvalidInputError
from nmmm.experiment.stats import (
    analyse_responses,
    binomial_test,
    critical_count,
    dprime_2afc,
    dprime_2afc_counts,
    format_report,
    pc_from_dprime_2afc,
    pooled_cluster_robust,
    pooled_beta_binomial,
    pooled_equivalence,
    pooled_naive,
    proportion_ci,
    proportion_ci_clopper_pearson,
    proportion_ci_wilson,
    tost_binomial,
)


def test_dprime_2afc_textbook():
    # Macmillan & Creelman (2005) ch. 7: d' = sqrt(2) z(Pc); z(0.76) = 0.706 (normal table),
    # so d' = 0.998.
    assert dprime_2afc(0.76) == pytest.approx(math.sqrt(2) * 0.7063, abs=2e-4)
    assert dprime_2afc(0.76) == pytest.approx(0.998, abs=2e-3)
    assert dprime_2afc(0.5) == 0.0
    # Pc = 0.92 -> z = 1.405 (normal table), d' = 1.987
    assert dprime_2afc(0.92) == pytest.approx(math.sqrt(2) * 1.4051, abs=2e-4)
    np.testing.assert_allclose(pc_from_dprime_2afc(dprime_2afc([0.3, 0.6, 0.9])), [0.3, 0.6, 0.9])
    with pytest.raises(InvalidInputError):
        dprime_2afc(1.2)


def test_dprime_counts_corrections():
    assert np.isfinite(dprime_2afc_counts(20, 20))
    # log-linear rule (Hautus 1995): Pc = (k + 0.5) / (n + 1)
    assert dprime_2afc_counts(20, 20) == pytest.approx(math.sqrt(2) * stats.norm.ppf(20.5 / 21))
    # 1/(2N) rule: 20/20 -> 1 - 1/40
    assert dprime_2afc_counts(20, 20, "1/(2N)") == pytest.approx(math.sqrt(2) * stats.norm.ppf(1 - 1 / 40))
    assert dprime_2afc_counts(15, 20, None) == pytest.approx(dprime_2afc(0.75))
    with pytest.raises(InvalidInputError):
        dprime_2afc_counts(21, 20)


def test_critical_count_binomial_table():
    # One-sided exact binomial criteria at alpha = 0.05, p = 0.5 (cumulative binomial tables,
    # e.g. Siegel & Castellan 1988, Nonparametric Statistics, table of the binomial test):
    # 15 of 20, 9 of 10, 18 of 25, 20 of 30, 26 of 40.
    assert critical_count(20) == 15
    assert critical_count(10) == 9
    assert critical_count(25) == 18
    assert critical_count(30) == 20
    assert critical_count(40) == 26
    # P(X >= 15 | 20, .5) = 0.0207 <= 0.05 < P(X >= 14) = 0.0577
    assert binomial_test(15, 20) == pytest.approx(0.020695, abs=1e-6)
    assert binomial_test(14, 20) == pytest.approx(0.057659, abs=1e-6)
    assert critical_count(3) == 4  # nothing is significant with 3 trials


# Newcombe (1998), Statistics in Medicine 17:857, worked examples: Wilson score (method 3) and
# Clopper-Pearson exact (method 5) 95 % intervals.
NEWCOMBE = [
    (81, 263, (0.2553, 0.3662), (0.2527, 0.3676)),
    (15, 148, (0.0624, 0.1605), (0.0578, 0.1617)),
    (0, 20, (0.0, 0.1611), (0.0, 0.1684)),
    (1, 29, (0.0061, 0.1718), (0.0009, 0.1776)),
]


@pytest.mark.parametrize("k,n,wilson,exact", NEWCOMBE)
def test_intervals_newcombe_1998(k, n, wilson, exact):
    np.testing.assert_allclose(proportion_ci_wilson(k, n), wilson, atol=6e-5)
    np.testing.assert_allclose(proportion_ci_clopper_pearson(k, n), exact, atol=6e-5)
    np.testing.assert_allclose(proportion_ci(k, n, method="exact"), exact, atol=6e-5)


def test_intervals_match_scipy_and_broadcast():
    k = np.array([0, 3, 10, 17, 20])
    n = 20
    lo, hi = proportion_ci_wilson(k, n, 0.9)
    lo2, hi2 = proportion_ci_clopper_pearson(k, n, 0.9)
    for i, ki in enumerate(k):
        r = stats.binomtest(int(ki), n)
        np.testing.assert_allclose((lo[i], hi[i]), tuple(r.proportion_ci(0.9, method="wilson")), atol=1e-12)
        np.testing.assert_allclose((lo2[i], hi2[i]), tuple(r.proportion_ci(0.9, method="exact")), atol=1e-9)
    with pytest.raises(InvalidInputError, match="interval method"):
        proportion_ci(3, 10, method="wald")


def test_tost_equals_interval_inclusion():
    # Schuirmann (1987): TOST at alpha rejects iff the 1 - 2 alpha interval lies inside the margin;
    # for the exact binomial the interval is Clopper-Pearson (inverted one-sided exact tests).
    n, delta, alpha = 200, 0.1, 0.05
    for k in range(70, 131):
        r = tost_binomial(k, n, delta, alpha)
        ci = stats.binomtest(k, n).proportion_ci(1 - 2 * alpha, method="exact")
        inside = (0.5 - delta) < ci.low and ci.high < (0.5 + delta)
        assert r.equivalent == inside, k
        assert r.p_lower == pytest.approx(stats.binom.sf(k - 1, n, 0.4))
        assert r.p_upper == pytest.approx(stats.binom.cdf(k, n, 0.6))
    assert tost_binomial(100, 200, 0.1).equivalent
    assert not tost_binomial(10, 20, 0.1).equivalent  # 20 trials cannot show +-0.1
    with pytest.raises(InvalidInputError, match="margin"):
        tost_binomial(10, 20, 0.7)


def _overdispersed(seed=3, g=30, m=20, mean=0.6, rho=0.1):
    rng = np.random.default_rng(seed)
    a, b = mean * (1 - rho) / rho, (1 - mean) * (1 - rho) / rho
    n = np.full(g, m)
    return rng.binomial(n, rng.beta(a, b, g)), n


def test_cluster_robust_is_one_sample_t_test_for_equal_n():
    k, n = _overdispersed()
    est = pooled_cluster_robust(k, n, floor_binomial=False)
    t = stats.ttest_1samp(k / n, 0.5)
    assert est.pc == pytest.approx(np.mean(k / n))
    assert est.se == pytest.approx(np.std(k / n, ddof=1) / np.sqrt(len(k)))
    assert est.p_value == pytest.approx(t.pvalue)
    ci = t.confidence_interval(0.95)
    np.testing.assert_allclose(est.interval, (ci.low, ci.high))
    # clustering widens the interval against the naive binomial one
    naive = pooled_naive(k, n)
    assert est.interval[1] - est.interval[0] > naive.interval[1] - naive.interval[0]


def test_cluster_robust_unequal_n_ratio_estimator():
    k = np.array([3, 12, 7, 20, 9])
    n = np.array([10, 20, 10, 25, 18])
    est = pooled_cluster_robust(k, n, floor_binomial=False)
    p = k.sum() / n.sum()
    # Cochran (1977), Sampling Techniques, ch. 6, ratio estimator without finite-population
    # correction: v(r) = sum (y_i - r x_i)^2 / (G (G-1) xbar^2)
    G = len(k)
    v = np.sum((k - p * n) ** 2) / (G * (G - 1) * n.mean() ** 2)
    assert est.se == pytest.approx(math.sqrt(v))


def test_beta_binomial_recovers_parameters_and_binomial_limit():
    k, n = _overdispersed(seed=11, g=400, m=20, mean=0.6, rho=0.1)
    est = pooled_beta_binomial(k, n)
    assert est.pc == pytest.approx(0.6, abs=0.02)
    assert est.rho == pytest.approx(0.1, abs=0.04)
    assert est.interval[0] < est.pc < est.interval[1]
    # the maximum-likelihood point itself, against scipy.stats.betabinom maximised directly
    # (a = mu (1 - rho) / rho, b = (1 - mu) (1 - rho) / rho; Nelder-Mead in logit space)

    def nll(x):
        mu, rho = special.expit(x)
        return -stats.betabinom.logpmf(k, n, mu * (1 - rho) / rho, (1 - mu) * (1 - rho) / rho).sum()

    ref = optimize.minimize(nll, [0.0, -2.0], method="Nelder-Mead", options={"xatol": 1e-8, "fatol": 1e-10})
    mu_ref, rho_ref = special.expit(ref.x)
    assert est.pc == pytest.approx(mu_ref, abs=1e-4)
    assert est.rho == pytest.approx(rho_ref, abs=1e-3)
    assert est.extra["loglik"] == pytest.approx(-ref.fun, abs=1e-6)
    # no overdispersion at all: every observer 12/20 -> rho at its lower bound, mu = 0.6 exactly
    flat = pooled_beta_binomial(np.full(10, 12), np.full(10, 20))
    assert flat.pc == pytest.approx(0.6, abs=1e-5)
    assert flat.rho < 1e-4
    # ... and then the likelihood-ratio test equals the binomial (score-free) LR test of 120/200
    lr_binom = 2 * (stats.binom.logpmf(120, 200, 0.6) - stats.binom.logpmf(120, 200, 0.5))
    assert flat.extra["lr_statistic"] == pytest.approx(lr_binom, rel=1e-3)


def test_pooled_equivalence_methods():
    k, n = _overdispersed(seed=5, g=40, m=20, mean=0.5, rho=0.02)
    for method in ("cluster-robust", "beta-binomial", "naive"):
        e = pooled_equivalence(k, n, 0.1, method=method)
        inside = 0.4 < e.interval[0] and e.interval[1] < 0.6
        assert e.equivalent == inside, method


def _rows(k_by_observer, n=20, pairs=("a", "b")):
    rows = []
    for i, k in enumerate(k_by_observer):
        for t in range(n):
            rows.append({"participant_id": f"P{i}", "pair_id": pairs[t % len(pairs)], "correct": int(t < k),
                         "rt_ms": 1000 + t})
    return rows


def test_analyse_responses_and_report(tmp_path):
    a = analyse_responses(_rows([15, 10, 12, 9, 14]), delta=0.15)
    assert [g.k for g in a.observers] == [15, 10, 12, 9, 14]
    assert a.observers[0].p_value == pytest.approx(binomial_test(15, 20, alternative="two-sided"))
    assert a.pooled.method == "cluster-robust"
    assert a.pooled.pc == pytest.approx(60 / 100)
    assert {g.name for g in a.pairs} == {"a", "b"}
    text = format_report(a)
    assert "Pooled (cluster-robust" in text and "TOST" in text
    partial = _rows([15, 10, 12]) + _rows([4], n=5)
    for r in partial:
        r["n_trials"] = 20
    for r in partial[-5:]:
        r["participant_id"] = "dropout"
    assert len(analyse_responses(partial).observers) == 4
    assert [g.name for g in analyse_responses(partial, complete_only=True).observers] == ["P0", "P1", "P2"]
    one = analyse_responses(_rows([15]))
    assert one.pooled.method == "naive"
    with pytest.raises(InvalidInputError, match="no responses"):
        analyse_responses([])
    with pytest.raises(InvalidInputError, match="participant_id"):
        analyse_responses([{"correct": 1}])
