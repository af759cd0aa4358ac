"""Colour matching: the values of a recipe's free keys (pigment fractions, film thickness,
particle size …) that reproduce a target spectrum or CIELAB colour, through nmmm's own forward
model (Mie optics of the compounds, then adding–doubling through the coat stack).

- :func:`parse_bound` — ``"pigments.0.fraction=0:0.2"`` -> :class:`Bound` (the key paths of
  ``nmmm sweep``, checked to exist, be numeric and have LO < HI).
- :class:`RecipeModel` — a recipe whose keys are free: ``reflectance(values, solver)``; counts
  its evaluations. Pigment fractions below the CPVC take the *linear* path: each component's
  Mie optics are computed once per unit fraction, and a film's μ_a, μ_s and phase moments are
  their fraction-weighted sums (independent scattering, exactly what
  :func:`nmmm.layers.pigment_mixture.mixture_optics` computes); other keys rebuild the recipe.
- :func:`match_recipe` — the match (:class:`MatchResult`).

Method. The free values are mapped to [0, 1] on their bounds. Stage 1 fits the linearised
Kubelka–Munk model of the same optics (Gate's K, S from the μ_a, μ_s, g of each colourant's Mie
optics, computed once; Saunderson's surface terms once; then KM algebra only, ~0.3 ms an
evaluation against ~8 ms for adding–doubling) with scipy's bounded trust-region least squares
(``least_squares(method="trf")``) from the box centre and from the recipe's own values. Stage 2
finishes the best KM optimum on adding–doubling (the quadrature pinned at the count the automatic
rule picks there; the final spectrum is re-evaluated with the automatic rule when it differs) by a
bounded Gauss–Newton whose Jacobian *starts as the KM model's* and is corrected by Broyden's update
after every step (:func:`_quasi_newton`): one adding–doubling evaluation a step while the KM
Jacobian predicts well, forward differences only where it stops doing so. A second KM optimum is
finished only when the first ends above ``refine_above_de00`` (0.3); a finish that ends short of
``stop_norm`` is also tried from the box centre (within 10 evaluations a key: the KM optima can lead
into another basin of adding–doubling's — a noise-free target with one colourant absent ended at
ΔE00 0.075, the fractions 60 % off), and the candidates are ranked by ΔE00 (spectral mode: by the
spectral residual, its objective). On a thin film over white the
two-flux model's optimum lies elsewhere along the valley of the weakly identifiable total amount
(the 3-colourant tint of benchmarks/bench_matching.py: hematite 0.048 by KM, 0.021 by adding–doubling),
so there the KM start saves about the first Jacobian only; its ~60 KM evaluations cost about two
adding–doubling ones. A stage stops when
the residual norm falls below ``stop_norm`` (1e-5: ΔE00 or % RMS; the Gauss–Newton step past 1e-4
costs one evaluation and pins a weakly identifiable scale far better). Residuals:

- ``mode="colorimetric"``: the CIEDE2000 residual vector under the primary illuminant
  (:func:`~nmmm.matching.metamerism.delta_e2000_residuals`, norm = ΔE00), plus, with a target
  spectrum and ``metamerism_weight`` w > 0, √w × the residual vector of the metamerism index
  under each test illuminant, plus ``spectral_weight`` (default 0.1) × the spectral residual in
  percent — with a target spectrum, this picks the isomeric member of a family of metamers that
  all reach ΔE00 = 0 (two fractions in an opaque film are one hue ratio for the eye);
- ``mode="spectral"``: (R − R_target) in percent / √W (its norm is the spectral RMS in %).

Reported: ΔE00, ΔL*, ΔC*, ΔH* under the primary illuminant, the CIE special metamerism index
(:func:`~nmmm.matching.metamerism.metamerism_index`, ΔE00, additive correction) under each test
illuminant, spectral RMS, the model evaluations of each stage, the fractions' standard errors
for a stated reflectance noise (Gauss–Newton covariance of the spectral residual, linearised at the
optimum: a large value says the key is not identifiable from the spectrum), and which bounds are
active. When every free key is a fraction, also their shares of the total with σ (well pinned) and
the total's 68 % profile-likelihood interval (:func:`_shares_and_total`): along the total the model is
far from linear, and the linearised σ understated the spread of the fractions up to 8× (20 noise
draws of the 3-colourant acceptance case; the profile interval held the true total in 18). A best match
above ``tolerance_de00`` warns, naming the ΔL*/ΔC*/ΔH* still missing and the bounds that stop it.

References
----------
- P. Virtanen et al., SciPy 1.0, Nat. Methods 17, 261 (2020) — ``scipy.optimize.least_squares``.
- R. McDonald, "Recipe prediction for textiles", in *Colour Physics for Industry*, 2nd ed.,
  SDC (1997), ch. 6 — the matching problem and its metamerism constraint.
- CIE 15:2004 §9.2; G. Sharma et al., Color Res. Appl. 30, 21 (2005).
- C. G. Broyden, "A class of methods for solving nonlinear simultaneous equations", Math. Comp. 19,
  577 (1965); J. E. Dennis, R. B. Schnabel, *Numerical Methods for Unconstrained Optimization and
  Nonlinear Equations*, SIAM (1996), §8.3 — the rank-one Jacobian update.
- J. W. Bandler et al., "Space mapping: the state of the art", IEEE Trans. Microw. Theory Tech. 52,
  337 (2004) — a cheap model's Jacobian corrected to finish on the fine one.
"""

from __future__ import annotations

import math
import re
import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from nmmm.errors import InvalidInputError, RecipeError

