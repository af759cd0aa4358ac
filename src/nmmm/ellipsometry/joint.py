"""Joint (multi-sample) fits: one set of shared parameters over several ellipsometric data sets.

Public objects
--------------
- :func:`fit_joint` — weighted least squares on Ψ and Δ of several data sets at once, each with
  its own model, some parameters (e.g. a resin's Cauchy A, B, C) shared by all of them and the
  others (e.g. each film's thickness) fitted per data set.
- :func:`joint_parameter_names` — how the names of each model's parameters map to the joint fit's.

Why
---
For one transparent film, thickness and refractive index are strongly correlated: a film a
little thicker with a slightly lower n gives nearly the same Ψ, Δ. Films of the same material
with different thicknesses (or one sample measured at several angles / on several instruments)
see the same n(λ) through different interference conditions; fitting them together with the
dispersion parameters shared and one thickness per film breaks that correlation and shrinks the
uncertainty of the optical constants ("multi-sample analysis": Fujiwara 2007, ch. 5;
Hilfiker et al. 2008; Jellison 1993).

Method
------
The joint χ² is the sum of each data set's χ² (:func:`~nmmm.ellipsometry.fitting.psi_delta_residuals`,
Δ wrapped), minimised by the same engine as single fits
(:func:`~nmmm.ellipsometry.fitting.least_squares_fit`): bounds, covariance from the SVD of the
Jacobian, correlation matrix, :class:`nmmm.ConvergenceError` on failure or an undetermined
parameter, :class:`~nmmm.ellipsometry.fitting.FitAtBoundWarning` when a parameter ends on a bound.

Naming: a shared parameter keeps the name it has in the first data set's model
(``epoxy.A``); every other parameter of data set *i* gets the suffix ``[i]``
(``epoxy.thickness_nm[0]``, ``epoxy.thickness_nm[1]``). A shared name is either a model's full
parameter name (``"epoxy.A"``) or the part after the layer prefix (``"A"``, ``"thickness_nm"``,
``"oscillators[0].center_ev"``); a full name of the first model also designates the parameter
of the same part in a model whose layer has another name. A shared parameter's start value, bounds and fit flag are
those of the first model.

References
----------
- H. Fujiwara, *Spectroscopic Ellipsometry: Principles and Applications*, Wiley (2007), ch. 5.
- J. N. Hilfiker et al., "Survey of methods to characterize
  thin absorbing films with spectroscopic ellipsometry", Thin Solid Films 516, 7979 (2008).
- G. E. Jellison Jr., Thin Solid Films 234, 416 (1993).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable

import numpy as np

from nmmm.ellipsometry.fitting import FitResult, least_squares_fit, psi_delta_residuals
from nmmm.errors import InvalidInputError

__all__ = ["fit_joint", "joint_parameter_names"]


def _unpack(datasets):
    """[(data, build, parameters, model_or_None)] from (data, EllipsometryModel) or
    (data, build, parameters) items; applies each model's [fit] wavelength window."""
    from nmmm.ellipsometry.model import EllipsometryModel

    try:
        items = list(datasets)
    except TypeError:
        raise InvalidInputError("fit_joint needs a list of (data, model) pairs") from None
    if not items:
        raise InvalidInputError("fit_joint needs at least one (data, model) pair; got an empty list")
    out = []
    for i, item in enumerate(items):
        if not isinstance(item, (tuple, list)) or len(item) not in (2, 3):
            raise InvalidInputError(f"data set {i}: expected (data, EllipsometryModel) or (data, build, parameters), "
                                    f"got {type(item).__name__}")
        data = item[0]
        if not all(hasattr(data, a) for a in ("psi_deg", "delta_deg", "wavelength_nm", "angle_deg")):
            raise InvalidInputError(f"data set {i}: the first element must be an EllipsometryData, "
                                    f"got {type(data).__name__}")
        if len(item) == 2:
            model = item[1]
            if not isinstance(model, EllipsometryModel):
                raise InvalidInputError(f"data set {i}: the model must be an EllipsometryModel (or give "
                                        f"(data, build, parameters)), got {type(model).__name__}")
            opts = model.options
            if "wavelength_min_nm" in opts or "wavelength_max_nm" in opts:
                data = data.within(opts.get("wavelength_min_nm"), opts.get("wavelength_max_nm"))
            out.append((data, model.build, tuple(model.parameters), model))
        else:
            _, build, params = item
            if not callable(build):
                raise InvalidInputError(f"data set {i}: build must be callable values -> stack")
            out.append((data, build, tuple(params), None))
    return out


