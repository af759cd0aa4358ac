"""Calibration of a colourant from measured samples of known recipes (a dilution ladder).

- :class:`LadderSample` — one measured sample: its recipe (raw dict or path) and its measured
  reflectance (on the recipe's grid).
- :func:`calibrate_colourant` — fit what is uncertain about one compound, shared by every
  sample: a smooth correction of its absorption, ``k_scale`` (k(λ) multiplied by s) and
  ``k_legendre_1`` … ``k_legendre_3`` (Legendre coefficients of the change of ln k over the
  calibration window, :mod:`nmmm.matching.k_correction`), with the index changed by the
  Kramers–Kronig transform of the change of k so n and k stay causal; and ``size_scale`` (the
  diameters of every pigment of that compound multiplied by d). Returns a
  :class:`CalibrationResult` with the values, their standard errors, ΔE00 of each sample before
  and after, and of the samples left out of the fit.
- :func:`write_calibrated_material` — the calibrated compound as a ``wavelength_nm,n,k`` CSV a
  recipe can name (``[compounds.X] file = "…"``), with a header saying how it was made.

The empirical (two-constant Kubelka–Munk, Duncan) calibration of the same ladder is
:func:`nmmm.matching.empirical_km.calibrate_empirical`.

Fit. ``scipy.optimize.least_squares`` (trf) on the stacked spectral residuals (percent) of the
fitted samples, through the full physical model (Mie + adding–doubling of each sample's
recipe); standard errors from σ̂²(JᵀJ)⁻¹ with σ̂² the residual variance (JᵀJ from the
finite-difference Jacobian at the solution). More unknowns than measured values, a parameter
the ladder does not constrain (a zero column of J), samples whose recipes define the compound
differently, or no fitted sample containing it are errors.

References
----------
- E. Allen, "Basic equations used in computer color matching, II. Tristimulus match,
  two-constant theory", J. Opt. Soc. Am. 64, 991 (1974) — the industry's ladder calibration
  (per-unit K and S) that this replaces with the compound's own optics.
- F. Wooten, *Optical Properties of Solids*, Academic Press (1972), §6.4 (KK for N − 1).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.matching.k_correction import K_LEGENDRE_TERMS, corrected_material_nk, kk_delta_n

__all__ = ["LadderSample", "CalibrationResult", "calibrate_colourant", "write_calibrated_material", "CALIBRATION_PARAMETERS",
           "DEFAULT_CALIBRATION_FIT"]

#: Every parameter a physical calibration can fit (a subset is chosen with ``fit=``).
CALIBRATION_PARAMETERS = ("k_scale",) + K_LEGENDRE_TERMS + ("size_scale",)
#: What ``calibrate_colourant`` fits unless told otherwise.
DEFAULT_CALIBRATION_FIT = ("k_scale", "size_scale")
_BOUNDS = {"k_scale": (0.2, 5.0), "size_scale": (0.3, 3.0), **{t: (-2.0, 2.0) for t in K_LEGENDRE_TERMS}}
_START = {"k_scale": 1.0, "size_scale": 1.0, **{t: 0.0 for t in K_LEGENDRE_TERMS}}


@dataclass(frozen=True)
class LadderSample:
    name: str
    recipe: object  # raw dict or path
    reflectance: np.ndarray
    base_dir: object = None  # folder a raw dict's relative files resolve from


@dataclass
class CalibrationResult:
    compound: str
    values: dict
    standard_errors: dict
    de00_before: dict  # sample -> ΔE00 with the uncorrected compound
    de00_after: dict
    left_out: tuple
    evaluations: int
    time_s: float
    wavelength_nm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    nk: np.ndarray = field(default_factory=lambda: np.zeros(0))  # calibrated n + ik on the grid
    predicted: dict = field(default_factory=dict)  # sample -> calibrated spectrum
    window_nm: tuple = (0.0, 0.0)  # the calibration window of the ln k correction
    base_material: object = None  # the uncorrected compound (a Material)
    covariance: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # of the fitted values, in fit order
    illuminant: str = "D65"
    uncalibrated: dict = field(default_factory=dict)  # sample -> spectrum with the uncorrected compound
    warnings: list = field(default_factory=list)  # what the ladder fixes poorly (also issued as IdentifiabilityWarning)

    @property
    def correction(self) -> tuple[float, tuple]:
        """(k_scale, Legendre coefficients) of the fitted k correction (1 and 0 where not fitted)."""
        return _k_params(self.values)

    def calibrated_nk(self, wavelength_nm) -> np.ndarray:
        """The calibrated compound's n + ik at ``wavelength_nm`` (inside the calibration window: outside
        it the ladder says nothing of k, and is an error)."""
        if self.base_material is None:
            raise InvalidInputError("this result carries no base compound; use .nk on .wavelength_nm")
        w = np.asarray(wavelength_nm, float)
        lo, hi = self.window_nm
        if w.size and (w.min() < lo * (1 - 1e-9) or w.max() > hi * (1 + 1e-9)):
            raise InvalidInputError(f"wavelengths {w.min():g}-{w.max():g} nm reach outside the calibration window {lo:g}-{hi:g} nm "
                                    "(the ladder's grid): the correction of k is fitted only there — ask inside it, or "
                                    "calibrate on samples measured over the range you need")
        sk, coef = self.correction
        return corrected_material_nk(self.base_material, w, self.window_nm, sk, coef)


def _k_params(values: dict) -> tuple[float, tuple]:
    coef = [float(values.get(t, 0.0)) for t in K_LEGENDRE_TERMS]
    while coef and coef[-1] == 0.0:
        coef.pop()
    return float(values.get("k_scale", 1.0)), tuple(coef)


_MATERIALS: dict = {}


def _materials(raw, rec, w, base):
    """build_materials of a recipe, shared by ladder samples whose compounds (and levels) are the same:
    a ladder varies fractions, not compounds, and building a database compound is the slow part."""
    import json

    from nmmm.recipes.run import build_materials

    key = json.dumps([raw.get("compounds"), raw.get("levels"), str(base)], sort_keys=True, default=str) + w.tobytes().hex()
    hit = _MATERIALS.get(key)
    if hit is None:
        if len(_MATERIALS) > 16:
            _MATERIALS.clear()
        hit = _MATERIALS[key] = build_materials(rec, w, progress=False)
    return dict(hit)


class _Sample:
    def __init__(self, s: LadderSample, compound: str):
        from nmmm.recipes.run import _grid
        from nmmm.recipes.schema import parse_recipe, read_toml

        raw, _, base = read_toml(s.recipe)
        base = base if base is not None else s.base_dir
        self.raw, self.base, self.name = raw, base, s.name
        rec = parse_recipe(raw, base_dir=base)
        if compound not in rec.compounds:
            raise InvalidInputError(f"sample {s.name!r}: its recipe has no compound {compound!r} ({sorted(rec.compounds)})")
        self.w = _grid(rec)
        R = np.asarray(s.reflectance, float)
        if R.shape != self.w.shape:
            raise InvalidInputError(f"sample {s.name!r}: {R.size} measured values, its recipe's grid has {self.w.size}")
        self.R = R
        self.mats = _materials(raw, rec, self.w, base)
        self.material = self.mats[compound]
        self.nk0 = np.asarray(self.material.nk(self.w))
        pigs = rec.pigments if rec.pigments is not None else ([rec.pigment] if rec.pigment is not None else [])
        if rec.coats is not None:
            pigs = [p for c in rec.coats for p in c.pigments]
        self.amount = sum(p.fraction for p in pigs if p.compound == compound)
        self.size_keys = [(f"pigments.{i}.diameter_nm", p.diameter_nm) for i, p in enumerate(pigs)
                          if p.compound == compound and p.diameter_nm is not None and rec.coats is None]
        self.compound = compound
        self.window = (float(self.w[0]), float(self.w[-1]))
        self.cache = {}

    def nk(self, s_k, coefficients=()):
        """The corrected compound on the sample's grid (KK on a 5 nm grid of the base compound);
        samples sharing a grid share the result (``self.cache``, set by :func:`calibrate_colourant`)."""
        key = (float(s_k), tuple(coefficients), self.window, self.w.tobytes())
        hit = self.cache.get(key)
        if hit is None:
            if len(self.cache) > 64:
                self.cache.clear()
            hit = self.cache[key] = corrected_material_nk(self.material, self.w, self.window, s_k, coefficients)
        return hit

    def reflectance(self, s_k, s_d, coefficients=()):
        from nmmm.layers.coat_stack import stack_reflectance
        from nmmm.recipes.paint_stack import _solver, geometry_of, recipe_stack
        from nmmm.recipes.schema import parse_recipe, set_key

        raw = self.raw
        for key, d in self.size_keys:
            raw = set_key(raw, key, float(d) * s_d)
        rec = parse_recipe(raw, base_dir=self.base)
        mats = dict(self.mats)
        mats[self.compound] = self.nk(s_k, coefficients)
        stack = recipe_stack(rec, mats, self.w)
        return stack_reflectance(stack, self.w, _solver(rec), geometry_of(rec)).reflectance


def _kk_delta_n(w, k):
    """n_KK[k] − 1 on ``w`` (kept for callers of the session-3 name; :func:`kk_delta_n`)."""
    return kk_delta_n(w, k)


def _check_ladder(prepared, used, compound, fit):
    """Errors for a ladder the fit cannot use (module docstring)."""
    ref = prepared[0]
    window = (min(p.window[0] for p in prepared), max(p.window[1] for p in prepared))
    for p in prepared[1:]:
        lo, hi = max(p.w[0], ref.w[0]), min(p.w[-1], ref.w[-1])
        probe = np.linspace(lo, hi, 7) if hi > lo else np.array([lo])
        if not np.allclose(p.material.nk(probe), ref.material.nk(probe), rtol=1e-9, atol=1e-12):
            raise InvalidInputError(f"sample {p.name!r} defines {compound!r} differently from sample {ref.name!r}: a shared "
                                    f"calibration needs one base {compound!r} in every recipe (vary fractions, sizes of "
                                    "other pigments, film or substrate — not the compound being calibrated)")
    if not any(p.amount > 0 for p in used):
        raise InvalidInputError(f"no fitted sample contains {compound!r} (its fractions are 0 in every one): the ladder "
                                f"cannot tell anything about it — fit on samples with {compound!r} in them")
    if "size_scale" in fit and not any(p.size_keys and p.amount > 0 for p in used):
        raise InvalidInputError(f"size_scale: no fitted sample has a pigment of {compound!r} with diameter_nm "
                                "(a [[pigments]] entry; sizes inside [[coats]] are not calibrated)")
    return window


def calibrate_colourant(samples, compound: str, fit=DEFAULT_CALIBRATION_FIT, left_out=(), illuminant: str = "D65",
                        bounds=None) -> CalibrationResult:
    """Fit ``fit`` (a subset of :data:`CALIBRATION_PARAMETERS`) for ``compound`` on ``samples``
    except those named in ``left_out``, which are only predicted (module docstring)."""
    from scipy.optimize import least_squares

    from nmmm.colour import delta_e2000, spectra_to_lab

    fit = tuple(fit)
    bad = [f for f in fit if f not in CALIBRATION_PARAMETERS]
    if bad or not fit or len(set(fit)) != len(fit):
        raise InvalidInputError(f"fit must name some of {CALIBRATION_PARAMETERS} (each once), got {fit!r}")
    prepared = [_Sample(s, compound) for s in samples]
    names = [p.name for p in prepared]
    missing = [n for n in left_out if n not in names]
    if missing:
        raise InvalidInputError(f"left_out names {missing}, not among the samples {names}")
    used = [p for p in prepared if p.name not in left_out]
    window = _check_ladder(prepared, used, compound, fit) if used else None
    n_data = sum(p.w.size for p in used if p.amount > 0)
    if not used or n_data <= len(fit):
        raise InvalidInputError(f"{len(fit)} unknowns from {n_data} measured values in {len(used)} fitted sample(s) that "
                                f"hold {compound!r}: more unknowns than data — measure more samples or fit fewer parameters")
    shared = {}
    for p in prepared:
        p.window, p.cache = window, shared
    bounds = bounds or {}
    lo = np.array([bounds.get(f, _BOUNDS[f])[0] for f in fit])
    hi = np.array([bounds.get(f, _BOUNDS[f])[1] for f in fit])
    count = [0]
    t0 = time.perf_counter()

    def params(x):
        d = dict(zip(fit, (float(v) for v in x)))
        sk, coef = _k_params(d)
        return sk, d.get("size_scale", 1.0), coef

    def residuals(x):
        count[0] += 1
        sk, sd, coef = params(x)
        return np.concatenate([(p.reflectance(sk, sd, coef) - p.R) * 100 for p in informative])

    informative = [p for p in used if p.amount > 0]  # a sample without the compound does not depend on it
    x0 = np.clip([_START[f] for f in fit], lo, hi)
    r = least_squares(residuals, x0, bounds=(lo, hi), method="trf", diff_step=1e-4, xtol=1e-7, ftol=1e-7)
    col = np.linalg.norm(r.jac, axis=0)
    if np.any(col <= 1e-9 * max(col.max(), 1e-300)):
        dead = [f for f, c in zip(fit, col) if c <= 1e-9 * max(col.max(), 1e-300)]
        raise InvalidInputError(f"the ladder does not constrain {dead}: the fitted samples' spectra do not change with it "
                                "— drop it from fit or add samples that depend on it")
    dof = max(r.fun.size - len(fit), 1)
    s2 = float(np.sum(r.fun**2)) / dof
    try:
        cov = s2 * np.linalg.inv(r.jac.T @ r.jac)
        se = {f: float(np.sqrt(max(cov[i, i], 0.0))) for i, f in enumerate(fit)}
    except np.linalg.LinAlgError:
        cov = np.full((len(fit), len(fit)), np.inf)
        se = {f: float("inf") for f in fit}
    notes = _identifiability(fit, r.x, se, cov, r.active_mask, lo, hi)
    sk, sd, coef = params(r.x)
    before, after, pred, unc = {}, {}, {}, {}
    for p in prepared:
        lab_m = spectra_to_lab(p.w, np.clip(p.R, 0, None), illuminant)
        unc[p.name] = p.reflectance(1.0, 1.0)
        before[p.name] = float(delta_e2000(lab_m, spectra_to_lab(p.w, unc[p.name], illuminant)))
        pred[p.name] = p.reflectance(sk, sd, coef)
        after[p.name] = float(delta_e2000(lab_m, spectra_to_lab(p.w, pred[p.name], illuminant)))
    return CalibrationResult(compound, dict(zip(fit, (float(v) for v in r.x))), se, before, after, tuple(left_out), count[0],
                             time.perf_counter() - t0, prepared[0].w, prepared[0].nk(sk, coef), pred, window,
                             prepared[0].material, cov, illuminant, unc, notes)


#: a fitted value is poorly fixed when its standard error exceeds this (relative for the scales, absolute
#: for the Legendre coefficients of ln k), or two values are nearly degenerate past this correlation
SE_WARNING, CORRELATION_WARNING = 0.1, 0.95


def _identifiability(fit, x, se, cov, active=None, lo=None, hi=None) -> list[str]:
    """Messages for values the ladder fixes poorly, each issued as an IdentifiabilityWarning; a value
    stopped at its bound is one (its standard error describes the bound, not the ladder)."""
    import warnings

    from nmmm.matching.recipe_match import IdentifiabilityWarning

    notes = []
    for i, f in enumerate(fit):
        if active is not None and active[i] != 0:
            notes.append(f"{f} = {x[i]:.4g} stopped at its bound [{lo[i]:g}, {hi[i]:g}]: the ladder asks for a value beyond "
                         "it and the standard error does not hold — widen bounds= or check the ladder's recipes")
    for i, f in enumerate(fit):
        rel = se[f] / abs(x[i]) if f in ("k_scale", "size_scale") else se[f]
        if not np.isfinite(rel) or rel > SE_WARNING:
            notes.append(f"{f} = {x[i]:.4g} ± {se[f]:.2g}: poorly fixed by this ladder (add samples: tints at other "
                         "concentrations, a draw-down over black)")
    d = np.sqrt(np.clip(np.diag(cov), 1e-300, None))
    with np.errstate(invalid="ignore"):
        rho = cov / np.outer(d, d)
    for i in range(len(fit)):
        for j in range(i + 1, len(fit)):
            if np.isfinite(rho[i, j]) and abs(rho[i, j]) > CORRELATION_WARNING:
                notes.append(f"{fit[i]} and {fit[j]} are correlated {rho[i, j]:+.3f} on this ladder: it tells them apart "
                             "poorly (tints with white and a film over black separate absorption from size)")
    for n in notes:
        warnings.warn(n, IdentifiabilityWarning, stacklevel=3)
    return notes


def write_calibrated_material(result: CalibrationResult, path, step_nm: float | None = None, source: str = "") -> "Path":  # noqa: F821
    """The calibrated compound as a ``wavelength_nm,n,k`` CSV (:func:`nmmm.materials.files.read_csv`
    reads it), its header citing how it was made: the base compound, the correction, the fitted
    values with their standard errors, the samples fitted and left out, ``source`` (e.g. the ladder
    file). ``step_nm``: sample the calibration window at this step (the base compound evaluated
    there, the smooth correction applied); default the calibration grid itself."""
    from nmmm.atomic_io import atomic_write_text

    if step_nm is not None and result.base_material is not None:
        lo, hi = result.window_nm
        w = np.unique(np.concatenate([np.arange(lo, hi + 1e-9, float(step_nm)), [hi]]))
        nk = result.calibrated_nk(w)
    else:
        w, nk = result.wavelength_nm, result.nk
    sk, coef = result.correction
    fitted = [n for n in result.de00_after if n not in result.left_out]
    base = getattr(result.base_material, "name", result.compound)
    lines = [f"# name: {result.compound} (calibrated)",
             f"# reference: nmmm.matching.calibrate_colourant{' on ' + source if source else ''}; base compound {base}",
             "# method: k(λ) multiplied by s·exp(Σ c_j P_j(x)) (Legendre P_j, x = λ mapped onto [-1, 1] over "
             f"{result.window_nm[0]:g}-{result.window_nm[1]:g} nm); n changed by the Kramers-Kronig transform of the change "
             "of k (nmmm.matching.k_correction), so n and k stay causal",
             "# fitted: " + ", ".join(f"{k} = {v:.6g} ± {result.standard_errors.get(k, float('nan')):.2g}"
                                      for k, v in result.values.items()),
             f"# samples fitted: {', '.join(fitted)}; left out: {', '.join(result.left_out) or 'none'}",
             "# ΔE00 after (" + result.illuminant + "): " + ", ".join(f"{k} {v:.3f}" for k, v in result.de00_after.items())]
    if "size_scale" in result.values:
        lines.append(f"# grain size (not in this file): multiply the compound's diameter_nm by {result.values['size_scale']:.6g}")
    lines.append(f"# k scale {sk:.6g}, Legendre coefficients {list(coef)}")
    lines.append("wavelength_nm,n,k")
    lines += [f"{x:.6g},{v.real:.8g},{max(v.imag, 0.0):.8g}" for x, v in zip(np.ravel(w), np.ravel(nk))]
    return atomic_write_text(path, "\n".join(lines) + "\n")
