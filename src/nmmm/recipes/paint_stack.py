"""The compute side of paint systems in a recipe: ``[[pigments]]`` films, ``[[coats]]`` stacks,
``[substrate]``, ``[measurement] geometry`` and the formulator's numbers (issue 16).

- :func:`components` — recipe pigments -> :class:`nmmm.layers.pigment_mixture.Component`.
- :func:`recipe_stack` — the recipe's film or coats as a :class:`nmmm.layers.CoatStack`.
- :func:`paint_system` — the ``coats`` macro, and the multi-pigment film: spectra, formulator
  quantities (over white/black, masstone, contrast ratio, hiding, spreading rate) into a
  RunResult.
- :func:`geometry_of` — the recipe's instrument geometry ([measurement] or the film's specular).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nmmm.errors import NmmmError, RecipeError

__all__ = ["components", "recipe_stack", "paint_system", "geometry_of", "add_formulator"]


def geometry_of(recipe) -> str:
    g = recipe.measurement.geometry
    if g is not None:
        return g
    f = recipe.film
    return "di:8" if (f is not None and f.specular == "included") else "de:8"


def _distribution(pg):
    from nmmm.layers.distributions import lognormal, monodisperse

    d = pg.equivalent_diameter_nm()
    return monodisperse(d) if pg.size_spread == 1.0 else lognormal(d, pg.size_spread, n_nodes=pg.size_nodes)


def components(pigments, mats):
    from nmmm.layers.pigment_mixture import Component

    return tuple(Component(mats[p.compound], _distribution(p), p.fraction, p.compound) for p in pigments)


def _substrate(recipe, w, default_reflectance):
    from nmmm.layers.coat_stack import Substrate

    s = recipe.substrate
    if s is None:
        return Substrate(reflectance=default_reflectance)
    try:
        if s.kind is not None:
            return Substrate.black() if s.kind == "black" else Substrate.white()
        if s.file is not None:
            p = Path(s.file)
            if not p.is_absolute() and recipe.base_dir:
                p = Path(recipe.base_dir) / p
            data = np.loadtxt(p, delimiter=",", skiprows=1)
            rho = np.interp(w, data[:, 0], data[:, 1])
            if w[0] < data[0, 0] or w[-1] > data[-1, 0]:
                raise RecipeError(f"substrate.file: {p.name} covers {data[0, 0]:g}–{data[-1, 0]:g} nm, the grid needs "
                                  f"{w[0]:g}–{w[-1]:g} nm")
            return Substrate(reflectance=rho)
        rho = np.asarray(s.reflectance, float)
        if rho.ndim == 1 and rho.size != w.size:
            raise RecipeError(f"substrate.reflectance: a list needs one value per wavelength ({w.size}), got {rho.size}")
        return Substrate(reflectance=rho)
    except RecipeError:
        raise
    except (NmmmError, OSError, ValueError) as exc:
        raise RecipeError(f"substrate: {exc}") from None


def recipe_stack(recipe, mats, w):
    """The recipe's coats (``[[coats]]``) or its film (with the clear coat as a coat on top)."""
    from nmmm.layers.coat_stack import Coat, CoatStack

    if recipe.coats is not None:
        coats = []
        for i, c in enumerate(recipe.coats):
            try:
                coats.append(Coat(c.name, c.thickness_nm, mats[c.binder], components(c.pigments, mats), False, c.cpvc))
            except NmmmError as exc:
                raise RecipeError(f"coats[{i}]: {exc}") from None
        default_rho = 0.0
    else:
        f = recipe.film
        pigs = recipe.pigments if recipe.pigments is not None else [recipe.pigment]
        dep = any(p.dependent_scattering for p in pigs)
        binder = mats[recipe.binder.compound]
        try:
            coats = [Coat("film", f.thickness_nm, binder, components(pigs, mats), dep, f.cpvc)]
        except NmmmError as exc:
            raise RecipeError(f"film: {exc}") from None
        if f.clear_coat_nm > 0:
            coats.insert(0, Coat("clear coat", f.clear_coat_nm, binder))
        default_rho = f.substrate_reflectance
    sub = _substrate_with(recipe, mats, w, default_rho)
    return CoatStack(coats, sub)


def _substrate_with(recipe, mats, w, default_rho):
    from nmmm.layers.coat_stack import Substrate

    s = recipe.substrate
    if s is not None and s.compound is not None:
        return Substrate(compound=mats[s.compound])
    return _substrate(recipe, w, default_rho)