def _resolve(name: str, local_names, i: int) -> str:
    """The local parameter name of data set ``i`` that the shared ``name`` designates: the exact
    name, else the one parameter whose name after its layer prefix (``epoxy.``) equals ``name``
    or ``name`` without its own prefix (so ``"resin1.A"`` designates ``resin2.A`` in a model
    whose layer is called ``resin2``)."""
    if name in local_names:
        return name
    candidates = [name] + ([name.split(".", 1)[1]] if "." in name else [])
    for cand in candidates:
        hits = [n for n in local_names if "." in n and n.split(".", 1)[1] == cand]
        if len(hits) == 1:
            return hits[0]
        if len(hits) > 1:
            raise InvalidInputError(f"shared parameter {name!r} is ambiguous in data set {i}'s model "
                                    f"(matches {hits}); give the full name")
    raise InvalidInputError(
        f"shared parameter {name!r} is not a parameter of data set {i}'s model; its parameters are "
        f"{list(local_names)} (a shared parameter must exist in every model)")


def joint_parameter_names(parameter_names, shared) -> list[dict]:
    """For each data set, ``{local name: joint name}``.

    ``parameter_names`` is a list (one per data set) of that model's parameter names; see the
    module docstring for the naming rules.

    >>> joint_parameter_names([["f.thickness_nm", "f.A"], ["f.thickness_nm", "f.A"]], ["A"])
    [{'f.thickness_nm': 'f.thickness_nm[0]', 'f.A': 'f.A'}, {'f.thickness_nm': 'f.thickness_nm[1]', 'f.A': 'f.A'}]
    """
    if isinstance(shared, str):
        shared = [s.strip() for s in shared.split(",") if s.strip()]
    shared = list(shared)
    if len(set(shared)) != len(shared):
        raise InvalidInputError(f"shared parameter names repeat: {shared}")
    lists = [list(names) for names in parameter_names]
    if not lists:
        raise InvalidInputError("no data sets")
    resolved = []  # per data set: shared name -> local name
    for i, names in enumerate(lists):
        r = {s: _resolve(s, names, i) for s in shared}
        if len(set(r.values())) != len(r):
            raise InvalidInputError(f"data set {i}: two shared names designate the same parameter ({r})")
        resolved.append(r)
    maps = []
    for i, names in enumerate(lists):
        local_to_shared = {loc: s for s, loc in resolved[i].items()}
        m = {}
        for n in names:
            m[n] = resolved[0][local_to_shared[n]] if n in local_to_shared else f"{n}[{i}]"
        maps.append(m)
    return maps