__all__ = ["Bound", "parse_bound", "RecipeModel", "MatchResult", "match_recipe", "MATCH_MODES"]

MATCH_MODES = ("colorimetric", "spectral")
_FRACTION_KEY = re.compile(r"^(?:coats\.(\d+)\.)?pigments\.(\d+)\.fraction$")


class IdentifiabilityWarning(UserWarning):
    """A matched key whose standard error exceeds its bound span (one spectrum cannot pin it)."""


@dataclass(frozen=True)
class Bound:
    key: str
    lo: float
    hi: float


def parse_bound(spec) -> Bound:
    """``KEY=LO:HI`` (or a ``(key, lo, hi)`` tuple) -> :class:`Bound` (LO < HI, finite)."""
    if isinstance(spec, Bound):
        return spec
    if isinstance(spec, (tuple, list)) and len(spec) == 3:
        key, lo, hi = spec
    else:
        s = str(spec)
        if "=" not in s or ":" not in s.split("=", 1)[1]:
            raise RecipeError(f"--vary {s!r}: write KEY=LO:HI (e.g. pigments.0.fraction=0:0.2)")
        key, rng = (t.strip() for t in s.split("=", 1))
        parts = rng.split(":")
        if len(parts) != 2:
            raise RecipeError(f"--vary {s!r}: a match range is LO:HI (two numbers)")
        try:
            lo, hi = float(parts[0]), float(parts[1])
        except ValueError:
            raise RecipeError(f"--vary {s!r}: LO and HI must be numbers") from None
    lo, hi = float(lo), float(hi)
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise RecipeError(f"--vary {key}: LO and HI must be finite")
    if not lo < hi:
        raise RecipeError(f"--vary {key}={lo:g}:{hi:g}: LO must be below HI")
    if key.endswith("fraction") and (lo < 0 or hi > 1):
        raise RecipeError(f"--vary {key}={lo:g}:{hi:g}: a fraction lies in [0, 1]")
    return Bound(str(key), lo, hi)


def _stack_index(recipe, m):
    """Index in the stack's coats of the coat holding ``m``'s pigment (film: after the clear coat)."""
    if m.group(1) is not None:
        return int(m.group(1))
    return 1 if (recipe.film is not None and recipe.film.clear_coat_nm > 0) else 0