def _solver(recipe):
    return recipe.film.solver if recipe.film is not None else "ad"


def _check_binder_range(recipe, mats, w):
    """A coat's binder must have data over the grid (absorbing beyond its range is not extrapolated)."""
    names = [c.binder for c in recipe.coats] if recipe.coats is not None else [recipe.binder.compound]
    for i, b in enumerate(names):
        rng = getattr(mats[b], "wavelength_range_nm", None)
        if rng is not None:
            lo, hi = rng
            if w[0] < lo - 1e-9 or w[-1] > hi + 1e-9:
                key = f"coats[{i}].binder" if recipe.coats is not None else "binder.compound"
                raise RecipeError(f"{key}: {b!r} has data for {lo:g}–{hi:g} nm only; the grid needs {w[0]:g}–{w[-1]:g} nm "
                                  "(narrow [spectral] or give a binder with data there)")


def add_formulator(recipe, mats, w, res, stack=None):
    """Over white/black, masstone, contrast ratio, hiding and spreading rate of the top
    pigmented coat, into ``res`` (spectra, scalars, summary, notes)."""
    from nmmm.colour import spectra_to_lab
    from nmmm.layers.formulation import formulator_quantities

    stack = recipe_stack(recipe, mats, w) if stack is None else stack
    geo = geometry_of(recipe)
    # the paint under test is the first coat with pigments, alone over the charts
    k = next((i for i, c in enumerate(stack.coats) if c.components), 0)
    top = stack.replace(coats=stack.coats[k:k + 1])
    fq = formulator_quantities(top, w, solver=_solver(recipe), geometry=geo, hiding=recipe.measurement.hiding)
    name = stack.coats[k].name
    res.spectra[f"over white (0.80) — {name}"] = fq.over_white
    res.spectra[f"over black — {name}"] = fq.over_black
    res.spectra[f"masstone (opaque) — {name}"] = fq.masstone
    lab = spectra_to_lab(w, fq.masstone)
    res.scalars["contrast_ratio"] = fq.contrast_ratio
    if recipe.measurement.hiding:
        res.scalars["hiding_thickness_um"] = fq.hiding_thickness_nm / 1e3
        res.scalars["hiding_spreading_rate_m2_per_L"] = fq.spreading_rate_m2_per_L
    res.scalars["masstone_L"], res.scalars["masstone_a"], res.scalars["masstone_b"] = (float(x) for x in lab)
    res.notes.append(f"Formulator ({name}, {geo}, {fq.solver}): contrast ratio Y(black)/Y(white 0.80) = "
                     f"{fq.contrast_ratio:.4f} at {stack.coats[k].thickness_nm / 1e3:g} µm (ISO 6504-3 / ASTM D2805, D65 2°)"
                     + (f"; hiding (CR 0.98) at {fq.hiding_thickness_nm / 1e3:.1f} µm dry, spreading rate "
                        f"{fq.spreading_rate_m2_per_L:.1f} m²/L" if recipe.measurement.hiding else "") + ".")
    return fq


def paint_system(recipe, mats, w, res):
    """The ``coats`` macro (and a multi-pigment ``film``): spectra by the stack solver."""
    from nmmm.layers.coat_stack import stack_reflectance

    _check_binder_range(recipe, mats, w)
    stack = recipe_stack(recipe, mats, w)
    geo = geometry_of(recipe)
    solver = _solver(recipe)
    r = stack_reflectance(stack, w, solver=solver, geometry=geo)
    label = f"reflectance ({geo}, {solver})"
    res.spectra[label] = r.reflectance
    res.primary = label
    if solver == "ad":
        km = stack_reflectance(stack, w, solver="km", geometry=geo, optics=r.optics)
        res.spectra[f"reflectance ({geo}, km)"] = km.reflectance
        res.scalars["km_minus_ad_max_abs"] = float(np.max(np.abs(km.reflectance - r.reflectance)))
    res.notes.append("Coat stack, top first: " + " | ".join(
        f"{c.name} {c.thickness_nm / 1e3:g} µm ({', '.join(f'{x.name} {x.fraction:g}' for x in c.components) or 'clear'})"
        for c in stack.coats) + f"; adding–doubling through every interface (index mismatches included), geometry {geo}.")
    add_formulator(recipe, mats, w, res, stack)