def fit_joint(datasets, shared, *, forward: Callable | None = None, absolute_sigma: bool | None = None,
              max_nfev: int | None = None, **kwargs) -> FitResult:
    """Fit several ellipsometric data sets at once with some parameters shared by all.

    Parameters
    ----------
    datasets : sequence
        ``[(data, model), ...]`` with an :class:`~nmmm.ellipsometry.data.EllipsometryData` and an
        :class:`~nmmm.ellipsometry.model.EllipsometryModel` each (its ``[fit]`` wavelength
        window applies), or ``(data, build, parameters)`` triples as for
        :func:`~nmmm.ellipsometry.fitting.fit_psi_delta`.
    shared : sequence of str (or a comma-separated str)
        Parameters common to every data set: full names (``"epoxy.A"``) or, if unambiguous,
        the name after the layer prefix (``"A"``). Must exist in every model.
    forward : callable, optional
        ``forward(stack, wavelength_nm, angle_deg) -> (psi_deg, delta_deg)``; default
        :func:`nmmm.ellipsometry.forward.psi_delta`.
    absolute_sigma : bool, optional
        Default: True when every data set carries σ (data sets with and without σ cannot be
        weighted together; give σ to all, or ``absolute_sigma=False`` to treat all as unit weights).
    max_nfev : int, optional
        Budget of model evaluations (default: the largest ``[fit] max_nfev`` of the models, or
        200·(M+1)).

    Returns
    -------
    FitResult
        Joint parameter names as in the module docstring. ``result.model`` is the list of
        fitted stacks; ``result.extra`` holds per data set lists ``"data"``, ``"psi_deg"``,
        ``"delta_deg"``, ``"values"`` (each model's own parameter names), ``"models"`` (fitted
        EllipsometryModels, or None for build functions), ``"chi2_per_dataset"``, and
        ``"name_map"`` (local -> joint names).

    Raises
    ------
    InvalidInputError
        Empty list, a shared name missing from a model, mixed σ, fewer data than parameters.
    ConvergenceError
        As :func:`~nmmm.ellipsometry.fitting.least_squares_fit`.
    """
    from nmmm.ellipsometry.forward import psi_delta

    items = _unpack(datasets)
    fwd = forward or psi_delta
    maps = joint_parameter_names([[p.name for p in params] for _, _, params, _ in items], shared)

    has_sigma = [bool(d.has_sigma) for d, *_ in items]
    if absolute_sigma is None:
        if all(has_sigma):
            absolute_sigma = True
        elif not any(has_sigma):
            absolute_sigma = False
        else:
            raise InvalidInputError(
                f"data sets {[i for i, h in enumerate(has_sigma) if not h]} have no sigma_psi/sigma_delta while "
                "the others do: their residuals would be weighted inconsistently. Give every data set its "
                "uncertainties, or pass absolute_sigma=False")
    elif absolute_sigma and not all(has_sigma):
        raise InvalidInputError("absolute_sigma=True needs sigma_psi/sigma_delta in every data set")

    joint_params, seen = [], set()
    for (_, _, params, _), m in zip(items, maps):
        for p in params:
            jn = m[p.name]
            if jn in seen:
                continue
            seen.add(jn)
            joint_params.append(replace(p, name=jn))

    def local_values(values: dict) -> list[dict]:
        return [{loc: values[jn] for loc, jn in m.items()} for m in maps]

    def residuals(values):
        return np.concatenate([psi_delta_residuals(d, *fwd(build(v), d.wavelength_nm, d.angle_deg))
                               for (d, build, _, _), v in zip(items, local_values(values))])

    def build_all(values):
        return [build(v) for (_, build, _, _), v in zip(items, local_values(values))]

    if max_nfev is None:
        budgets = [int(mod.options["max_nfev"]) for *_, mod in items if mod is not None and "max_nfev" in mod.options]
        max_nfev = max(budgets) if budgets else None

    result = least_squares_fit(residuals, joint_params, absolute_sigma=absolute_sigma, max_nfev=max_nfev,
                               build=build_all, **kwargs)
    locs = local_values(result.values)
    psis, deltas, chi2s = [], [], []
    for (d, _, _, _), stack in zip(items, result.model):
        p, dl = fwd(stack, d.wavelength_nm, d.angle_deg)
        r = psi_delta_residuals(d, p, dl)
        psis.append(p), deltas.append(dl), chi2s.append(float(r @ r))
    result.extra.update(
        data=[d for d, *_ in items], psi_deg=psis, delta_deg=deltas, values=locs, chi2_per_dataset=chi2s,
        models=[mod.with_values(v) if mod is not None else None for (*_, mod), v in zip(items, locs)],
        name_map=maps)
    return result