class RecipeModel:
    """The forward model of a recipe with free keys (module docstring)."""

    def _check_bounds_parse(self, raw, base):
        """Each bound checked before any fit: the recipe with the key at LO, then at HI, must parse,
        so a bound the schema refuses (a negative thickness) is named with the value the user typed,
        not met later at some value the optimiser chose."""
        from nmmm.errors import NmmmError
        from nmmm.recipes.schema import parse_recipe, set_key

        for b in self.bounds:
            for side, value in (("LO", b.lo), ("HI", b.hi)):
                try:
                    parse_recipe(set_key(raw, b.key, value), base_dir=base)
                except NmmmError as exc:
                    raise RecipeError(f"--vary {b.key}={b.lo:g}:{b.hi:g}: {side} = {value:g} is not a valid value for "
                                      f"{b.key} ({exc}); choose a range the recipe accepts") from None

    def __init__(self, recipe, bounds, solver: str = "ad"):
        from nmmm.recipes.paint_stack import _solver, geometry_of, recipe_stack
        from nmmm.recipes.run import _grid, build_materials
        from nmmm.recipes.schema import get_key, parse_recipe, read_toml

        raw, _, base = read_toml(recipe)
        self.raw, self.base_dir = raw, base
        self.bounds = tuple(parse_bound(b) for b in bounds)
        if not self.bounds:
            raise RecipeError("--vary: give at least one KEY=LO:HI to match")
        keys = [b.key for b in self.bounds]
        if len(set(keys)) != len(keys):
            raise RecipeError(f"--vary: a key is given twice: {keys}")
        for b in self.bounds:
            v = get_key(raw, b.key)
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise RecipeError(f"{b.key}: is {v!r}, not a number; only numeric keys can be matched")
        self.recipe = parse_recipe(raw, base_dir=base)
        self._check_bounds_parse(raw, base)
        if self.recipe.film is None and self.recipe.coats is None:
            raise RecipeError("matching needs a paint recipe ([[pigments]] + [film], or [[coats]]); "
                              f"this one is a {self.recipe.macro!r} recipe")
        self.wavelength_nm = _grid(self.recipe)
        self.mats = build_materials(self.recipe, self.wavelength_nm, progress=False)
        self.geometry = geometry_of(self.recipe)
        self.solver = solver if solver else _solver(self.recipe)
        self.stack = recipe_stack(self.recipe, self.mats, self.wavelength_nm)
        self.initial = np.array([float(get_key(raw, k)) for k in keys])
        self.evaluations = {"km": 0, "ad": 0}
        self._recipe_stack = recipe_stack
        self._linear = self._linear_path()
        self._km_terms = self._km_setup() if self._linear is not None else None

    # -- the linear path (fractions below the CPVC, independent scattering)
    def _linear_path(self):
        from nmmm.layers.coat_stack import Coat, coat_optics
        from nmmm.layers.pigment_mixture import DEFAULT_CPVC

        hits = [_FRACTION_KEY.match(b.key) for b in self.bounds]
        if not all(hits):
            return None
        w = self.wavelength_nm
        coats = self.stack.coats
        per = {}
        for j, (b, m) in enumerate(zip(self.bounds, hits)):
            ci, pi = _stack_index(self.recipe, m), int(m.group(2))
            if ci >= len(coats) or pi >= len(coats[ci].components):
                return None
            per.setdefault(ci, []).append((pi, j))
        unit = {}
        for ci, items in per.items():
            c = coats[ci]
            cpvc = DEFAULT_CPVC if c.cpvc is None else c.cpvc
            fixed = sum(x.fraction for i, x in enumerate(c.components) if i not in [p for p, _ in items])
            top = fixed + sum(self.bounds[j].hi for _, j in items)
            if c.dependent_scattering or top >= cpvc:
                return None  # structure factor or voids: not linear in the fractions
            parts = []
            for i, comp in enumerate(c.components):
                f_ref = comp.fraction if comp.fraction > 0 else 0.01
                one = type(comp)(comp.compound, comp.distribution, f_ref, comp.name)
                o = coat_optics(Coat(c.name, c.thickness_nm, c.binder, (one,)), w)
                mu_s = o.mu_s_per_nm
                mom = o.phase_moments * mu_s[:, None]
                parts.append(((o.mu_a_per_nm - (1 - f_ref) * o.binder_absorption_per_nm) / f_ref, mom / f_ref))
            unit[ci] = ((np.stack([p[0] for p in parts]), np.stack([p[1] for p in parts])), dict(items), o.n_binder,
                        o.binder_absorption_per_nm)
        self._fixed_optics = tuple(coat_optics(c, w) if i not in unit else None for i, c in enumerate(coats))
        return unit

    def _km_setup(self):
        """What the Kubelka–Munk path needs that the free fractions do not change, computed once: the
        substrate's diffuse reflectance R_g under the bottom coat's binder, and the instrument reading
        as an affine function ``a + b·core`` of ``core = R_b / (1 − k2 R_b)`` (Saunderson's surface
        terms of the top binder; k2 integrates Fresnel over 96 Gauss nodes, the costliest part of a
        KM evaluation). Equal to ``stack_reflectance(..., "km")`` (tested to 1e-12)."""
        from nmmm.layers.fresnel_equations import fresnel, medium_nk
        from nmmm.layers.geometries import geometry_reflectance
        from nmmm.layers.kubelka_munk import saunderson_k2

        w = self.wavelength_nm
        opts, stack = self.optics(np.array([b.lo for b in self.bounds]))
        sub = stack.substrate
        if sub.reflectance is None:
            Rg = np.broadcast_to(fresnel(opts[-1].n_binder, medium_nk(sub.compound, w, "substrate"), 0.0).R, w.shape)
        else:
            Rg = np.broadcast_to(np.asarray(sub.reflectance, dtype=float), w.shape)
        n_top = opts[0].n_binder
        k2 = saunderson_k2(n_top)
        a = geometry_reflectance(self.geometry, "km", body=np.zeros(w.shape), n_top=n_top)
        half = geometry_reflectance(self.geometry, "km", body=np.full(w.shape, 0.5), n_top=n_top)
        b = (half - a) * (1 - 0.5 * k2) / 0.5
        thick = [c.thickness_nm if np.isfinite(c.thickness_nm) else 1e15 for c in stack.coats]
        return np.array(Rg, float), k2, a, b, thick

    def _km_reflectance(self, opts) -> np.ndarray:
        """Kubelka–Munk through the coats (Gate's K, S; Kubelka 1954 for stacking; the terms of
        :meth:`_km_setup`): the same algebra as :func:`nmmm.layers.coat_stack.stack_reflectance`'s KM solver."""
        from nmmm.layers.kubelka_munk import km_coefficients, km_reflectance, km_transmittance

        Rg, k2, a, b, thick = self._km_terms
        R = Rg
        for o, X in zip(opts[::-1], thick[::-1]):
            K, S = 2 * o.mu_a_per_nm, 0.75 * o.mu_s_per_nm * (1 - o.phase_moments[:, 1])  # Gate (1974)
            if np.all(S == 0):
                from scipy.special import expn

                t = 2 * expn(3, K * X / 2)
                R = t * t * R
                continue
            R1 = T1 = None
            if np.all(S > 0) and np.all(K >= 0):  # Kubelka (1948) in tanh form: no overflow for opaque coats
                ak = 1 + K / S
                bk = np.sqrt(np.maximum(ak * ak - 1, 0.0))
                bsx = bk * S * X
                if np.all(bsx > 1e-6):
                    e = np.exp(-2 * bsx)
                    th = (1 - e) / (1 + e)
                    den = ak * th + bk
                    R1, T1 = th / den, bk * 2 * np.sqrt(e) / (1 + e) / den
            if R1 is None:
                K, S = km_coefficients(o.mu_a_per_nm, o.mu_s_per_nm, o.g)
                R1 = km_reflectance(K, S, X, 0.0)
                T1 = km_transmittance(K, S, X)
            R = R1 + T1**2 * R / (1 - R1 * R)
        R = np.asarray(R, float)
        return a + b * R / (1 - k2 * R)

    def values(self, x) -> dict:
        return {b.key: float(v) for b, v in zip(self.bounds, np.atleast_1d(x))}

    def matched_raw(self, x) -> dict:
        from nmmm.recipes.schema import set_key

        raw = self.raw
        for k, v in self.values(x).items():
            raw = set_key(raw, k, float(f"{v:.6g}"))
        return raw

    def optics(self, x):
        """The coats' MixtureOptics and the stack at the free values ``x`` (physical units)."""
        from nmmm.layers.coat_stack import coat_optics
        from nmmm.layers.pigment_mixture import MixtureOptics
        from nmmm.recipes.schema import parse_recipe

        x = np.atleast_1d(np.asarray(x, float))
        if self._linear is None:
            rec = parse_recipe(self.matched_raw_exact(x), base_dir=self.base_dir)
            if any(b.key.startswith(("compounds", "levels")) for b in self.bounds):
                from nmmm.recipes.run import build_materials

                mats = build_materials(rec, self.wavelength_nm, progress=False)
            else:
                mats = self.mats
            stack = self._recipe_stack(rec, mats, self.wavelength_nm)
            return tuple(coat_optics(c, self.wavelength_nm) for c in stack.coats), stack
        w = self.wavelength_nm
        opts = list(self._fixed_optics)
        for ci, (parts, where, n_b, alpha_b) in self._linear.items():
            comps = self.stack.coats[ci].components
            f = np.array([x[where[i]] if i in where else comps[i].fraction for i in range(len(comps))])
            pvc = float(f.sum())
            mu_a = (1 - pvc) * alpha_b + f @ parts[0]
            mom = np.tensordot(f, parts[1], axes=1)
            mu_s = np.maximum(mom[:, 0], 0.0)
            with np.errstate(invalid="ignore", divide="ignore"):
                chi = np.where(mu_s[:, None] > 0, mom / np.where(mu_s > 0, mu_s, 1.0)[:, None], np.eye(1, mom.shape[1]))
            chi = np.clip(chi, -1, 1)
            chi[:, 0] = 1.0
            opts[ci] = MixtureOptics(w, np.maximum(mu_a, 0.0), mu_s, chi, n_b, alpha_b, pvc, 0.0)
        return tuple(opts), self.stack

    def matched_raw_exact(self, x) -> dict:
        from nmmm.recipes.schema import set_key

        raw = self.raw
        for k, v in self.values(x).items():
            raw = set_key(raw, k, v)
        return raw

    def quad_pts_at(self, x) -> int:
        """The node count the automatic adding–doubling rule picks at ``x``."""
        from nmmm.layers.adding_doubling_method import auto_quad_pts

        opts, _ = self.optics(x)
        chis = [o.phase_moments for o in opts]

        def chi_of(m):
            return (np.concatenate([c[:, 1] for c in chis]),
                    np.concatenate([c[:, m] if m < c.shape[1] else np.zeros(c.shape[0]) for c in chis]))

        return auto_quad_pts(chi_of)

    def reflectance(self, x, solver: str | None = None, quad_pts: int | None = None) -> np.ndarray:
        """The recipe's reflectance (its geometry) at the free values ``x`` (physical units)."""
        from nmmm.layers.coat_stack import stack_reflectance

        s = solver or self.solver
        opts, stack = self.optics(x)
        self.evaluations[s] = self.evaluations.get(s, 0) + 1
        if s == "km" and self._km_terms is not None:
            return self._km_reflectance(opts)
        return stack_reflectance(stack, self.wavelength_nm, s, self.geometry, quad_pts=quad_pts if s == "ad" else None,
                                 optics=opts).reflectance


