"""Global start of an ellipsometric fit, and the quality check that follows it.

A thick film's χ²(d) has one local minimum per interference order: a local least-squares fit
started 10-50 nm off a 1.2 µm film stops in the neighbouring order with a reduced MSE of
hundreds, and its tiny parameter uncertainty looks like success. The remedy (Fujiwara 2007,
§5.2) is a global scan of every varied layer thickness over its range on a grid finer than the
interference period, before the local fit.

Public functions
----------------
- :func:`thickness_prescan` — scan each varied thickness (one vectorised ``Stack.rt`` call each)
  and start the local fit from the best grid point.
- :func:`check_fit_quality` — the sentence to warn with when the reduced MSE is far above 1.

References
----------
- Fujiwara, H. (2007). *Spectroscopic Ellipsometry: Principles and Applications*. Wiley,
  §5.2 (data analysis procedure, global search). DOI 10.1002/9780470060193.
"""

from __future__ import annotations

import warnings

import numpy as np

__all__ = ["thickness_prescan", "check_fit_quality", "MSE_WARN_THRESHOLD", "PRESCAN_MAX_POINTS"]

#: Reduced MSE (sqrt(χ²/dof), 1 for residuals at the stated σ) above which a fit is reported as
#: not describing the data: residuals ten times the measurement uncertainty are a local minimum
#: or a wrong model, never noise (a good fit of a 1.2 µm Cauchy film gives ~1, its neighbouring
#: interference order ~450). Without σ in the file the MSE is the r.m.s. residual in degrees,
#: and 10° is just as far from a fit.
MSE_WARN_THRESHOLD = 10.0

#: Most grid points of one thickness scan (the grid is coarsened beyond it).
PRESCAN_MAX_POINTS = 4000


def _scan_range(par):
    """The thickness range (nm) scanned for parameter ``par``: its bounds where finite, else
    0.5x-1.5x the start value (within the bounds)."""
    v = par.value
    lo = par.min if np.isfinite(par.min) and par.min > 0 else max(0.5 * v, 0.1)
    hi = par.max if np.isfinite(par.max) else 1.5 * v + 10.0
    lo, hi = max(lo, par.min, 0.1), min(hi, par.max)
    return float(lo), float(hi)


def thickness_prescan(model, data, *, points_per_fringe: int = 8, max_points: int = PRESCAN_MAX_POINTS):
    """Start values for a fit: each varied layer thickness scanned over its range.

    The grid step is ``λ_min / (2 n_max) / points_per_fringe`` (one interference period in
    thickness is λ / (2 n cos θ) ≥ λ / (2 n)), so every order is sampled. Thicknesses are scanned
    one after the other, the others at their current values.

    Returns
    -------
    (model, lines)
        The model with the best thicknesses set, and one line of text per scan (what was
        scanned, how finely, the start value and the one chosen).
    """
    lines = []
    layer_of = {lay.thickness.name: lay.name for lay in model.layers}
    w = np.asarray(data.wavelength_nm, float)
    for par in model.parameters:
        if not par.vary or par.name not in layer_of:
            continue
        lo, hi = _scan_range(par)
        if not hi > lo:
            continue
        try:
            n_max = float(np.max(np.real(model.material(layer_of[par.name]).nk(w))))
        except Exception:  # noqa: BLE001 - a material that cannot be evaluated: use a high index
            n_max = 4.0
        n_max = max(n_max, 1.0)
        step = float(np.min(w)) / (2.0 * n_max) / points_per_fringe
        count = int(min(max_points, max(3, np.ceil((hi - lo) / step) + 1)))
        grid = np.linspace(lo, hi, count)
        start = par.value
        # the grid's real sampling of the narrowest period (coarser than asked once max_points caps it)
        per = (step * points_per_fringe) / (grid[1] - grid[0])
        if per < 2:
            warnings.warn(f"pre-scan {par.name}: the {lo:g}-{hi:g} nm range at {count} points (max_points) samples "
                          f"an interference period only {per:.3g} times (< 2): the scan can miss the interference "
                          "order; narrow the thickness bounds or raise max_points", UserWarning, stacklevel=2)
        with warnings.catch_warnings():
            # the grid's thickest layers are coherent on purpose here: the scan looks for the order
            warnings.filterwarnings("ignore", message=r"layer \d+ .* is coherent but its interference fringes")
            model, _, chi2 = model.scan(data, par.name, grid, set_best=True)
        best = next(p.value for p in model.parameters if p.name == par.name)
        lines.append(f"pre-scan {par.name}: {count} thicknesses {lo:g}-{hi:g} nm (step {grid[1] - grid[0]:.3g} nm, "
                     f"{per:.3g} per interference period): start {start:g} -> {best:g} nm")
    return model, lines


def check_fit_quality(result, threshold: float = MSE_WARN_THRESHOLD) -> str | None:
    """A sentence saying the fit does not describe the data when ``result.mse`` exceeds
    ``threshold`` (:data:`MSE_WARN_THRESHOLD`), else ``None``."""
    mse = float(result.mse)
    if np.isfinite(mse) and mse <= threshold:
        return None
    return (f"the fit's reduced MSE is {mse:.4g}, above {threshold:g} (1 is a fit at the measurement uncertainty): "
            "the model does not describe the data — a local minimum (another interference order: widen the "
            "thickness bounds or the pre-scan) or a wrong model; the uncertainties printed do not hold")
