"""Calibration of a colourant from measured samples of known recipes (a dilution ladder).

- :class:`LadderSample` — one measured sample: its recipe (raw dict or path) and its measured
  reflectance (on the recipe's grid).
- :func:`calibrate_colourant` — fit what is uncertain about one compound, shared by every
  sample: ``k_scale`` (its absorption k(λ) multiplied by s, with the index changed by the
  Kramers–Kronig transform of the change, so n and k stay causal) and ``size_scale`` (the
  diameters of every pigment of that compound multiplied by d). Returns a
  :class:`CalibrationResult` with the values, their standard errors, ΔE00 of each sample before
  and after, and of the samples left out of the fit.
- :func:`write_calibrated_material` — the calibrated compound as a ``wavelength_nm,n,k`` CSV a
  recipe can name (``[compounds.X] file = "…"``).

Kramers–Kronig. With k' = s·k, the change Δk = (s − 1)·k implies Δn(λ) = (s − 1)·(n_KK[k](λ) − 1),
n_KK the KK integral of k (:func:`nmmm.materials.kramers_kronig.n_from_k`, n_∞ = 1) over the
calibration grid extended by 50 % on each side (k held at its end values): a linear, causal
correction; the absorption outside that window is unchanged, which the data cannot see.

Fit. ``scipy.optimize.least_squares`` (trf) on the stacked spectral residuals (percent) of the
fitted samples, through the full physical model (Mie + adding–doubling of each sample's
recipe); standard errors from σ̂²(JᵀJ)⁻¹ with σ̂² the residual variance. More unknowns than
measured values is an error.

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

__all__ = ["LadderSample", "CalibrationResult", "calibrate_colourant", "write_calibrated_material", "CALIBRATION_PARAMETERS"]

CALIBRATION_PARAMETERS = ("k_scale", "size_scale")


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


class _Sample:
    def __init__(self, s: LadderSample, compound: str):
        from nmmm.recipes.run import _grid, build_materials
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
        self.mats = build_materials(rec, self.w, progress=False)
        self.nk0 = np.asarray(self.mats[compound].nk(self.w))
        self.dn_per_s = _kk_delta_n(self.w, self.nk0.imag)
        pigs = rec.pigments if rec.pigments is not None else ([rec.pigment] if rec.pigment is not None else [])
        self.size_keys = [(f"pigments.{i}.diameter_nm", p.diameter_nm) for i, p in enumerate(pigs)
                          if p.compound == compound and p.diameter_nm is not None]
        self.compound = compound

    def nk(self, s_k):
        return (self.nk0.real + (s_k - 1) * self.dn_per_s) + 1j * s_k * self.nk0.imag

    def reflectance(self, s_k, s_d):
        from nmmm.layers.coat_stack import stack_reflectance
        from nmmm.recipes.paint_stack import _solver, geometry_of, recipe_stack
        from nmmm.recipes.schema import parse_recipe, set_key

        raw = self.raw
        for key, d in self.size_keys:
            raw = set_key(raw, key, float(d) * s_d)
        rec = parse_recipe(raw, base_dir=self.base)
        mats = dict(self.mats)
        mats[self.compound] = self.nk(s_k)
        stack = recipe_stack(rec, mats, self.w)
        return stack_reflectance(stack, self.w, _solver(rec), geometry_of(rec)).reflectance


def _kk_delta_n(w, k):
    """n_KK[k] − 1 on ``w``: KK of k over the grid extended by 50 % each side (module docstring)."""
    from nmmm.materials.kramers_kronig import n_from_k

    span = w[-1] - w[0]
    fine = np.linspace(max(w[0] - 0.5 * span, 50.0), w[-1] + 0.5 * span, 600)
    kf = np.interp(fine, w, k)
    return np.interp(w, fine, np.asarray(n_from_k(kf, fine, n_inf=1.0)) - 1.0)


def calibrate_colourant(samples, compound: str, fit=CALIBRATION_PARAMETERS, left_out=(), illuminant: str = "D65",
                        bounds=None) -> CalibrationResult:
    """Fit ``fit`` (a subset of :data:`CALIBRATION_PARAMETERS`) for ``compound`` on ``samples``
    except those named in ``left_out``, which are only predicted (module docstring)."""
    from scipy.optimize import least_squares

    from nmmm.colour import delta_e2000, spectra_to_lab

    fit = tuple(fit)
    bad = [f for f in fit if f not in CALIBRATION_PARAMETERS]
    if bad or not fit:
        raise InvalidInputError(f"fit must name some of {CALIBRATION_PARAMETERS}, got {fit!r}")
    prepared = [_Sample(s, compound) for s in samples]
    names = [p.name for p in prepared]
    missing = [n for n in left_out if n not in names]
    if missing:
        raise InvalidInputError(f"left_out names {missing}, not among the samples {names}")
    used = [p for p in prepared if p.name not in left_out]
    n_data = sum(p.w.size for p in used)
    if not used or n_data <= len(fit):
        raise InvalidInputError(f"{len(fit)} unknowns from {n_data} measured values in {len(used)} fitted sample(s): "
                                "more unknowns than data — measure more samples or fit fewer parameters")
    if "size_scale" in fit and not any(p.size_keys for p in used):
        raise InvalidInputError(f"size_scale: no fitted sample has a pigment of {compound!r} with diameter_nm")
    lo = np.array([(bounds or {}).get(f, (0.2, 5.0) if f == "k_scale" else (0.3, 3.0))[0] for f in fit])
    hi = np.array([(bounds or {}).get(f, (0.2, 5.0) if f == "k_scale" else (0.3, 3.0))[1] for f in fit])
    count = [0]
    t0 = time.perf_counter()

    def params(x):
        d = dict(zip(fit, x))
        return d.get("k_scale", 1.0), d.get("size_scale", 1.0)

    def residuals(x):
        count[0] += 1
        sk, sd = params(x)
        return np.concatenate([(p.reflectance(sk, sd) - p.R) * 100 for p in used])

    r = least_squares(residuals, np.ones(len(fit)), bounds=(lo, hi), method="trf", diff_step=1e-4, xtol=1e-8, ftol=1e-10)
    dof = max(r.fun.size - len(fit), 1)
    s2 = float(np.sum(r.fun**2)) / dof
    try:
        cov = s2 * np.linalg.inv(r.jac.T @ r.jac)
        se = {f: float(np.sqrt(max(cov[i, i], 0.0))) / 1.0 for i, f in enumerate(fit)}
    except np.linalg.LinAlgError:
        se = {f: float("inf") for f in fit}
    sk, sd = params(r.x)
    before, after, pred = {}, {}, {}
    for p in prepared:
        lab_m = spectra_to_lab(p.w, np.clip(p.R, 0, None), illuminant)
        before[p.name] = float(delta_e2000(lab_m, spectra_to_lab(p.w, p.reflectance(1.0, 1.0), illuminant)))
        pred[p.name] = p.reflectance(sk, sd)
        after[p.name] = float(delta_e2000(lab_m, spectra_to_lab(p.w, pred[p.name], illuminant)))
    return CalibrationResult(compound, dict(zip(fit, (float(v) for v in r.x))), se, before, after, tuple(left_out), count[0],
                             time.perf_counter() - t0, prepared[0].w, prepared[0].nk(sk), pred)


def write_calibrated_material(result: CalibrationResult, path) -> "Path":  # noqa: F821
    """The calibrated compound as ``wavelength_nm,n,k`` CSV (:func:`nmmm.materials.files.write_csv`)."""
    from nmmm.materials.files import write_csv
    from nmmm.materials.material import TabulatedMaterial

    m = TabulatedMaterial(f"{result.compound} (calibrated: {result.values})", result.wavelength_nm, result.nk.real,
                          result.nk.imag, reference="nmmm.matching.calibration")
    return write_csv(m, path, result.wavelength_nm)