@dataclass
class MatchResult:
    values: dict
    reflectance: np.ndarray
    wavelength_nm: np.ndarray
    target_lab: np.ndarray
    lab: np.ndarray
    de00: float
    dlch: np.ndarray
    metamerism: dict  # test illuminant -> index (ΔE00); empty without a target spectrum
    spectral_rms: float  # reflectance units; nan without a target spectrum
    illuminant: str
    mode: str
    evaluations: dict
    time_s: float
    candidates: list = field(default_factory=list)  # dicts, ranked by dE00
    standard_errors: dict = field(default_factory=dict)  # key -> σ at the stated noise, linearised at the optimum
    active_bounds: list = field(default_factory=list)
    recipe_raw: dict = field(default_factory=dict)
    target_reflectance: np.ndarray | None = None
    warnings: list = field(default_factory=list)
    quad_pts: int = 0
    shares: dict = field(default_factory=dict)  # key -> (share of the matched fractions' total, its σ)
    total: dict = field(default_factory=dict)  # the total's 68 % profile interval (:func:`_shares_and_total`)
    noise: float = 0.002  # the reflectance noise the uncertainties are stated for


def _check_target(target, w):
    R = np.asarray(target, float)
    if R.shape != w.shape:
        raise InvalidInputError(f"target spectrum has {R.size} values; the recipe's grid has {w.size} "
                                "(interpolate it with MeasuredSpectra.on_grid)")
    if not np.all(np.isfinite(R)):
        raise InvalidInputError("target spectrum has non-finite values")
    if R.max() > 1.5:
        raise InvalidInputError(f"target reflectance reaches {R.max():g}: percent, not factors (0-1); divide by 100")
    if R.min() < 0 or R.max() > 1.0 + 1e-9:
        raise InvalidInputError(f"target reflectance spans {R.min():g}–{R.max():g}; a reflectance factor of a paint lies in [0, 1]")
    return R


def _lab_function(w, illuminant: str, observer: str):
    """CIELAB of a reflectance on the grid ``w``, the ASTM E308 weighting factors computed once
    (XYZ = R @ W, white Y = 100; CIE 015:2018 eqs. for L*, a*, b*): what
    :func:`nmmm.colour.spectra_to_lab` computes, without its per-call checks (tested equal to 1e-10)."""
    from nmmm.colour.tristimulus import weighting_factors

    W = weighting_factors(w, illuminant, observer)
    white = W.sum(axis=0)
    eps = (6.0 / 29.0) ** 3

    def lab(R):
        t = (np.clip(R, 0, None) @ W) / white
        f = np.where(t > eps, np.cbrt(t), t / (3 * (6.0 / 29.0) ** 2) + 4.0 / 29.0)
        return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])

    return lab


