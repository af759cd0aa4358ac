"""Power of the 2AFC equivalence test: how many viewers are enough.

- :func:`tost_power` — the power of the TOST that :func:`nmmm.experiment.stats.analyse_responses`
  runs, for ``G`` observers × ``m`` trials each.
- :func:`tost_observers_needed` — the observers needed (``m`` trials each) for a stated power.
- :func:`tost_power_analysis` — both, as a :class:`PowerResult` (what ``nmmm experiment stats``
  prints for the design of the data it analyses).

How many viewers are enough (power of the TOST)
-----------------------------------------------
The power of the equivalence test is the probability that it declares 'indistinguishable
within ±δ' when the rendering is in truth perfect (``Pc = 0.5``, or another ``pc`` inside the
margin). It grows with the number of observers ``G`` and of trials per observer ``m``, and
falls when observers differ: with intra-class correlation ``rho`` the variance of the pooled
proportion is inflated by the design effect ``1 + (m - 1) rho`` (Kish 1965), so past a point
more trials per observer buy little and only more observers help. :func:`tost_power` computes
it for the analysis :func:`~nmmm.experiment.stats.analyse_responses` runs: exactly (a sum over the binomial
distribution of the rejection region) for naive pooling of independent trials, and by Monte
Carlo simulation of beta-binomial observers through the same cluster-robust decision otherwise.
For the seed paper's 40 observers × 20 trials, δ = 0.1, α = 0.05 and a perfect rendering the
power is 0.9999 for identical observers (ρ = 0) and 0.98 for ρ = 0.05 (cluster-robust); at
δ = 0.05 it is 0.71 (ρ = 0; exact naive binomial 0.757) and only 0.27 for ρ = 0.05. 80 % power
at δ = 0.1 with 20 trials each needs 13 observers (ρ = 0) or 23 (ρ = 0.05). The normal
approximation ``2 Φ(δ / se - z_{1-α}) - 1`` with
``se = sqrt(Pc (1 - Pc) (1 + (m - 1) ρ) / (G m))`` (Chow, Shao & Wang 2008, §4.2) gives
nearly the same numbers.

References
----------
- Schuirmann, D. J. (1987). A comparison of the two one-sided tests procedure and the power
  approach for assessing the equivalence of average bioavailability. *J. Pharmacokinet.
  Biopharm.* 15, 657-680. doi:10.1007/BF01068419
- Chow, S.-C., Shao, J., Wang, H. (2008). *Sample Size Calculations in Clinical Research*, 2nd
  ed., Chapman & Hall/CRC, §3.2 and §4.2 (power of the two one-sided tests for equivalence).
- Kish, L. (1965). *Survey Sampling*, Wiley, §5.4 (design effect ``1 + (m - 1) rho`` of cluster samples).
- Cameron, A. C., Miller, D. L. (2015). A practitioner's guide to cluster-robust inference.
  *J. Human Resources* 50, 317-372. doi:10.3368/jhr.50.2.317
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

from nmmm.errors import InvalidInputError


def _check_delta(delta, p0=0.5):
    # the margin check of nmmm.experiment.stats (which imports this module, not the reverse)
    if not (isinstance(delta, (int, float)) and 0 < delta <= min(p0, 1 - p0)):
        raise InvalidInputError(f"equivalence margin delta must be in (0, {min(p0, 1 - p0)}] "
                                f"(units of proportion correct, e.g. 0.1), got {delta!r}")

#: Pooling methods whose TOST power :func:`tost_power` computes.
POWER_METHODS = ("cluster-robust", "naive")


@dataclass(frozen=True)
class PowerResult:
    """Power of the equivalence test (TOST within ``0.5 ± delta``) of one design.

    ``power`` is for ``n_observers`` × ``n_trials`` (per observer) when the true proportion
    correct is ``pc`` and observers differ with intra-class correlation ``rho``;
    ``observers_needed`` is the smallest number of observers (same trials each) with at least
    ``target_power``. ``n_sim`` is None when the power is exact.
    """

    n_observers: int
    n_trials: int
    delta: float
    alpha: float
    pc: float
    rho: float
    method: str
    power: float
    target_power: float
    observers_needed: int | None
    n_sim: int | None


def _check_power_args(n_observers, n_trials, delta, alpha, pc, rho, method):
    for name, v, lo in (("n_observers", n_observers, 1), ("n_trials", n_trials, 1)):
        if not (isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v >= lo):
            raise InvalidInputError(f"{name} must be an integer >= {lo}, got {v!r}")
    _check_delta(delta)
    if not (isinstance(alpha, (int, float)) and 0 < alpha < 0.5):
        raise InvalidInputError(f"alpha must be in (0, 0.5), got {alpha!r}")
    if not (isinstance(pc, (int, float)) and 0 < pc < 1):
        raise InvalidInputError(f"pc (the true proportion correct) must be in (0, 1), got {pc!r}")
    if not (isinstance(rho, (int, float)) and 0 <= rho < 1):
        raise InvalidInputError(f"rho (intra-class correlation) must be in [0, 1), got {rho!r}")
    if method not in POWER_METHODS:
        raise InvalidInputError(f"power is computed for pooling {list(POWER_METHODS)}, got {method!r} "
                                f"(beta-binomial: use 'cluster-robust', its large-sample equivalent)")
    if method == "cluster-robust" and n_observers < 2:
        raise InvalidInputError("cluster-robust pooling needs at least 2 observers")


def _tost_binomial_region(N: int, delta: float, alpha: float) -> np.ndarray:
    """Boolean over k = 0..N: does the exact TOST (:func:`~nmmm.experiment.stats.tost_binomial`) declare equivalence?"""
    k = np.arange(N + 1)
    return (stats.binom.sf(k - 1, N, 0.5 - delta) < alpha) & (stats.binom.cdf(k, N, 0.5 + delta) < alpha)


def _simulate_counts(rng, n_sim, G, m, pc, rho):
    """Counts correct of ``G`` observers × ``m`` trials, ``n_sim`` times: beta-binomial (binomial
    for ``rho = 0``), drawn by inverting the distribution function of ``k = 0..m``."""
    k = np.arange(m + 1)
    if rho > 0:
        pmf = stats.betabinom.pmf(k, m, pc * (1 - rho) / rho, (1 - pc) * (1 - rho) / rho)
    else:
        pmf = stats.binom.pmf(k, m, pc)
    cdf = np.cumsum(pmf)
    cdf[-1] = 1.0
    return np.searchsorted(cdf, rng.random((n_sim, G)), side="right").astype(np.int64)


def _cluster_robust_tost_reject(k, m, delta, alpha):
    """The decision of :func:`~nmmm.experiment.stats.pooled_equivalence` (cluster-robust, binomial floor), vectorised
    over the rows of ``k`` (simulations × observers, ``m`` trials each)."""
    G = k.shape[1]
    N = G * m
    p = k.sum(axis=1) / N
    var = G / (G - 1) * np.sum((k - p[:, None] * m) ** 2, axis=1) / N**2
    se = np.maximum(np.sqrt(var), np.sqrt(p * (1 - p) / N))
    with np.errstate(divide="ignore", invalid="ignore"):
        p_lo = stats.t.sf((p - (0.5 - delta)) / se, G - 1)
        p_hi = stats.t.cdf((p - (0.5 + delta)) / se, G - 1)
    return (se > 0) & (p_lo < alpha) & (p_hi < alpha)


def tost_power(n_observers: int, n_trials: int, delta: float = 0.1, alpha: float = 0.05, *, pc: float = 0.5,
               rho: float = 0.0, method: str = "cluster-robust", n_sim: int = 20000, seed: int = 0) -> float:
    """Power of the equivalence test that :func:`analyse_responses` runs.

    The probability that the TOST declares ``|Pc - 0.5| < delta`` at level ``alpha`` for
    ``n_observers`` observers of ``n_trials`` trials each, when observer ``i`` picks the
    photograph with probability ``p_i ~ Beta`` of mean ``pc`` and intra-class correlation
    ``rho`` (``rho = 0``: every observer has ``pc``).

    ``method='naive'`` with ``rho = 0`` is exact: the sum of the binomial probabilities of the
    counts for which :func:`~nmmm.experiment.stats.tost_binomial` rejects. Otherwise the power is the fraction of
    ``n_sim`` simulated experiments (seeded: the same call gives the same number) in which the
    decision of :func:`~nmmm.experiment.stats.pooled_equivalence` is 'equivalent'; its standard error is at most
    ``0.5 / sqrt(n_sim)`` (0.0035 for 20000).

    >>> round(tost_power(40, 20, 0.1, method="naive"), 4)    # the seed's 40 viewers x 20 trials
    0.9999
    >>> round(tost_power(40, 20, 0.05, method="naive"), 3)
    0.757
    """
    _check_power_args(n_observers, n_trials, delta, alpha, pc, rho, method)
    G, m = int(n_observers), int(n_trials)
    N = G * m
    if method == "naive" and rho == 0:
        region = _tost_binomial_region(N, delta, alpha)
        return float(np.sum(stats.binom.pmf(np.arange(N + 1)[region], N, pc)))
    if not (isinstance(n_sim, int) and n_sim >= 100):
        raise InvalidInputError(f"n_sim must be an integer >= 100, got {n_sim!r}")
    rng = np.random.default_rng(seed)
    hits, done = 0, 0
    chunk = max(100, min(n_sim, 2_000_000 // max(G, 1)))
    region = _tost_binomial_region(N, delta, alpha) if method == "naive" else None
    while done < n_sim:
        n = min(chunk, n_sim - done)
        k = _simulate_counts(rng, n, G, m, pc, rho)
        if method == "naive":
            hits += int(region[k.sum(axis=1)].sum())
        else:
            hits += int(_cluster_robust_tost_reject(k, m, delta, alpha).sum())
        done += n
    return hits / n_sim


def tost_observers_needed(n_trials: int, delta: float = 0.1, power: float = 0.8, alpha: float = 0.05, *,
                          pc: float = 0.5, rho: float = 0.0, method: str = "cluster-robust",
                          max_observers: int = 10_000, n_sim: int = 20000, seed: int = 0) -> int | None:
    """Smallest number of observers (``n_trials`` each) whose TOST has at least ``power``.

    Returns None if even ``max_observers`` do not reach it (e.g. ``pc`` close to the margin).
    The search doubles ``G`` and then bisects, with the same random numbers at every ``G``
    (seeded), so it is reproducible; the exact binomial power is slightly saw-toothed in ``N``,
    so for ``method='naive'`` the bisection is followed by a scan down to the smallest ``G``.

    >>> tost_observers_needed(20, 0.1, 0.8, method="naive")   # 20 trials each, 80 % power
    12
    """
    if not (isinstance(power, (int, float)) and 0 < power < 1):
        raise InvalidInputError(f"power must be in (0, 1), e.g. 0.8, got {power!r}")
    lo_g = 2 if method == "cluster-robust" else 1
    _check_power_args(max(lo_g, 2), n_trials, delta, alpha, pc, rho, method)
    f = lambda g: tost_power(g, n_trials, delta, alpha, pc=pc, rho=rho, method=method, n_sim=n_sim, seed=seed)
    hi = lo_g
    while f(hi) < power:
        if hi >= max_observers:
            return None
        lo_g, hi = hi, min(2 * hi, max_observers)
    if hi == lo_g:
        return hi
    lo = lo_g   # f(lo) < power <= f(hi)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (lo, mid) if f(mid) >= power else (mid, hi)
    if method == "naive":
        while hi > 1 and f(hi - 1) >= power:
            hi -= 1
    return hi


def tost_power_analysis(n_observers: int, n_trials: int, delta: float = 0.1, alpha: float = 0.05, *,
                        pc: float = 0.5, rho: float = 0.0, method: str = "cluster-robust",
                        target_power: float = 0.8, n_sim: int = 20000, seed: int = 0) -> PowerResult:
    """:func:`tost_power` of a design and :func:`tost_observers_needed` for ``target_power``,
    as a :class:`PowerResult`."""
    pw = tost_power(n_observers, n_trials, delta, alpha, pc=pc, rho=rho, method=method, n_sim=n_sim, seed=seed)
    need = tost_observers_needed(n_trials, delta, target_power, alpha, pc=pc, rho=rho, method=method,
                                 n_sim=n_sim, seed=seed)
    exact = method == "naive" and rho == 0
    return PowerResult(int(n_observers), int(n_trials), float(delta), float(alpha), float(pc), float(rho), method,
                       float(pw), float(target_power), need, None if exact else int(n_sim))


__all__ = ["PowerResult", "POWER_METHODS", "tost_power", "tost_observers_needed", "tost_power_analysis"]
