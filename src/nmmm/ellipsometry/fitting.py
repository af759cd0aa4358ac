"""Weighted least-squares fitting of Ψ and Δ: parameters, uncertainties, correlations, diagnostics.

Public objects
--------------
- :class:`Parameter` — one fit parameter: value, bounds, whether it varies, unit.
- :class:`FitAtBoundWarning` — issued when a fitted parameter ends on one of its bounds.
- :class:`FitResult` — best values, standard uncertainties, covariance and correlation
  matrices, χ², Woollam's MSE, residuals, the cost history; ``summary()`` prints them.
- :func:`fit_psi_delta` — fit any model ``build(values) -> Stack`` to an
  :class:`~nmmm.ellipsometry.data.EllipsometryData` set over all its angles at once.
- :func:`psi_delta_residuals` — the weighted residual vector (Ψ then Δ).
- :func:`least_squares_fit` — the engine, for any residual function.

Method
------
The objective is χ² = Σ [(Ψ_mod − Ψ_exp)/σΨ]² + [wrap(Δ_mod − Δ_exp)/σΔ]² over the N
(wavelength, angle) points, with Δ differences wrapped into (−180°, 180°]; it is minimised by
:func:`scipy.optimize.least_squares` (trust-region reflective, bounds respected), with
parameters scaled by their typical size. At the optimum the covariance is

    C = (JᵀJ)⁻¹             (σ given: absolute uncertainties), or
    C = (JᵀJ)⁻¹ · χ²/(2N − M) (no σ in the data: unit weights, scaled by the reduced χ²),

computed from the SVD of the weighted Jacobian J (Press et al., *Numerical Recipes*, ch. 15;
Fujiwara 2007, ch. 5). Standard uncertainties are √diag C; the correlation is
C_ij/√(C_ii C_jj). The fit reports the mean-squared error of J. A. Woollam's WVASE,
MSE = √(χ²/(2N − M)) (Fujiwara 2007, ch. 5, with σ weights).

A fit that did not converge (evaluation budget exhausted, non-finite model values) or whose
parameters the data cannot determine (a singular Jacobian: a parameter without effect, or two
parameters perfectly correlated) raises :class:`nmmm.ConvergenceError` carrying the cost
history and a diagnosis; it never returns silently wrong parameters. A fit that ends with a
parameter on one of its bounds is a constrained optimum, not a minimum of χ²: the covariance
(a local quadratic approximation) does not describe it. It returns, lists those parameters in
``FitResult.at_bound`` and issues a :class:`FitAtBoundWarning` per parameter.

References
----------
- H. Fujiwara, *Spectroscopic Ellipsometry: Principles and Applications*, Wiley (2007), ch. 5 (data analysis).
- W. H. Press et al., *Numerical Recipes*, 3rd ed., Cambridge University Press (2007), ch. 15.
- G. E. Jellison Jr., "Data analysis for spectroscopic ellipsometry", Thin Solid Films 234,
  416 (1993), doi:10.1016/0040-6090(93)90298-4 (uncertainties and correlations).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np
from scipy.optimize import least_squares

from nmmm.ellipsometry.forward import psi_delta, wrap_delta
from nmmm.errors import ConvergenceError, InvalidInputError, NmmmError

__all__ = ["Parameter", "FitResult", "FitAtBoundWarning", "fit_psi_delta", "psi_delta_residuals", "least_squares_fit"]


class FitAtBoundWarning(UserWarning):
    """A fitted parameter ended on one of its bounds: its value is set by the bound, not by the
    data, and its reported uncertainty is not meaningful."""


@dataclass(frozen=True)
class Parameter:
    """A model parameter. ``vary=False`` holds it fixed; ``min``/``max`` bound the fit."""

    name: str
    value: float
    vary: bool = True
    min: float = -np.inf
    max: float = np.inf
    unit: str = ""

    def __post_init__(self):
        v = float(self.value)
        lo, hi = float(self.min), float(self.max)
        if not np.isfinite(v):
            raise InvalidInputError(f"parameter {self.name}: value must be finite, got {self.value!r}")
        if not lo < hi:
            raise InvalidInputError(f"parameter {self.name}: need min < max, got [{lo:g}, {hi:g}]")
        if not lo <= v <= hi:
            raise InvalidInputError(f"parameter {self.name}: start value {v:g} is outside its bounds [{lo:g}, {hi:g}]")
        object.__setattr__(self, "value", v)
        object.__setattr__(self, "min", lo)
        object.__setattr__(self, "max", hi)


@dataclass(frozen=True, repr=False)
class FitResult:
    """Outcome of a converged fit.

    Attributes
    ----------
    parameters : tuple of Parameter
        All parameters, with their fitted values.
    names : tuple of str
        Names of the varied parameters, in the order of the matrices.
    stderr : dict
        Standard uncertainty of each varied parameter (same unit as the parameter).
    covariance, correlation : ndarray (M, M)
    chi2 : float
        Σ of squared weighted residuals.
    dof : int
        Number of residuals minus number of varied parameters.
    mse : float
        √(χ²/dof), WVASE's MSE (≈ 1 for a good model and honest σ).
    absolute_sigma : bool
        True when the data's σ were used as absolute uncertainties.
    residuals : ndarray
        Weighted residuals at the optimum (Ψ block then Δ block).
    nfev : int
    message : str
    cost_history : tuple of float
        χ² after each model evaluation (diagnostics).
    model : object
        What the model builder returned for the best values (e.g. the fitted Stack).
    at_bounds : tuple of str
        Parameters that ended on a bound (their uncertainty is not meaningful); also
        available as :attr:`at_bound`.
    """

    parameters: tuple
    names: tuple
    stderr: dict
    covariance: np.ndarray
    correlation: np.ndarray
    chi2: float
    dof: int
    mse: float
    absolute_sigma: bool
    residuals: np.ndarray
    nfev: int
    message: str
    cost_history: tuple = ()
    model: object = None
    at_bounds: tuple = ()
    extra: dict = field(default_factory=dict)

    @property
    def values(self) -> dict:
        """name -> fitted value, for every parameter (fixed ones included)."""
        return {p.name: p.value for p in self.parameters}

    @property
    def at_bound(self) -> tuple:
        """Names of the varied parameters that ended on a bound (a :class:`FitAtBoundWarning`
        was issued for each); empty for an unconstrained optimum."""
        return self.at_bounds

    @property
    def reduced_chi2(self) -> float:
        return self.mse**2

    def __getitem__(self, name: str) -> float:
        return self.values[name]

    def __repr__(self) -> str:
        return f"<FitResult MSE={self.mse:.4g}, {len(self.names)} varied parameters>"

    def summary(self) -> str:
        """A readable table: values ± uncertainties, fit statistics, strong correlations."""
        lines = [f"fit: MSE = {self.mse:.4g}  (chi2 = {self.chi2:.6g}, dof = {self.dof}, "
                 f"{'absolute sigma' if self.absolute_sigma else 'unit weights scaled by reduced chi2'}), "
                 f"{self.nfev} model evaluations", ""]
        width = max(len(p.name) for p in self.parameters)
        for p in self.parameters:
            unit = f" {p.unit}" if p.unit else ""
            if p.name in self.stderr:
                flag = "  (at bound: uncertainty not meaningful)" if p.name in self.at_bounds else ""
                lines.append(f"  {p.name:<{width}} = {p.value:.6g} ± {self.stderr[p.name]:.2g}{unit}{flag}")
            else:
                lines.append(f"  {p.name:<{width}} = {p.value:.6g}{unit}  (fixed)")
        m = len(self.names)
        strong = [(self.names[i], self.names[j], self.correlation[i, j])
                  for i in range(m) for j in range(i + 1, m) if abs(self.correlation[i, j]) > 0.9]
        if strong:
            lines += ["", "  strong correlations (|r| > 0.9):"]
            lines += [f"    {a} / {b}: {r:+.3f}" for a, b, r in strong]
        return "\n".join(lines)

    def correlation_table(self) -> str:
        """The correlation matrix as text."""
        w = max(len(n) for n in self.names)
        head = " " * (w + 2) + " ".join(f"{i:>7d}" for i in range(len(self.names)))
        rows = [f"{n:<{w}}  " + " ".join(f"{v:+7.3f}" for v in row) for n, row in zip(self.names, self.correlation)]
        return "\n".join([head] + rows)


def least_squares_fit(residual_function: Callable, parameters, *,
                      absolute_sigma: bool = True, max_nfev: int | None = None, ftol: float = 1e-10,
                      xtol: float = 1e-10, gtol: float = 1e-10, rcond: float = 1e-10,
                      build: Callable | None = None, diff_step: float | None = None) -> FitResult:
    """Minimise Σ residual² over the varied ``parameters``.

    ``residual_function(values: dict) -> 1-D array`` of weighted residuals. Returns a
    :class:`FitResult`; raises :class:`ConvergenceError` (see the module docstring) or
    :class:`InvalidInputError` (fewer residuals than varied parameters).
    """
    params = tuple(parameters)
    names_all = [p.name for p in params]
    if len(set(names_all)) != len(names_all):
        raise InvalidInputError(f"duplicate parameter names in {names_all}")
    varied = [p for p in params if p.vary]
    if not varied:
        raise InvalidInputError("no parameter varies: set vary=True (fit = true) on at least one")
    names = tuple(p.name for p in varied)
    fixed = {p.name: p.value for p in params if not p.vary}
    x0 = np.array([p.value for p in varied])
    lo = np.array([p.min for p in varied])
    hi = np.array([p.max for p in varied])
    scale = np.where(np.abs(x0) > 0, np.abs(x0), 1.0)

    history: list[float] = []

    def values_of(x):
        v = dict(fixed)
        v.update(zip(names, (float(t) for t in x)))
        return {n: v[n] for n in names_all}

    state = {"n_res": None, "last_error": None}

    def fun(x):
        try:
            r = np.asarray(residual_function(values_of(x)), dtype=float)
        except NmmmError as exc:
            if state["n_res"] is None:  # the start values themselves are not valid
                raise InvalidInputError(f"the model cannot be evaluated at the start values: {exc}") from None
            # a trial step gave non-physical parameters (e.g. Tauc-Lorentz needs E0 > Eg):
            # a large, finite penalty sends the trust region back
            state["last_error"] = str(exc)
            history.append(float("nan"))
            return np.full(state["n_res"], 1e6)
        if not np.all(np.isfinite(r)):
            raise ConvergenceError(
                f"the model gave non-finite Psi/Delta at parameters {values_of(x)}; bound the parameters "
                "(min/max) to a physical region", history=list(history))
        history.append(float(r @ r))
        return r

    r0 = fun(x0)
    n_res = state["n_res"] = r0.size
    m = len(varied)
    if n_res <= m:
        raise InvalidInputError(
            f"{n_res} residuals (data points x 2) for {m} varied parameters: need more data than "
            "parameters; fix some parameters (vary=False) or add wavelengths/angles")
    if max_nfev is None:
        max_nfev = 200 * (m + 1)
    res = least_squares(fun, x0, bounds=(lo, hi), x_scale=scale, method="trf", ftol=ftol, xtol=xtol,
                        gtol=gtol, max_nfev=max_nfev, diff_step=diff_step)
    best = values_of(res.x)
    if res.status == 0:
        raise ConvergenceError(
            f"the fit did not converge in {res.nfev} model evaluations (max_nfev={max_nfev}); "
            f"last parameters {best}, chi2 {2 * res.cost:.6g}. Better start values, tighter bounds or "
            "fewer varied parameters would help", history=list(history))
    if res.status < 0:
        raise ConvergenceError(f"the fit failed: {res.message}", history=list(history))
    # covariance from the SVD of the Jacobian at the optimum (scipy's J is w.r.t. x)
    J = np.asarray(res.jac, dtype=float)
    _, s, vt = np.linalg.svd(J, full_matrices=False)
    if s.size < m or s[-1] <= rcond * s[0]:
        null = vt[-1]
        involved = [n for n, c in zip(names, null) if abs(c) > 0.1]
        raise ConvergenceError(
            "the data do not determine all parameters (singular Jacobian, condition number "
            f"{(s[0] / s[-1]) if s[-1] > 0 else np.inf:.3g}); the combination involving "
            f"{', '.join(involved)} has no effect on Psi/Delta. Fix one of them (vary=False) or add data "
            "(angles, wavelengths)", history=list(history))
    cov = (vt.T / s**2) @ vt
    sd = np.sqrt(np.diag(cov))
    corr = cov / np.outer(sd, sd)  # before the χ² scaling, which cancels here but is 0 for exact data
    chi2 = float(res.fun @ res.fun)
    dof = n_res - m
    if not absolute_sigma:
        cov = cov * chi2 / dof
    err = np.sqrt(np.diag(cov))
    new_params = tuple(replace(p, value=best[p.name]) for p in params)
    span = hi - lo
    at_b = []
    for n, x, a, b, sp, e in zip(names, res.x, lo, hi, span, err):
        tol = 1e-6 * max(abs(a) if np.isfinite(a) else 0, abs(b) if np.isfinite(b) else 0,
                         sp if np.isfinite(sp) else 1, 1e-12)
        which = ("lower", a) if np.isfinite(a) and x - a <= tol else ("upper", b) if np.isfinite(b) and b - x <= tol else None
        if which is None:
            continue
        at_b.append(n)
        warnings.warn(FitAtBoundWarning(
            f"parameter {n} ended on its {which[0]} bound ({x:.6g}, bound {which[1]:.6g}): the data "
            f"pull it beyond the allowed range, so its value is set by the bound and its uncertainty "
            f"(± {e:.2g}) is not meaningful. Widen the bound if the range allows it, or fix the "
            "parameter (vary=False) at a value you trust"), stacklevel=2)
    at_b = tuple(at_b)
    return FitResult(
        parameters=new_params, names=names, stderr=dict(zip(names, map(float, err))), covariance=cov,
        correlation=corr, chi2=chi2, dof=dof, mse=float(np.sqrt(chi2 / dof)), absolute_sigma=absolute_sigma,
        residuals=np.asarray(res.fun), nfev=int(res.nfev), message=str(res.message),
        cost_history=tuple(history), model=build(best) if build is not None else None, at_bounds=at_b)


def psi_delta_residuals(data, psi_model, delta_model) -> np.ndarray:
    """Weighted residuals [(Ψ_mod − Ψ)/σΨ, wrap(Δ_mod − Δ)/σΔ] (unit σ when the data have none)."""
    sp = data.sigma_psi_deg if data.has_sigma else 1.0
    sd = data.sigma_delta_deg if data.has_sigma else 1.0
    return np.concatenate([(psi_model - data.psi_deg) / sp, wrap_delta(delta_model - data.delta_deg) / sd])


def fit_psi_delta(data, build: Callable[[dict], object], parameters, *, forward: Callable | None = None,
                  absolute_sigma: bool | None = None, max_nfev: int | None = None, **kwargs) -> FitResult:
    """Fit a model to measured Ψ and Δ at all the data's wavelengths and angles at once.

    Parameters
    ----------
    data : EllipsometryData
    build : callable
        ``build(values: dict) -> stack``: makes the sample (e.g. an :class:`nmmm.layers.Stack`)
        for a set of parameter values. :meth:`EllipsometryModel.build
        <nmmm.ellipsometry.model.EllipsometryModel.build>` is one.
    parameters : sequence of Parameter
    forward : callable, optional
        ``forward(sample, wavelength_nm, angle_deg) -> (psi_deg, delta_deg)``;
        default :func:`nmmm.ellipsometry.forward.psi_delta`.
    absolute_sigma : bool, optional
        Default: True when the data carry σ.
    max_nfev : int, optional
        Budget of model evaluations (default 200·(M+1)); exhausting it raises ConvergenceError.

    Returns
    -------
    FitResult
        ``result.model`` is the fitted stack; ``result.extra["psi_deg"], ["delta_deg"]`` the model.
    """
    fwd = forward or psi_delta
    if absolute_sigma is None:
        absolute_sigma = bool(data.has_sigma)

    def residuals(values):
        psi, delta = fwd(build(values), data.wavelength_nm, data.angle_deg)
        return psi_delta_residuals(data, psi, delta)

    result = least_squares_fit(residuals, parameters, absolute_sigma=absolute_sigma, max_nfev=max_nfev,
                               build=build, **kwargs)
    psi, delta = fwd(result.model, data.wavelength_nm, data.angle_deg)
    result.extra.update(psi_deg=psi, delta_deg=delta, data=data)
    return result