def _forward_jacobian(fun, u, r0, h: float = 1e-6) -> np.ndarray:
    """Forward differences of ``fun`` at ``u`` in [0, 1]^n, stepping inwards from a bound."""
    J = np.empty((np.size(r0), np.size(u)))
    for j in range(np.size(u)):
        step = h if u[j] < 0.5 else -h
        v = np.array(u, float)
        v[j] += step
        J[:, j] = (fun(v) - r0) / step
    return J


def _shares_and_total(model, x, J, R0, Rt, quad, lo, hi, noise, dchi2: float = 1.0, n_side: int = 4):
    """What one spectrum pins when every free key is a fraction: their *shares* p_i = x_i / Σx (σ by the
    delta method on the Gauss–Newton covariance σ²(JᵀJ)⁻¹: well pinned, the linearisation holds) and
    their *total* Σx as a profile-likelihood interval, since along the total the spectrum is far from
    linear (a film over white turns opaque: at a larger amount R barely changes, and σ(JᵀJ)⁻¹ taken at
    the optimum understates the spread by up to 8× — 20 noise draws of the 3-colourant acceptance case).
    χ²(s) = |R(s·x) − R_t|²/σ² with the shares re-fitted to first order (the residual's part in the span
    of J's share directions removed), on ``n_side`` geometric steps each way to the --vary bounds; the
    interval is where χ² − χ²_min ≤ ``dchi2`` (1: 68 %), √Δχ² interpolated linearly in ln s. Returns
    ``({key: (p, σ_p)}, {"total", "low", "high", "low_at_bound", "high_at_bound"})``."""
    from scipy.linalg import null_space

    n, T = x.size, float(x.sum())
    cov = noise**2 * np.linalg.pinv(J.T @ J)
    G = (np.eye(n) * T - x[:, None]) / T**2  # d p_i / d x_j
    p_se = np.sqrt(np.maximum(np.diag(G @ cov @ G.T), 0.0))
    shares = {b.key: (float(v / T), float(e)) for b, v, e in zip(model.bounds, x, p_se)}
    Q = np.linalg.qr(J @ null_space(np.ones((1, n))))[0]  # the shares' directions in reflectance

    def chi2(R):
        r = R - Rt
        return float(r @ r - np.sum((Q.T @ r) ** 2)) / noise**2

    c0 = chi2(R0)
    sides = {}
    for name, s_end in (("low", max(float(np.max(lo / x)), 1e-3)), ("high", float(np.min(hi / x)))):
        s = np.geomspace(1.0, s_end, n_side + 1)[1:] if abs(np.log(s_end)) > 1e-9 else np.array([])
        c = np.array([chi2(model.reflectance(v * x, "ad", quad)) for v in s])
        sides[name] = (s, c)
    c_min = min([c0] + [float(np.min(c)) for _, c in sides.values() if c.size])
    out = {"total": T}
    for name, (s, c) in sides.items():
        root = np.sqrt(np.maximum(np.concatenate([[c0], c]) - c_min, 0.0))
        ls = np.log(np.concatenate([[1.0], s]))
        over = np.nonzero(root[1:] > np.sqrt(dchi2))[0]
        if over.size == 0:  # Δχ² stays within the level to the bound: the bound ends the interval
            out[name], out[name + "_at_bound"] = T * float(np.exp(ls[-1])), True
            continue
        i = int(over[0]) + 1
        f = (np.sqrt(dchi2) - root[i - 1]) / (root[i] - root[i - 1]) if root[i] > root[i - 1] else 0.0
        out[name], out[name + "_at_bound"] = T * float(np.exp(ls[i - 1] + np.clip(f, 0, 1) * (ls[i] - ls[i - 1]))), False
    return shares, out


_SHRINK = 0.35  # a rejected step's box: 0.35 of it (¼ was too timid along the curved valley, ½ too bold)


#: the adding–doubling finish's evaluation cap; a finish stopped by it is warned (not converged)
_FINISH_MAX_EVALS = 80


