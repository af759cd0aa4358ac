"""When a solve of :mod:`nmmm.homogenize.fft` is stopped as too slow: the extrapolation of its
residual history (and, with COCG's flux rule, of its flux's estimated error) to ``tol``, and the
monitor that fft_permittivity gives COCG on its default path (issue 22: a solve that would need
far more than ``maxiter`` is stopped early and the other Willot operator takes over).

- :func:`predicted_projections` — the projections a residual history would need to reach ``tol``.
- :func:`flux_prediction`, :func:`solve_prediction` — the same for the flux rule's estimates, and
  for a finished solve (the earlier of the two).
- :func:`slow_solve_monitor` — the ``monitor`` of :func:`~nmmm.homogenize.solvers.solve_cocg`.
- :data:`PREDICT`, :data:`PREDICT_FROM`, :func:`first_prediction` — when the checks start.
"""

from __future__ import annotations

import numpy as np

#: Early detection of a solve that will not reach ``tol`` within ``maxiter`` (default path):
#: from :func:`first_prediction` projections on (PREDICT[0], or PREDICT_FROM × maxiter when
#: later), every 25, the decay rate of the running-minimum residual over the last half of the
#: history is extrapolated to ``tol``; the solve is stopped when the predicted count exceeds
#: PREDICT[1] × maxiter. Krylov convergence near a resonance is superlinear — a slow phase, even a
#: plateau of the best residual, while the Krylov space resolves the near-singular modes, then a
#: fast one — so the linear extrapolation errs long early in a solve: Boolean spheres 16³,
#: ε = −50 + 2i, tol 1e-8 converge in 531 projections where the extrapolation said 2308 at 150;
#: with the rotated operator (willot2015), complex128, tol 1e-6, 16³ spheres at −50 + 1i converge
#: in 510 where it said 15156 at 150 (30×), at −50 + 0.5i in 520 after a plateau (no decrease)
#: at 150, 24³ spheres at −50 + 0.5i in 676 where it said 4230 at 350. Replayed on 132 COCG
#: histories (16³-32³ Boolean spheres, 64² and 128² discs; −50 + 0.5..8i, −44 + 13i, −20 + 0.3i,
#: −10 + 2i, −5 + 0.2i, −3 + 0.5i, −2.5 + 0.05i; both Willot operators; complex64 and complex128)
#: with maxiter from the converged count up: checks from 150 on stopped 49 of those converging
#: solves, from maxiter / 2 on 2, from 0.6 maxiter on none (and still stopped 43 of the 48 solves
#: that did not converge within maxiter, about 1/3 of their maxiter early). A plateau
#: (complex64's floor, no decrease over the last half) is stopped at the first check.
PREDICT = (150, 5.0)
#: The fraction of maxiter before which no prediction is trusted (see :data:`PREDICT`).
PREDICT_FROM = 0.6


def first_prediction(maxiter: int) -> int:
    """The projection count of the first check of a solve's prediction: PREDICT[0], or
    :data:`PREDICT_FROM` × ``maxiter`` when later (earlier, the extrapolation of a superlinear
    solve errs too long)."""
    return max(PREDICT[0], int(np.ceil(PREDICT_FROM * int(maxiter))))


def predicted_projections(history, tol: float) -> float:
    """Projections a solve with relative residual ``history`` (one entry per projection, the
    first before any) would need to reach ``tol``, extrapolating the geometric decay rate of the
    running minimum over the last half of the history; ``inf`` when it no longer decreases.

    >>> h = [10.0 ** (-k / 100) for k in range(201)]   # one decade per 100 projections
    >>> round(predicted_projections(h, 1e-5))
    500
    """
    h = np.minimum.accumulate(np.asarray(history, dtype=float))
    n = h.size - 1
    if n < 2 or h[-1] <= tol:
        return float(n)
    half = max(1, n // 2)
    drop = np.log(h[-1]) - np.log(h[-1 - half])
    if not drop < 0:
        return float("inf")
    return n + (np.log(tol) - np.log(h[-1])) * half / drop


def flux_prediction(flux, tol: float | None = None) -> float:
    """Projections a COCG with the flux rule would need until its estimated flux error reaches its
    tolerance: ``flux = (window, estimates, flux_tol)`` as :func:`~nmmm.homogenize.solvers.solve_cocg`
    gives its monitor (one estimate per projection from ``window`` on), extrapolated like the
    residual (:func:`predicted_projections`). Measured on 128³ flakes
    (benchmarks/bench_fft_metals.py): at −50 + 2i it said 842 at 150 and 787 at 500 for a stop at
    775 (the residual's said 2115 and 1365), at −50 + 1i 2052 at 300 for 1433; it also errs long
    early in a superlinear solve (64³ flakes, −50 + 1i: 1963 at 150 for 419). ``inf`` with fewer than 3
    estimates."""
    window, estimates, ftol = flux
    if len(estimates) < 3:  # nothing to extrapolate yet
        return float("inf")
    return window + predicted_projections(estimates, ftol if tol is None else tol)


def solve_prediction(out, tol: float) -> float:
    """The projections a stopped solve ``out`` (SolveOutcome) was predicted to need: the residual's
    extrapolation (:func:`predicted_projections`), or, for a COCG with the flux rule, the earlier of
    that and the flux estimate's (:func:`flux_prediction`)."""
    pred = predicted_projections(out.history, tol)
    est = getattr(out, "flux_estimates", None)
    if est:  # one estimate per projection from the window on: the window is what the history has more
        pred = min(pred, flux_prediction((len(out.history) - len(est), est, tol)))
    return pred


def slow_solve_monitor(tol: float, maxiter: int, first: int | None = None, margin: float | None = None):
    """A ``monitor(history, flux=None) -> message | None`` for
    :func:`~nmmm.homogenize.solvers.solve_cocg` that stops a solve predicted
    (:func:`predicted_projections`) to need more than ``margin`` × ``maxiter`` projections, checked
    every 25 from ``first`` (default :func:`first_prediction`) on; the message states the
    prediction and the residual reached. With COCG's flux rule (``flux = (window, estimates,
    flux_tol)``) a solve is stopped only when the flux estimate's extrapolation
    (:func:`flux_prediction`) is beyond that too."""
    first = first_prediction(maxiter) if first is None else first
    margin = PREDICT[1] if margin is None else margin

    def monitor(history, flux=None):
        n = len(history) - 1
        if n < first or n % 25:
            return None
        pred = predicted_projections(history, tol)
        if pred > margin * maxiter:
            when = (f"never at its recent rate (no decrease over the last {n // 2} projections)"
                    if not np.isfinite(pred) else f"after ~{pred:.0f} projections")
            also = ""
            if flux is not None:
                fpred = flux_prediction(flux)
                if fpred <= margin * maxiter:
                    return None
                also = (f", and its flux's estimated relative error {flux[1][-1] if flux[1] else float('nan'):.3g} "
                        f"would reach {flux[2]:g} " + ("never at its recent rate" if not np.isfinite(fpred)
                                                      else f"after ~{fpred:.0f} projections"))
            return (f"predicted slow: relative residual {min(history):.3g} after {n} projections would reach "
                    f"tol={tol:g} {when}{also}, beyond maxiter={maxiter}")
        return None

    return monitor


__all__ = ["PREDICT", "PREDICT_FROM", "first_prediction", "predicted_projections", "flux_prediction",
           "solve_prediction", "slow_solve_monitor"]
