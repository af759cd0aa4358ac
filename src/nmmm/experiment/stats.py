"""Statistics of the two-alternative forced-choice (2AFC) validation experiment.

A participant sees a photograph of a real plate and a computed image of it and picks the
photograph. If the rendering is perfect, the proportion correct ``Pc`` is 0.5 (chance).

Public functions
----------------
- :func:`critical_count` — smallest number correct that is significant in a one-sided
  exact binomial test.
- :func:`binomial_test` — exact binomial test of ``k`` correct out of ``n`` against ``p0``
  (:func:`scipy.stats.binomtest`).
- :func:`dprime_2afc`, :func:`pc_from_dprime_2afc`, :func:`dprime_2afc_counts` — sensitivity
  d' of an unbiased 2AFC observer, ``d' = sqrt(2) z(Pc)``.
- :func:`proportion_ci_wilson`, :func:`proportion_ci_clopper_pearson` and the dispatcher
  :func:`proportion_ci` (registry :data:`PROPORTION_CI_METHODS`).
- :func:`tost_binomial` — exact two one-sided tests (TOST) of equivalence to chance within ±δ.
- :func:`pooled_naive`, :func:`pooled_cluster_robust`, :func:`pooled_beta_binomial` and the
  dispatcher :func:`pooled_proportion` (registry :data:`POOLING_METHODS`) — the pooled
  proportion correct over observers.
- The power of the equivalence test and the observers needed (how many viewers are enough)
  are in :mod:`nmmm.experiment.power_analysis`; :func:`analyse_responses` reports them.
- :func:`analyse_responses` — the whole analysis of a response table (per observer, per pair,
  pooled, power of the design) -> :class:`ExperimentAnalysis`; :func:`format_report` and
  :func:`plot_analysis`.

Pooling over observers
----------------------
Trials of one observer are not independent of each other: observers differ in acuity and
strategy. Treating all trials as one binomial sample (``"naive"``) understates the
uncertainty when observers differ. Two methods account for it:

``"cluster-robust"`` (default)
    The pooled proportion ``p = sum k_i / sum n_i`` with the cluster-robust (sandwich,
    "CR1") standard error of a ratio estimator, ``V = G/(G-1) sum (k_i - p n_i)^2 / N^2``,
    and Student's t with ``G - 1`` degrees of freedom for tests and intervals (Cameron & Miller
    2015). With equal trial counts this is exactly the one-sample t-test of the observers'
    proportions against 0.5, the usual analysis in psychophysics. By default the standard
    error is not allowed below the binomial one, ``sqrt(p(1-p)/N)``.
``"beta-binomial"``
    Each observer's probability correct is drawn from a beta distribution of mean ``mu`` and
    intra-class correlation ``rho``; ``k_i`` is then beta-binomial. ``mu`` and ``rho`` are
    fitted by maximum likelihood; the interval for ``mu`` is the profile-likelihood interval
    and the test of ``mu = 0.5`` a likelihood-ratio test (Williams 1975; Skellam 1948).

(A mixed-effects logistic regression would be a third choice; it needs statsmodels or lme4,
which nmmm does not depend on. Export the CSV for that.)

Equivalence ('indistinguishable within ±δ')
-------------------------------------------
Not rejecting ``Pc = 0.5`` does not show that the images are indistinguishable. The TOST
procedure (Schuirmann 1987) tests ``H0: |Pc - 0.5| >= δ`` against ``H1: |Pc - 0.5| < δ``; it
rejects at level α exactly when the ``1 - 2α`` confidence interval lies inside
``(0.5 - δ, 0.5 + δ)``. ``δ`` is in units of proportion correct (e.g. 0.1 means Pc between
0.4 and 0.6; ``d' = sqrt(2) z(0.6) = 0.36``).

References
----------
- Macmillan, N. A., Creelman, C. D. (2005). *Detection Theory: A User's Guide*, 2nd ed.,
  Lawrence Erlbaum, ch. 7: d' for 2AFC is ``sqrt(2) z(Pc)`` for an unbiased observer.
- Hacker, M. J., Ratcliff, R. (1979). A revised table of d' for M-alternative forced choice.
  *Perception & Psychophysics* 26, 168-170. doi:10.3758/BF03208311
- Wilson, E. B. (1927). Probable inference, the law of succession, and statistical inference.
  *J. Am. Stat. Assoc.* 22, 209-212. doi:10.1080/01621459.1927.10502953
- Clopper, C. J., Pearson, E. S. (1934). The use of confidence or fiducial limits illustrated
  in the case of the binomial. *Biometrika* 26, 404-413. doi:10.1093/biomet/26.4.404
- Newcombe, R. G. (1998). Two-sided confidence intervals for the single proportion: comparison
  of seven methods. *Statistics in Medicine* 17, 857-872.
- Schuirmann, D. J. (1987). A comparison of the two one-sided tests procedure and the power
  approach for assessing the equivalence of average bioavailability. *J. Pharmacokinet.
  Biopharm.* 15, 657-680. doi:10.1007/BF01068419
- Cochran, W. G. (1977). *Sampling Techniques*, 3rd ed., Wiley, ch. 6 (ratio estimators).
- Cameron, A. C., Miller, D. L. (2015). A practitioner's guide to cluster-robust inference.
  *J. Human Resources* 50, 317-372. doi:10.3368/jhr.50.2.317
- Williams, D. A. (1975). The analysis of binary responses from toxicological experiments
  involving reproduction and teratogenicity. *Biometrics* 31, 949-952. doi:10.2307/2529820
- Hautus, M. J. (1995). Corrections for extreme proportions and their biasing effects on
  estimated values of d'. *Behav. Res. Methods Instrum. Comput.* 27, 46-51.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, special, stats

from nmmm.errors import InvalidInputError
from nmmm.experiment.power_analysis import PowerResult, tost_power_analysis

SQRT2 = math.sqrt(2.0)


# -- input checks ---------------------------------------------------------------------
def _counts(k, n):
    k = np.asarray(k)
    n = np.asarray(n)
    for name, a in (("k", k), ("n", n)):
        if a.dtype.kind not in "iuf" or not np.all(np.isfinite(a)) or np.any(a != np.round(a)):
            raise InvalidInputError(f"{name} must be whole numbers (counts of trials), got {a!r}")
    if np.any(n < 1):
        raise InvalidInputError(f"n (number of trials) must be >= 1, got {n!r}")
    if np.any(k < 0) or np.any(k > n):
        raise InvalidInputError(f"k (number correct) must be in [0, n], got k={k!r}, n={n!r}")
    return k.astype(np.int64), n.astype(np.int64)


def _level(confidence):
    if not (0 < confidence < 1):
        raise InvalidInputError(f"confidence must be in (0, 1), e.g. 0.95, got {confidence!r}")
    return float(confidence)


# -- binomial tests -------------------------------------------------------------------
def critical_count(n: int, alpha: float = 0.05, p0: float = 0.5) -> int:
    """Smallest ``k`` with ``P(X >= k | n, p0) <= alpha``: the one-sided exact binomial criterion.

    ``n + 1`` means no count out of ``n`` trials is significant.

    >>> critical_count(20)      # binomial table: 15 of 20 at alpha = 0.05, one-sided
    15
    >>> critical_count(40)
    26
    """
    _counts(0, n)
    if not (0 < alpha < 1) or not (0 < p0 < 1):
        raise InvalidInputError(f"alpha and p0 must be in (0, 1), got alpha={alpha}, p0={p0}")
    k = np.arange(n + 1)
    sf = stats.binom.sf(k - 1, n, p0)  # P(X >= k)
    ok = np.nonzero(sf <= alpha * (1 + 1e-12))[0]
    return int(ok[0]) if ok.size else n + 1


def binomial_test(k: int, n: int, p0: float = 0.5, alternative: str = "greater") -> float:
    """P-value of the exact binomial test of ``k`` correct in ``n`` against ``p0``.

    ``alternative`` is 'greater' (observers pick the photograph more often than chance),
    'less' or 'two-sided' (:func:`scipy.stats.binomtest`).
    """
    k, n = _counts(k, n)
    if alternative not in ("greater", "less", "two-sided"):
        raise InvalidInputError(f"alternative must be 'greater', 'less' or 'two-sided', got {alternative!r}")
    return float(stats.binomtest(int(k), int(n), p0, alternative=alternative).pvalue)


# -- d' for 2AFC --------------------------------------------------------------------------
def dprime_2afc(pc):
    """Sensitivity d' of an unbiased 2AFC observer: ``d' = sqrt(2) * z(Pc)``.

    ``z`` is the inverse of the standard normal CDF.
    Macmillan & Creelman (2005), ch. 7. ``Pc`` = 0 or 1 gives -inf / +inf; use :func:`dprime_2afc_counts` for counts.

    >>> round(float(dprime_2afc(0.76)), 3)    # sqrt(2) * 0.706
    0.999
    >>> float(dprime_2afc(0.5))
    0.0
    """
    pc = np.asarray(pc, dtype=float)
    if np.any(~np.isfinite(pc)) or np.any((pc < 0) | (pc > 1)):
        raise InvalidInputError(f"proportion correct must be in [0, 1], got {pc!r}")
    out = SQRT2 * special.ndtri(pc)
    return out if out.ndim else out[()]


def pc_from_dprime_2afc(dprime):
    """Proportion correct of an unbiased 2AFC observer of sensitivity d': ``Phi(d'/sqrt(2))``."""
    d = np.asarray(dprime, dtype=float)
    out = special.ndtr(d / SQRT2)
    return out if out.ndim else out[()]


def dprime_2afc_counts(k, n, correction: str | None = "loglinear"):
    """d' for 2AFC from ``k`` correct in ``n`` trials, finite at ``k = 0`` or ``k = n``.

    correction:
        'loglinear' — ``Pc = (k + 0.5) / (n + 1)`` always (Hautus 1995);
        '1/(2N)' — only extreme counts move half a trial inwards (Macmillan & Creelman 2005);
        None — no correction (infinite at the extremes).
    """
    k, n = _counts(k, n)
    if correction == "loglinear":
        pc = (k + 0.5) / (n + 1.0)
    elif correction == "1/(2N)":
        pc = np.clip(k / n, 0.5 / n, 1 - 0.5 / n)
    elif correction is None:
        pc = k / n
    else:
        raise InvalidInputError(f"correction must be 'loglinear', '1/(2N)' or None, got {correction!r}")
    return dprime_2afc(pc)


# -- confidence intervals of a proportion ------------------------------------------------
def _binomtest_ci(k, n, confidence, method):
    """``scipy.stats.binomtest(k, n).proportion_ci(confidence, method)`` broadcast over ``k``, ``n``."""
    k, n = _counts(k, n)
    level = _level(confidence)
    k, n = np.broadcast_arrays(k, n)
    lo = np.empty(k.shape)
    hi = np.empty(k.shape)
    for i in np.ndindex(k.shape):
        ci = stats.binomtest(int(k[i]), int(n[i])).proportion_ci(level, method=method)
        lo[i], hi[i] = ci.low, ci.high
    # the bounds are exact at the ends (scipy's Wilson bound at k = 0 is 0 only to rounding)
    lo = np.where(k == 0, 0.0, np.clip(lo, 0, 1))
    hi = np.where(k == n, 1.0, np.clip(hi, 0, 1))
    return (lo[()], hi[()])


def proportion_ci_wilson(k, n, confidence: float = 0.95):
    """Wilson score interval of a binomial proportion (Wilson 1927; Newcombe 1998, method 3),
    computed by :meth:`scipy.stats.binomtest` ``(...).proportion_ci(method="wilson")``.

    Returns ``(lower, upper)`` arrays (broadcast over ``k`` and ``n``).

    >>> lo, hi = proportion_ci_wilson(81, 263)    # Newcombe (1998) example: 0.2553-0.3662
    >>> round(float(lo), 4), round(float(hi), 4)
    (0.2553, 0.3662)
    """
    return _binomtest_ci(k, n, confidence, "wilson")


def proportion_ci_clopper_pearson(k, n, confidence: float = 0.95):
    """Clopper-Pearson 'exact' interval (Clopper & Pearson 1934), computed by
    :meth:`scipy.stats.binomtest` ``(...).proportion_ci(method="exact")``.

    >>> lo, hi = proportion_ci_clopper_pearson(81, 263)  # Newcombe (1998) example: 0.2527-0.3676
    >>> round(float(lo), 4), round(float(hi), 4)
    (0.2527, 0.3676)
    """
    return _binomtest_ci(k, n, confidence, "exact")


#: Confidence-interval methods of a proportion, by name.
PROPORTION_CI_METHODS = {
    "Wilson": proportion_ci_wilson,
    "Clopper-Pearson": proportion_ci_clopper_pearson,
}


def proportion_ci(k, n, confidence: float = 0.95, method: str = "Wilson"):
    """Confidence interval of a binomial proportion; ``method`` from :data:`PROPORTION_CI_METHODS`
    ('Wilson' or 'Clopper-Pearson', case-insensitive; 'exact' is Clopper-Pearson)."""
    key = {m.lower(): m for m in PROPORTION_CI_METHODS}
    key["exact"] = "Clopper-Pearson"
    m = key.get(str(method).lower())
    if m is None:
        raise InvalidInputError(f"unknown interval method {method!r}; choose from {list(PROPORTION_CI_METHODS)}")
    return PROPORTION_CI_METHODS[m](k, n, confidence)


# -- equivalence ----------------------------------------------------------------------
@dataclass(frozen=True)
class EquivalenceResult:
    """Two one-sided tests of ``|Pc - p0| < delta``.

    ``p_value = max(p_lower, p_upper)``; ``interval`` is the ``1 - 2 alpha`` interval whose
    inclusion in ``(p0 - delta, p0 + delta)`` is the same decision.
    """

    delta: float
    alpha: float
    p_lower: float
    p_upper: float
    p_value: float
    interval: tuple[float, float]
    equivalent: bool


def _check_delta(delta, p0=0.5):
    if not (isinstance(delta, (int, float)) and 0 < delta <= min(p0, 1 - p0)):
        raise InvalidInputError(f"equivalence margin delta must be in (0, {min(p0, 1 - p0)}] "
                                f"(units of proportion correct, e.g. 0.1), got {delta!r}")


def tost_binomial(k: int, n: int, delta: float, alpha: float = 0.05, p0: float = 0.5) -> EquivalenceResult:
    """Exact TOST: is the proportion correct within ``p0 ± delta``? (Schuirmann 1987)

    ``p_lower = P(X >= k | p0 - delta)`` tests ``Pc <= p0 - delta``; ``p_upper = P(X <= k | p0 + delta)``
    tests ``Pc >= p0 + delta``. Equivalence is declared when both are below ``alpha``, which is
    the same as the ``1 - 2 alpha`` Clopper-Pearson interval lying inside the margin.
    """
    k, n = _counts(k, n)
    k, n = int(k), int(n)
    _check_delta(delta, p0)
    if not 0 < alpha < 0.5:
        raise InvalidInputError(f"alpha must be in (0, 0.5), got {alpha!r}")
    p_lo = float(stats.binom.sf(k - 1, n, p0 - delta))
    p_hi = float(stats.binom.cdf(k, n, p0 + delta))
    lo, hi = proportion_ci_clopper_pearson(k, n, 1 - 2 * alpha)
    p = max(p_lo, p_hi)
    return EquivalenceResult(float(delta), float(alpha), p_lo, p_hi, p, (float(lo), float(hi)), p < alpha)


# -- pooling over observers -------------------------------------------------------------
@dataclass(frozen=True)
class PooledEstimate:
    """The pooled proportion correct over observers and its inference.

    ``p_value`` is for ``H0: Pc = 0.5`` against ``alternative``; ``interval`` is at
    ``confidence``; ``equivalence`` is set by :func:`analyse_responses`. ``rho`` is the
    intra-class correlation (beta-binomial) or the design-effect based estimate (cluster-robust).
    """

    method: str
    pc: float
    se: float
    interval: tuple[float, float]
    p_value: float
    alternative: str
    n_observers: int
    n_trials: int
    df: float | None = None
    rho: float | None = None
    extra: dict = field(default_factory=dict)


def _one_sided_from_stat(stat, dist_sf, dist_cdf, alternative):
    if alternative == "greater":
        return float(dist_sf(stat))
    if alternative == "less":
        return float(dist_cdf(stat))
    return float(min(1.0, 2 * min(dist_sf(stat), dist_cdf(stat))))


def pooled_naive(k, n, confidence=0.95, alternative="two-sided", interval_method="Wilson", **_):
    """All trials as one binomial sample (ignores observers; for comparison only)."""
    k, n = _counts(k, n)
    K, N = int(k.sum()), int(n.sum())
    p = K / N
    lo, hi = proportion_ci(K, N, confidence, interval_method)
    return PooledEstimate("naive", p, math.sqrt(p * (1 - p) / N), (float(lo), float(hi)),
                          binomial_test(K, N, 0.5, alternative), alternative, int(k.size), N)


def pooled_cluster_robust(k, n, confidence=0.95, alternative="two-sided", floor_binomial=True, **_):
    """Pooled proportion with a cluster-robust (CR1) standard error, t with G - 1 df.

    ``V = G/(G-1) * sum_i (k_i - p n_i)^2 / N^2`` (Cameron & Miller 2015, eq. 11 with the
    G/(G-1) correction) for the ratio estimator ``p = sum k_i / N``. With equal ``n_i`` this is
    ``s^2 / G`` of the observers' proportions: the one-sample t-test. ``floor_binomial``
    keeps the standard error at least the binomial ``sqrt(p(1-p)/N)``.
    """
    k, n = _counts(k, n)
    G = int(k.size)
    if G < 2:
        raise InvalidInputError("cluster-robust pooling needs at least 2 observers; use method='naive'")
    K, N = int(k.sum()), int(n.sum())
    p = K / N
    e = k - p * n
    var = G / (G - 1) * float(np.sum(e**2)) / N**2
    se_binom = math.sqrt(p * (1 - p) / N)
    se = max(math.sqrt(var), se_binom) if floor_binomial else math.sqrt(var)
    df = G - 1
    tq = stats.t.ppf(0.5 + _level(confidence) / 2, df)
    if se > 0:
        t = (p - 0.5) / se
        pv = _one_sided_from_stat(t, lambda x: stats.t.sf(x, df), lambda x: stats.t.cdf(x, df), alternative)
    else:
        pv = 1.0 if p == 0.5 else 0.0
    m = N / G
    deff = (var / se_binom**2) if se_binom > 0 else float("nan")
    rho = (deff - 1) / (m - 1) if m > 1 and np.isfinite(deff) else float("nan")
    return PooledEstimate("cluster-robust", p, se, (float(max(0.0, p - tq * se)), float(min(1.0, p + tq * se))), pv,
                          alternative, G, N, df=df, rho=float(rho), extra={"design_effect": deff})


def _bb_loglik(mu, rho, k, n):
    a = mu * (1 - rho) / rho
    b = (1 - mu) * (1 - rho) / rho
    return float(np.sum(stats.betabinom.logpmf(k, n, a, b)))


_RHO_MIN = 1e-6


def _bb_profile(mu, k, n):
    """max over rho of the beta-binomial log-likelihood at fixed mu -> (loglik, rho)."""
    f = lambda r: -_bb_loglik(mu, special.expit(r), k, n)
    res = optimize.minimize_scalar(f, bounds=(math.log(_RHO_MIN / (1 - _RHO_MIN)), 6.0), method="bounded",
                                   options={"xatol": 1e-7})
    return -res.fun, float(special.expit(res.x))


def pooled_beta_binomial(k, n, confidence=0.95, alternative="two-sided", **_):
    """Beta-binomial maximum likelihood: mean ``mu`` and intra-class correlation ``rho``.

    The interval for ``mu`` is the profile-likelihood interval
    ``2 (l_max - l_p(mu)) <= chi2_1(confidence)``; the test of ``mu = 0.5`` is the
    likelihood-ratio test (one-sided versions use the signed root). ``rho`` is bounded below
    at 1e-6 (the binomial limit).
    """
    k, n = _counts(k, n)
    G = int(k.size)
    if G < 2:
        raise InvalidInputError("beta-binomial pooling needs at least 2 observers; use method='naive'")
    K, N = int(k.sum()), int(n.sum())
    eps = 1e-9
    prof = lambda mu: _bb_profile(mu, k, n)[0]
    if K == 0 or K == N:
        mu_hat = float(np.clip(K / N, eps, 1 - eps))
    else:
        res = optimize.minimize_scalar(lambda x: -prof(special.expit(x)), bracket=(-1.0, 1.0),
                                       options={"xtol": 1e-9})
        mu_hat = float(special.expit(res.x))
    lmax, rho_hat = _bb_profile(mu_hat, k, n)
    crit = stats.chi2.ppf(_level(confidence), 1) / 2
    g = lambda mu: lmax - prof(mu) - crit
    lo = 0.0 if g(eps) <= 0 else optimize.brentq(g, eps, mu_hat, xtol=1e-8) if mu_hat > eps else 0.0
    hi = 1.0 if g(1 - eps) <= 0 else optimize.brentq(g, mu_hat, 1 - eps, xtol=1e-8) if mu_hat < 1 - eps else 1.0
    lr = max(0.0, 2 * (lmax - prof(0.5)))
    signed = math.copysign(math.sqrt(lr), mu_hat - 0.5)
    pv = _one_sided_from_stat(signed, stats.norm.sf, stats.norm.cdf, alternative)
    se = float((hi - lo) / (2 * stats.norm.ppf(0.5 + confidence / 2)))
    return PooledEstimate("beta-binomial", mu_hat, se, (float(lo), float(hi)), pv, alternative, G, N,
                          rho=rho_hat, extra={"loglik": float(lmax), "lr_statistic": float(lr)})


#: Pooling methods over observers, by name.
POOLING_METHODS = {
    "cluster-robust": pooled_cluster_robust,
    "beta-binomial": pooled_beta_binomial,
    "naive": pooled_naive,
}


def pooled_proportion(k, n, method: str = "cluster-robust", confidence: float = 0.95,
                      alternative: str = "two-sided", **kwargs) -> PooledEstimate:
    """Pooled proportion correct over observers (``k[i]`` correct of ``n[i]`` for observer i).

    ``method`` from :data:`POOLING_METHODS`: 'cluster-robust' (default), 'beta-binomial', 'naive'.
    """
    if method not in POOLING_METHODS:
        raise InvalidInputError(f"unknown pooling method {method!r}; choose from {list(POOLING_METHODS)}")
    if alternative not in ("greater", "less", "two-sided"):
        raise InvalidInputError(f"alternative must be 'greater', 'less' or 'two-sided', got {alternative!r}")
    return POOLING_METHODS[method](k, n, confidence=confidence, alternative=alternative, **kwargs)


def pooled_equivalence(k, n, delta, alpha=0.05, method="cluster-robust") -> EquivalenceResult:
    """TOST of the pooled proportion within ``0.5 ± delta`` with the chosen pooling.

    Cluster-robust: two one-sided t-tests with ``G - 1`` df. Beta-binomial and naive: the
    interval-inclusion form with the ``1 - 2 alpha`` interval (Schuirmann 1987).
    """
    _check_delta(delta)
    if method == "naive":
        k_, n_ = _counts(k, n)
        return tost_binomial(int(k_.sum()), int(n_.sum()), delta, alpha)
    est = pooled_proportion(k, n, method=method, confidence=1 - 2 * alpha)
    lo, hi = est.interval
    if method == "cluster-robust" and est.se > 0:
        p_lo = float(stats.t.sf((est.pc - (0.5 - delta)) / est.se, est.df))
        p_hi = float(stats.t.cdf((est.pc - (0.5 + delta)) / est.se, est.df))
    else:
        # p-values from the signed-root likelihood-ratio statistics at the margins
        k_, n_ = _counts(k, n)
        lmax = est.extra.get("loglik")
        def p_at(mu0, upper):
            r = math.sqrt(max(0.0, 2 * (lmax - _bb_profile(mu0, k_, n_)[0])))
            r = math.copysign(r, est.pc - mu0)
            return float(stats.norm.cdf(r) if upper else stats.norm.sf(r))
        p_lo, p_hi = p_at(0.5 - delta, False), p_at(0.5 + delta, True)
    p = max(p_lo, p_hi)
    return EquivalenceResult(float(delta), float(alpha), p_lo, p_hi, p, (float(lo), float(hi)), p < alpha)


# -- whole analysis ---------------------------------------------------------------------
@dataclass(frozen=True)
class GroupSummary:
    """Proportion correct of one observer or one pair."""

    name: str
    k: int
    n: int
    pc: float
    interval: tuple[float, float]
    p_value: float
    dprime: float
    significant: bool
    median_rt_ms: float


@dataclass(frozen=True)
class ExperimentAnalysis:
    """Result of :func:`analyse_responses`."""

    observers: tuple[GroupSummary, ...]
    pairs: tuple[GroupSummary, ...]
    pooled: PooledEstimate
    pooled_naive: PooledEstimate
    pooled_dprime: float
    pooled_dprime_interval: tuple[float, float]
    equivalence: EquivalenceResult
    alpha: float
    confidence: float
    interval_method: str
    alternative: str
    n_responses: int
    power: PowerResult | None = None


def _group(name, correct, rt, confidence, alpha, alternative, interval_method):
    k, n = int(np.sum(correct)), int(len(correct))
    lo, hi = proportion_ci(k, n, confidence, interval_method)
    p = binomial_test(k, n, 0.5, alternative)
    return GroupSummary(str(name), k, n, k / n, (float(lo), float(hi)), p,
                        float(dprime_2afc_counts(k, n, "loglinear")), p < alpha, float(np.median(rt)))


def analyse_responses(rows, *, delta: float = 0.1, alpha: float = 0.05, confidence: float = 0.95,
                      pooling: str = "cluster-robust", alternative: str = "two-sided",
                      interval_method: str = "Wilson", complete_only: bool = False, power: bool = True,
                      target_power: float = 0.8) -> ExperimentAnalysis:
    """Analyse 2AFC responses: per observer, per pair, pooled, and equivalence to chance.

    Parameters
    ----------
    rows : iterable of mappings
        One per answered trial with keys ``participant_id``, ``pair_id`` (or ``label``),
        ``correct`` (0/1) and optionally ``rt_ms`` — e.g. :func:`nmmm.experiment.storage.read_responses`.
    delta : float
        Equivalence margin in proportion correct (0.1: indistinguishable if Pc in (0.4, 0.6)).
    alternative : str
        Of the tests against 0.5: 'two-sided' (default: a rendering systematically judged *more*
        real than the photograph is also distinguishable), 'greater' or 'less'.
    complete_only : bool
        Keep only observers who answered all their trials (rows need ``n_trials``).
    power : bool
        Compute the power of the equivalence test of this design (:func:`tost_power_analysis`):
        the observers and their mean number of trials, a perfect rendering (``Pc = 0.5``), the
        intra-class correlation estimated from the data (0 if negative), and the observers
        needed for ``target_power``.
    """
    _check_delta(delta)
    if not (isinstance(alpha, (int, float)) and 0 < alpha < 0.5):
        raise InvalidInputError(f"alpha (the significance level of each one-sided test) must be in (0, 0.5), "
                                f"e.g. 0.05; got {alpha!r}")
    if not (isinstance(confidence, (int, float)) and 0 < confidence < 1):
        raise InvalidInputError(f"confidence must be in (0, 1), e.g. 0.95; got {confidence!r}")
    rows = list(rows)
    if complete_only:
        answered = {}
        for r in rows:
            answered[r["participant_id"]] = answered.get(r["participant_id"], 0) + 1
        rows = [r for r in rows if answered[r["participant_id"]] >= int(r["n_trials"])]
    if not rows:
        raise InvalidInputError("no responses to analyse (the database holds no answered trial)")
    try:
        obs = np.array([str(r["participant_id"]) for r in rows])
        pair = np.array([str(r.get("label") or r["pair_id"]) for r in rows])
        correct = np.array([int(r["correct"]) for r in rows])
        rt = np.array([float(r.get("rt_ms", np.nan)) for r in rows])
    except (KeyError, TypeError, ValueError) as exc:
        raise InvalidInputError(f"each response needs participant_id, pair_id and correct (0/1): {exc}") from None
    if np.any((correct != 0) & (correct != 1)):
        raise InvalidInputError("'correct' must be 0 or 1")
    args = (confidence, alpha, alternative, interval_method)
    names = list(dict.fromkeys(obs))
    observers = tuple(_group(o, correct[obs == o], rt[obs == o], *args) for o in names)
    pairs = tuple(_group(p, correct[pair == p], rt[pair == p], *args) for p in sorted(set(pair)))
    k = np.array([g.k for g in observers])
    n = np.array([g.n for g in observers])
    method = pooling if len(names) >= 2 else "naive"
    pooled = pooled_proportion(k, n, method=method, confidence=confidence, alternative=alternative,
                               **({"interval_method": interval_method} if method == "naive" else {}))
    naive = pooled_naive(k, n, confidence, alternative, interval_method)
    eq = pooled_equivalence(k, n, delta, alpha, method)
    eps = 0.5 / n.sum()
    d = float(dprime_2afc(np.clip(pooled.pc, eps, 1 - eps)))
    dlo, dhi = (float(x) for x in dprime_2afc(np.clip(pooled.interval, eps, 1 - eps)))
    pw = None
    if power and len(names) >= 2:
        rho = pooled.rho if pooled.rho is not None and np.isfinite(pooled.rho) else 0.0
        pw = tost_power_analysis(len(names), max(1, int(round(n.mean()))), delta, alpha,
                                 rho=float(min(max(rho, 0.0), 0.99)),
                                 method="naive" if method == "naive" else "cluster-robust", target_power=target_power)
    return ExperimentAnalysis(observers, pairs, pooled, naive, d, (dlo, dhi), eq, alpha, confidence,
                              interval_method, alternative, len(rows), pw)


def format_report(a: ExperimentAnalysis) -> str:
    """A plain-text report of an :class:`ExperimentAnalysis`."""
    pct = lambda x: f"{100 * x:5.1f}"
    ci = lambda iv: f"[{pct(iv[0])}, {pct(iv[1])}]"
    conf = f"{100 * a.confidence:g} %"
    lines = [f"2AFC validation: {a.n_responses} responses, {len(a.observers)} observer(s), {len(a.pairs)} pair(s)",
             f"Pc = proportion of trials on which the photograph was picked (chance = 50 %); "
             f"tests {a.alternative}, alpha = {a.alpha:g}; {a.interval_method} {conf} intervals", "",
             "Per observer:", f"  {'observer':<20} {'k/n':>8} {'Pc %':>6} {conf + ' CI':>16} {'p':>8} {'d′':>6} "
             f"{'median RT ms':>13}"]
    for g in a.observers:
        lines.append(f"  {g.name:<20} {f'{g.k}/{g.n}':>8} {pct(g.pc):>6} {ci(g.interval):>16} {g.p_value:8.4f} "
                     f"{g.dprime:6.2f} {g.median_rt_ms:13.0f}{'  *' if g.significant else ''}")
    lines += ["", "Per pair (all observers, trials treated as independent):"]
    for g in a.pairs:
        lines.append(f"  {g.name:<20} {f'{g.k}/{g.n}':>8} {pct(g.pc):>6} {ci(g.interval):>16} {g.p_value:8.4f} "
                     f"{g.dprime:6.2f}{'  *' if g.significant else ''}")
    p, e = a.pooled, a.equivalence
    rho = f", intra-class correlation {p.rho:.3f}" if p.rho is not None and np.isfinite(p.rho) else ""
    lines += ["", f"Pooled ({p.method}{rho}):",
              f"  Pc = {pct(p.pc)} %  {conf} CI {ci(p.interval)}  p = {p.p_value:.4g}  "
              f"d′ = {a.pooled_dprime:.2f} [{a.pooled_dprime_interval[0]:.2f}, {a.pooled_dprime_interval[1]:.2f}]",
              f"  (naive binomial pooling: CI {ci(a.pooled_naive.interval)}, p = {a.pooled_naive.p_value:.4g})",
              f"Equivalence (TOST, Pc within 50 ± {100 * e.delta:g} %): p = {e.p_value:.4g}, "
              f"{100 * (1 - 2 * e.alpha):g} % CI {ci(e.interval)} -> "
              + ("indistinguishable within the margin" if e.equivalent else "equivalence NOT shown"),
              ]
    if a.power is not None:
        w = a.power
        need = (f"{w.observers_needed} observers x {w.n_trials} trials" if w.observers_needed is not None
                else f"more than 10000 observers x {w.n_trials} trials")
        how = "exact" if w.n_sim is None else f"{w.n_sim} simulations"
        lines.append(f"Power of this design: {w.power:.3f} for {w.n_observers} observers x {w.n_trials} trials "
                     f"(TOST ±{100 * w.delta:g} %, alpha {w.alpha:g}, true Pc = {100 * w.pc:g} %, ICC {w.rho:.3f}, "
                     f"{w.method}, {how}); {100 * w.target_power:g} % power needs {need}")
    if p.p_value < a.alpha:
        lines.append("Observers distinguish the rendering from the photograph (Pc differs from chance).")
    else:
        lines.append("No evidence that observers distinguish the rendering from the photograph.")
    return "\n".join(lines)


def plot_analysis(a: ExperimentAnalysis, path=None):
    """Forest plot of Pc per observer and pooled (with the equivalence band), and Pc per pair.

    Writes ``path`` (PNG, PDF, SVG) if given; returns the matplotlib figure.
    """
    import matplotlib

    if path is not None:
        from pathlib import Path

        if not Path(path).parent.is_dir():
            raise InvalidInputError(f"cannot write the plot {path}: the directory {Path(path).parent} does not exist")
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    n_obs, n_pair = len(a.observers), len(a.pairs)
    height = max(3.5, 0.28 * max(n_obs + 2, n_pair) + 1.6)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, height), gridspec_kw={"width_ratios": [1.2, 1]})
    band = (0.5 - a.equivalence.delta, 0.5 + a.equivalence.delta)
    for ax in (ax1, ax2):
        ax.axvspan(*band, color="tab:green", alpha=0.12, lw=0, label=f"equivalence ±{a.equivalence.delta:g}")
        ax.axvline(0.5, color="0.3", lw=1, ls="--", label="chance")
        ax.set_xlim(0, 1)
        ax.set_xlabel("proportion correct (photograph picked)")
    obs = sorted(a.observers, key=lambda g: g.pc)
    y = np.arange(len(obs))
    pcs = np.array([g.pc for g in obs])
    lo = pcs - np.array([g.interval[0] for g in obs])
    hi = np.array([g.interval[1] for g in obs]) - pcs
    colours = ["tab:red" if g.significant else "tab:blue" for g in obs]
    ax1.errorbar(pcs, y, xerr=[lo, hi], fmt="none", ecolor="0.5", lw=1)
    ax1.scatter(pcs, y, c=colours, s=18, zorder=3)
    yp = len(obs) + 0.8
    ax1.errorbar([a.pooled.pc], [yp], xerr=[[a.pooled.pc - a.pooled.interval[0]], [a.pooled.interval[1] - a.pooled.pc]],
                 fmt="D", color="k", ms=7, capsize=4, label=f"pooled ({a.pooled.method})")
    ax1.set_yticks(list(y) + [yp], [g.name for g in obs] + ["pooled"], fontsize=7 if len(obs) > 25 else 9)
    ax1.set_title(f"Observers ({a.interval_method} {100 * a.confidence:g} % CI; red: p < {a.alpha:g})", fontsize=10, pad=30)
    ax1.legend(loc="lower right", fontsize=8)
    sec = ax1.secondary_xaxis("top", functions=(lambda p: dprime_2afc(np.clip(p, 1e-3, 1 - 1e-3)),
                                                 lambda d: pc_from_dprime_2afc(d)))
    sec.set_xticks([-2, -1, 0, 1, 2])
    sec.set_xlabel("d′ (2AFC)")
    pr = list(a.pairs)
    yy = np.arange(len(pr))
    ppc = np.array([g.pc for g in pr])
    ax2.barh(yy, ppc, height=0.5, color=["tab:red" if g.significant else "tab:blue" for g in pr], alpha=0.6)
    ax2.errorbar(ppc, yy, xerr=[ppc - np.array([g.interval[0] for g in pr]),
                                np.array([g.interval[1] for g in pr]) - ppc], fmt="none", ecolor="k", lw=1)
    ax2.set_yticks(yy, [g.name for g in pr], fontsize=8)
    ax2.set_title("Pairs (all observers)", fontsize=10, pad=30)
    ax2.invert_yaxis()
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=130)
        plt.close(fig)
    return fig


__all__ = [
    "critical_count", "binomial_test", "dprime_2afc", "pc_from_dprime_2afc", "dprime_2afc_counts",
    "proportion_ci_wilson", "proportion_ci_clopper_pearson", "proportion_ci", "PROPORTION_CI_METHODS",
    "EquivalenceResult", "tost_binomial", "PooledEstimate", "pooled_naive", "pooled_cluster_robust",
    "pooled_beta_binomial", "pooled_proportion", "POOLING_METHODS", "pooled_equivalence", "GroupSummary",
    "ExperimentAnalysis", "analyse_responses", "format_report", "plot_analysis",
]
