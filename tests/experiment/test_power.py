"""Power of the equivalence test (issue 20 item 4), checked against independent computations:
the TOST functions themselves run on simulated experiments, and the normal approximation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from nmmm.errors import InvalidInputError
from nmmm.experiment.power_analysis import tost_observers_needed, tost_power, tost_power_analysis
from nmmm.experiment.stats import analyse_responses, format_report, pooled_equivalence, tost_binomial


def _normal_power(G, m, delta, alpha, rho=0.0, pc=0.5):
    """Chow, Shao & Wang (2008) §4.2: 2 Phi(delta/se - z_(1-alpha)) - 1 with the design effect."""
    se = math.sqrt(pc * (1 - pc) * (1 + (m - 1) * rho) / (G * m))
    return max(0.0, 2 * stats.norm.cdf(delta / se - stats.norm.ppf(1 - alpha)) - 1)


def test_exact_power_is_the_rate_at_which_tost_binomial_rejects():
    G, m, delta = 12, 20, 0.1
    N = G * m
    exact = tost_power(G, m, delta, method="naive")
    rng = np.random.default_rng(3)
    K = rng.binomial(N, 0.5, size=4000)
    decide = {k: tost_binomial(int(k), N, delta).equivalent for k in np.unique(K)}
    mc = np.mean([decide[k] for k in K])
    se = math.sqrt(exact * (1 - exact) / K.size)
    assert abs(mc - exact) < 4 * se + 1e-3, (mc, exact)
    # a true Pc on the margin: the exact TOST keeps its level (power <= alpha)
    assert tost_power(G, m, delta, pc=0.6, method="naive") <= 0.05


@pytest.mark.parametrize("rho", [0.0, 0.1])
def test_simulated_power_is_the_rate_at_which_pooled_equivalence_rejects(rho):
    G, m, delta = 10, 20, 0.1
    fast = tost_power(G, m, delta, rho=rho, n_sim=20000, seed=1)
    rng = np.random.default_rng(11)
    n = 1500
    hits = 0
    for _ in range(n):
        if rho > 0:   # scipy's own beta-binomial sampler, not the power function's
            a = 0.5 * (1 - rho) / rho
            k = stats.betabinom.rvs(m, a, a, size=G, random_state=rng)
        else:
            k = rng.binomial(m, 0.5, size=G)
        hits += pooled_equivalence(k, np.full(G, m), delta).equivalent
    mc = hits / n
    se = math.sqrt(fast * (1 - fast) / n) + math.sqrt(fast * (1 - fast) / 20000)
    assert abs(mc - fast) < 4 * se + 1e-3, (mc, fast)


@pytest.mark.parametrize("G, m, delta, rho", [(40, 20, 0.05, 0.0), (100, 20, 0.05, 0.05), (60, 10, 0.06, 0.1)])
def test_power_follows_the_normal_approximation_for_large_designs(G, m, delta, rho):
    approx = _normal_power(G, m, delta, 0.05, rho)
    assert abs(tost_power(G, m, delta, rho=rho) - approx) < 0.06, approx
    if rho == 0:
        assert abs(tost_power(G, m, delta, method="naive") - approx) < 0.03


def test_seed_design_40_observers_20_trials():
    # the numbers stated in the stats module docstring
    assert tost_power(40, 20, 0.1, method="naive") == pytest.approx(0.99994, abs=1e-5)
    assert tost_power(40, 20, 0.1) > 0.999
    assert tost_power(40, 20, 0.1, rho=0.05) == pytest.approx(0.98, abs=0.01)
    assert tost_power(40, 20, 0.05) == pytest.approx(0.71, abs=0.015)
    assert tost_power(40, 20, 0.05, method="naive") == pytest.approx(0.757, abs=1e-3)
    assert tost_power(40, 20, 0.05, rho=0.05) == pytest.approx(0.27, abs=0.015)


def test_observers_needed_is_the_smallest_that_reaches_the_power():
    for method, rho in (("naive", 0.0), ("cluster-robust", 0.0), ("cluster-robust", 0.05)):
        g = tost_observers_needed(20, 0.1, 0.8, method=method, rho=rho)
        assert tost_power(g, 20, 0.1, method=method, rho=rho) >= 0.8
        assert tost_power(g - 1, 20, 0.1, method=method, rho=rho) < 0.8
    # the normal-theory sample size (z_(1-alpha) + z_(1-beta/2))^2 Pc(1-Pc)/delta^2 = 214 trials
    n_normal = (stats.norm.ppf(0.95) + stats.norm.ppf(0.9)) ** 2 * 0.25 / 0.1**2
    assert abs(tost_observers_needed(20, 0.1, 0.8, method="naive") - n_normal / 20) <= 2
    # heterogeneous observers need more of them; a margin the truth sits on is never reached
    assert tost_observers_needed(20, 0.1, 0.8, rho=0.05) > tost_observers_needed(20, 0.1, 0.8)
    assert tost_observers_needed(20, 0.1, 0.8, pc=0.6, method="naive", max_observers=64) is None


def test_power_inputs_are_checked():
    for kw, word in [({"n_observers": 0}, "n_observers"), ({"delta": 0.7}, "delta"), ({"pc": 1.0}, "pc"),
                     ({"rho": -0.1}, "rho"), ({"method": "beta-binomial"}, "cluster-robust")]:
        args = {"n_observers": 10, "n_trials": 20, **kw}
        with pytest.raises(InvalidInputError, match=word):
            tost_power(**args)
    with pytest.raises(InvalidInputError, match="power"):
        tost_observers_needed(20, power=1.5)


def test_analysis_and_report_state_the_power_of_the_design():
    rng = np.random.default_rng(0)
    rows = [{"participant_id": f"S{i}", "pair_id": f"p{t % 5}", "correct": int(rng.random() < 0.5), "rt_ms": 900}
            for i in range(40) for t in range(20)]
    a = analyse_responses(rows, delta=0.1)
    assert a.power.n_observers == 40 and a.power.n_trials == 20 and a.power.method == "cluster-robust"
    expected = tost_power_analysis(40, 20, 0.1, rho=a.power.rho)
    assert a.power == expected and a.power.power > 0.95
    text = format_report(a)
    assert "Power of this design: " in text and "40 observers x 20 trials" in text
    assert f"80 % power needs {expected.observers_needed} observers x 20 trials" in text