def _quasi_newton(fun, u0, J0, stop_norm: float, max_evals: int | None = None, ftol: float = 1e-6,
                  report: dict | None = None):
    """Bounded Gauss–Newton on [0, 1]^n in a box trust region, whose Jacobian starts from ``J0`` (the
    Kubelka–Munk model's, cheap; None: forward differences of ``fun``) and is corrected by Broyden's
    rank-one update after every evaluation (Broyden 1965; Dennis & Schnabel 1996, §8.3), so a step
    costs one evaluation of the physical model while the linear model predicts it well.

    A step is the bounded linear least-squares solution within the box ``|d|∞ ≤ Δ`` (scipy's BVLS).
    A rejected step shrinks Δ to 0.35 of the step; a well-predicted one (ratio ρ > 0.75) at the box edge
    doubles it. A Jacobian updated twice or more since its last forward differences that mispredicts
    (ρ < 0.3) is refreshed by them (n evaluations) instead of shrinking Δ; a step that gains less than
    ``ftol`` with a fresh Jacobian, or a box below 1e-9, ends the fit (a noisy or unreachable target).
    Returns (u, residual) at the best point; ``report["capped"]`` (when a dict is given) says whether
    the evaluation cap ended it instead."""
    from scipy.optimize import lsq_linear

    max_evals = _FINISH_MAX_EVALS if max_evals is None else max_evals
    converged = False

    u = np.array(u0, float)
    r = fun(u)
    n_eval = 1
    if J0 is None:
        J, since = _forward_jacobian(fun, u, r), 0
        n_eval += u.size
    else:
        J, since = np.array(J0, float), 99
    cost = float(r @ r)
    delta = 1.0
    while n_eval < max_evals and np.sqrt(cost) >= stop_norm and delta > 1e-9:
        fresh = since == 0
        d = lsq_linear(J, -r, bounds=(np.maximum(-u, -delta), np.minimum(1 - u, delta)), method="bvls").x
        step = float(np.max(np.abs(d)))
        if step < 1e-12:
            if fresh:
                converged = True
                break
            J, since = _forward_jacobian(fun, u, r), 0
            n_eval += u.size
            continue
        lin = r + J @ d
        predicted = cost - float(lin @ lin)
        u_new = np.clip(u + d, 0, 1)
        r_new = fun(u_new)
        n_eval += 1
        since += 1
        J = J + np.outer(r_new - r - J @ d, d) / float(d @ d)  # Broyden's update
        cost_new = float(r_new @ r_new)
        rho = (cost - cost_new) / predicted if predicted > 0 else -1.0
        worn = since > 2  # two Broyden updates or more since the last forward differences
        if cost_new < cost:
            gain = (cost - cost_new) / cost
            u, r, cost = u_new, r_new, cost_new
            if gain < ftol and fresh:
                converged = True
                break
            if rho > 0.75 and step > 0.9 * delta:
                delta = min(2 * delta, 1.0)
            elif rho < 0.25 and not worn:
                delta = _SHRINK * step
        elif not worn:
            delta = _SHRINK * step
        if rho < 0.3 and worn:  # the corrected Jacobian mispredicts: refresh it, keep the box
            J, since = _forward_jacobian(fun, u, r), 0
            n_eval += u.size
    if report is not None:
        report["capped"] = not converged and n_eval >= max_evals and np.sqrt(cost) >= stop_norm and delta > 1e-9
    return u, r


#: CIELAB's hue circle (CIE 15:2004 §8.2.1): h_ab = 0° red (+a*), 90° yellow (+b*), 180° green, 270° blue
_HUE_WORDS = ("red", "yellow", "green", "blue")


def _hue_words(lab_target, lab_match, min_chroma: float = 2.0) -> str | None:
    """``"too yellow: Δh° +20.0"``: the CIE hue angle of the match minus the target's, and the hue
    it has turned towards (of red, yellow, green, blue round the circle in that sense: the last one
    passed, or the next one ahead when none is); None
    when either colour is nearly neutral (C*ab < ``min_chroma``, the hue angle undefined)."""
    a, b = np.asarray(lab_target, float), np.asarray(lab_match, float)
    if min(np.hypot(a[1], a[2]), np.hypot(b[1], b[2])) < min_chroma:
        return None
    h_t = float(np.degrees(np.arctan2(a[2], a[1]))) % 360.0
    h_m = float(np.degrees(np.arctan2(b[2], b[1]))) % 360.0
    dh = (h_m - h_t + 180.0) % 360.0 - 180.0
    sense = 1.0 if dh > 0 else -1.0
    ahead = [((90.0 * k - h_t) * sense) % 360.0 or 360.0 for k in range(4)]  # how far round each hue lies
    passed = [k for k in range(4) if ahead[k] <= abs(dh)]
    k = max(passed, key=lambda i: ahead[i]) if passed else min(range(4), key=lambda i: ahead[i])
    return f"too {_HUE_WORDS[k]}: Δh° {dh:+.1f}"


def _missing_words(dlch, lab_target=None, lab_match=None):
    dL, dC, dH = dlch
    bits = []
    if abs(dL) > 0.3:
        bits.append(f"{'too light' if dL > 0 else 'too dark'} by ΔL* {dL:+.2f}")
    if abs(dC) > 0.3:
        bits.append(f"{'too chromatic' if dC > 0 else 'too dull'} by ΔC* {dC:+.2f}")
    if abs(dH) > 0.3:
        hue = None if lab_target is None else _hue_words(lab_target, lab_match)
        bits.append(f"{hue} (ΔH* {dH:+.2f})" if hue else f"hue off by ΔH* {dH:+.2f}")
    return ", ".join(bits) or "small in every direction"


def match_recipe(model: RecipeModel, target_reflectance=None, target_lab=None, mode: str = "colorimetric",
                 illuminant: str = "D65", test_illuminants=("A", "F11"), observer: str = "2",
                 metamerism_weight: float = 0.0, spectral_weight: float = 0.1, tolerance_de00: float = 1.0,
                 noise: float = 0.002, km_start: bool = True, n_refine: int = 2, stop_norm: float = 1e-5,
                 refine_above_de00: float = 0.3, km_tol: float = 1e-6, progress: bool = False) -> MatchResult:
    """Match ``model``'s free keys to a target spectrum (on the model's grid) or CIELAB (module docstring)."""
    from scipy.optimize import least_squares
    from tqdm import tqdm

    from nmmm.colour import delta_e2000, spectra_to_lab
    from nmmm.colour.illuminants import canonical_illuminant
    from nmmm.matching.metamerism import delta_e2000_residuals, delta_lch, metamerism_index

    if mode not in MATCH_MODES:
        raise InvalidInputError(f"mode must be one of {MATCH_MODES}, got {mode!r}")
    w = model.wavelength_nm
    Rt = None if target_reflectance is None else _check_target(target_reflectance, w)
    if Rt is None and target_lab is None:
        raise InvalidInputError("give a target spectrum or a target CIELAB")
    if Rt is None and mode == "spectral":
        raise InvalidInputError("a spectral match needs a target spectrum (a CIELAB target allows mode='colorimetric' only)")
    lab_t = spectra_to_lab(w, Rt, illuminant, observer) if Rt is not None else np.asarray(target_lab, float)
    if lab_t.shape != (3,) or not np.all(np.isfinite(lab_t)) or lab_t[0] < 0 or lab_t[0] > 100:
        raise InvalidInputError(f"target CIELAB must be (L*, a*, b*) with 0 <= L* <= 100, got {target_lab!r}")
    tests = tuple(test_illuminants) if Rt is not None else ()
    lab_t_test = {t: spectra_to_lab(w, Rt, t, observer) for t in tests}
    lo = np.array([b.lo for b in model.bounds])
    span = np.array([b.hi - b.lo for b in model.bounds])
    t0 = time.perf_counter()
    ev0 = dict(model.evaluations)  # the model counts over its life; a result reports this match's own

    def phys(u):
        return lo + np.clip(u, 0, 1) * span

    lab_of = _lab_function(w, illuminant, observer)
    lab_of_test = {t: _lab_function(w, t, observer) for t in (tests if metamerism_weight > 0 else ())}
    cache = {}  # adding-doubling spectra already computed: (u, quadrature) -> R

    def residuals(u, solver, quad):
        R = model.reflectance(phys(u), solver, quad)
        if solver == "ad":
            cache[(np.asarray(u, float).tobytes(), quad)] = R
        if mode == "spectral":
            return (R - Rt) * 100 / np.sqrt(w.size)
        lab = lab_of(R)
        parts = [delta_e2000_residuals(lab_t, lab)]
        for t, lab_fn in lab_of_test.items():
            corr = lab_fn(R) - (lab - lab_t)
            parts.append(np.sqrt(metamerism_weight) * delta_e2000_residuals(lab_t_test[t], corr))
        if spectral_weight > 0 and Rt is not None:
            parts.append(spectral_weight * (R - Rt) * 100 / np.sqrt(w.size))
        return np.concatenate(parts)

    class _Done(Exception):
        pass

    def stopping(u, solver, quad):
        r = residuals(u, solver, quad)
        if float(np.linalg.norm(r)) < stop_norm:  # matched to well below a visible difference: stop
            raise _Done(np.array(u, float), r)
        return r

    def fit(u0, solver, quad):
        try:
            r = least_squares(stopping, u0, args=(solver, quad), bounds=(0.0, 1.0), method="trf", x_scale=1.0,
                              diff_step=1e-4, xtol=km_tol, ftol=km_tol, gtol=km_tol, max_nfev=100)
            return r.x, r.fun
        except _Done as done:
            return done.args[0], done.args[1]

    starts = [np.full(lo.size, 0.5), np.clip((model.initial - lo) / span, 0, 1)]
    bar = tqdm(total=2, desc="match", disable=not progress, leave=False, unit="stage")
    stage1 = []
    for u0 in starts:
        if km_start:
            u, fun = fit(u0, "km", None)
            stage1.append((float(np.sum(fun**2)), u))
        else:
            stage1.append((0.0, u0))
    bar.update(1)
    stage1.sort(key=lambda t: t[0])
    distinct = []  # starts that reached the same KM optimum are refined once
    for c, u in stage1:
        if not any(np.max(np.abs(u - v)) < 1e-3 for _, v in distinct):
            distinct.append((c, u))
    stage1 = distinct
    quad = model.quad_pts_at(phys(stage1[0][1]))
    def finish(u0, max_evals=None):
        if km_start:  # the KM model's Jacobian (cheap) starts the quasi-Newton on adding-doubling
            J0 = _forward_jacobian(lambda v: residuals(v, "km", None), u0, residuals(u0, "km", None))
        else:
            J0 = None
        how = {}
        u, fun = _quasi_newton(lambda v: residuals(v, "ad", quad), u0, J0, stop_norm, max_evals=max_evals, report=how)
        q_auto = model.quad_pts_at(phys(u))
        R = cache.get((np.asarray(u, float).tobytes(), quad)) if q_auto == quad else None
        if R is None:
            R = model.reflectance(phys(u), "ad", None)  # the automatic quadrature, as `nmmm run` computes it
        lab = spectra_to_lab(w, np.clip(R, 0, None), illuminant, observer)
        return dict(u=u, R=R, lab=lab, de00=float(delta_e2000(lab_t, lab)), cost=float(np.sum(fun**2)),
                    R_quad=cache.get((np.asarray(u, float).tobytes(), quad)), capped=how.get("capped", False))

    cands = []
    for _, u0 in stage1[:max(1, n_refine)]:
        if cands and min(c["de00"] for c in cands) <= refine_above_de00:
            break  # the first finish reached the target: a second start would only confirm it
        cands.append(finish(u0))
    centre = np.full(lo.size, 0.5)
    if km_start and min(np.sqrt(c["cost"]) for c in cands) >= stop_norm \
            and not any(np.max(np.abs(u0 - centre)) < 1e-3 for _, u0 in stage1[:max(1, n_refine)]):
        # the KM optima can lead the finish into another basin than adding-doubling's own (a noise-free target
        # with one colourant absent: ΔE00 0.075 and the fractions 60 % off, where trf from the centre reaches 0):
        # a finish that did not reach stop_norm is tried from the box centre as well, within 10 evaluations a key
        # (that case: ~25 for 3 keys; a noisy target never reaches stop_norm, and this bounds what it costs there)
        cands.append(finish(centre, max_evals=10 * lo.size))
    bar.update(1)
    bar.close()
    cands.sort(key=lambda c: c["cost"] if mode == "spectral" else c["de00"])  # spectral: the objective itself
    unique = []  # starts that converged to the same values are one candidate
    for c in cands:
        if not any(np.max(np.abs(c["u"] - d["u"])) < 1e-4 for d in unique):
            unique.append(c)
    cands = unique
    best = cands[0]
    x = phys(best["u"])
    dlch = delta_lch(lab_t, best["lab"])
    mi = {canonical_illuminant(t): float(metamerism_index(w, Rt, best["R"], t, illuminant, observer)) for t in tests}
    rms = float(np.sqrt(np.mean((best["R"] - Rt) ** 2))) if Rt is not None else float("nan")
    active = [b.key + ("=LO" if u < 1e-6 else "=HI") for b, u in zip(model.bounds, best["u"]) if u < 1e-6 or u > 1 - 1e-6]
    se = {}
    if Rt is not None:  # Gauss-Newton covariance of the spectral residual at the optimum, noise σ per wavelength
        R0 = best["R_quad"] if best["R_quad"] is not None else model.reflectance(x, "ad", quad)
        J = np.empty((w.size, lo.size))
        for j in range(lo.size):  # one-sided steps of 1e-5 of the span, inwards from a bound
            h = (1e-5 if best["u"][j] < 0.5 else -1e-5) * span[j]
            e = np.zeros(lo.size)
            e[j] = h
            J[:, j] = (model.reflectance(x + e, "ad", quad) - R0) / h
        try:
            cov = noise**2 * np.linalg.inv(J.T @ J)
            se = {b.key: float(np.sqrt(max(cov[j, j], 0.0))) for j, b in enumerate(model.bounds)}
        except np.linalg.LinAlgError:
            se = {b.key: float("inf") for b in model.bounds}
    shares, total = {}, {}
    if se and lo.size >= 2 and all(_FRACTION_KEY.match(b.key) for b in model.bounds) and np.all(x > 0) \
            and all(np.isfinite(v) for v in se.values()):
        shares, total = _shares_and_total(model, x, J, R0, Rt, quad, lo, lo + span, noise)
    msgs = []
    if best["capped"] and best["de00"] > refine_above_de00:  # capped below it: a noisy target's spectral part
        msg = (f"the adding-doubling finish stopped at its cap of {_FINISH_MAX_EVALS} evaluations before converging "
               f"(ΔE00 {best['de00']:.3g} there): a better match may exist — narrow the --vary bounds or start the "
               "recipe nearer the target")
        warnings.warn(msg, stacklevel=2)
        msgs.append(msg)
    if total and (total["low_at_bound"] or total["high_at_bound"]):
        ends = [e for e, hit in (("lower", total["low_at_bound"]), ("upper", total["high_at_bound"])) if hit]
        msg = (f"the total of the matched fractions, {total['total']:.4g}, is pinned by the spectrum (noise {noise:g}) "
               f"only to {total['low']:.4g}–{total['high']:.4g} (68 % profile interval; "
               + ("both ends are" if len(ends) == 2 else f"its {ends[0]} end is") + " at the --vary bounds): the shares are what it fixes ("
               + ", ".join(f"{k} {v:.3g} ± {e:.2g}" for k, (v, e) in shares.items())
               + "); measure over black and white or fix the film's amount")
        warnings.warn(IdentifiabilityWarning(msg), stacklevel=2)
        msgs.append(msg)
    for j, b in enumerate(model.bounds):
        sigma = se.get(b.key, 0.0)
        if not sigma <= span[j]:  # also inf / nan: nothing in the spectrum pins the key within its range
            msg = (f"{b.key} = {x[j]:.4g} ± {sigma:.3g}: its uncertainty (noise {noise:g}) exceeds its bound span "
                   f"{b.lo:g}–{b.hi:g} — only the ratio is identifiable from one spectrum; measure over black and white "
                   "or fix one key")
            warnings.warn(IdentifiabilityWarning(msg), stacklevel=2)
            msgs.append(msg)
    if best["de00"] > tolerance_de00:
        msg = (f"the best match is ΔE00 = {best['de00']:.2f} (> {tolerance_de00:g}) from the target: the colourants "
               f"cannot reach it — {_missing_words(dlch, lab_t, best['lab'])}" + (f"; stopped by the bounds {active}" if active else "")
               + " (add a colourant that supplies the missing direction, or widen the bounds)")
        warnings.warn(msg, stacklevel=2)
        msgs.append(msg)
    rows = []
    for c in cands:
        rows.append(dict(**model.values(phys(c["u"])), dE00=c["de00"],
                         **{f"metamerism_index_{canonical_illuminant(t)}": float(metamerism_index(w, Rt, c["R"], t, illuminant,
                                                                                                  observer)) for t in tests},
                         illuminant=canonical_illuminant(illuminant), **dict(zip(("dL", "dC", "dH"),
                                                                                 (float(v) for v in delta_lch(lab_t, c["lab"]))))))
    return MatchResult(model.values(x), best["R"], w, lab_t, best["lab"], best["de00"], dlch, mi, rms,
                       canonical_illuminant(illuminant), mode, {k: v - ev0.get(k, 0) for k, v in model.evaluations.items()},
                       time.perf_counter() - t0, rows, se,
                       active, model.matched_raw(x), Rt, msgs, quad, shares, total, noise)
