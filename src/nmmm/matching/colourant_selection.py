"""Colourant selection (issue 17 item 3): given a palette larger than needed, the best subsets of
at most N colourants.

The palette is the varied ``…pigments.<i>.fraction`` keys of a :class:`~nmmm.matching.RecipeModel`
(other varied keys, e.g. ``film.thickness_nm``, stay free in every subset). Every subset of 1..N
palette keys is fitted with the fast Kubelka–Munk stage (the excluded colourants' fractions set to
0, the model's optics computed once for the whole palette) and ranked by ΔE00; the best
``n_finish`` subsets are then finished by :func:`~nmmm.matching.match_recipe` on the full physical
model (adding–doubling). :func:`select_colourants` returns them ranked: finished subsets by their
adding–doubling ΔE00 first, then the rest by their KM ΔE00 (``stage`` says which).
"""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, field

import numpy as np

from nmmm.errors import InvalidInputError

__all__ = ["SubsetMatch", "select_colourants", "subset_rows"]


@dataclass
class SubsetMatch:
    colourants: tuple  # the palette keys used
    values: dict  # every varied key -> value (the excluded colourants' fractions 0)
    de00: float
    metamerism: dict  # test illuminant -> index (ΔE00); empty for a CIELAB target
    dlch: np.ndarray
    stage: str  # "ad" (finished on the physical model) or "km" (ranking stage only)
    result: object = None  # the MatchResult of a finished subset
    reflectance: np.ndarray | None = None
    evaluations: dict = field(default_factory=dict)


class _SubsetModel:
    """A :class:`RecipeModel` restricted to some of its keys, the others held at 0 (excluded
    colourants); it offers what :func:`match_recipe` uses of a model."""

    def __init__(self, full, keep):
        self.full, self.keep = full, list(keep)
        self.bounds = tuple(full.bounds[i] for i in self.keep)
        self.wavelength_nm = full.wavelength_nm
        self.geometry, self.solver = full.geometry, full.solver
        self.initial = np.asarray(full.initial, float)[self.keep]
        self.evaluations = {"km": 0, "ad": 0}

    def _full(self, x):
        xf = np.zeros(len(self.full.bounds))
        xf[self.keep] = np.atleast_1d(np.asarray(x, float))
        return xf

    def values(self, x) -> dict:
        return {b.key: float(v) for b, v in zip(self.bounds, np.atleast_1d(x))}

    def matched_raw(self, x) -> dict:
        return self.full.matched_raw(self._full(x))

    def quad_pts_at(self, x) -> int:
        return self.full.quad_pts_at(self._full(x))

    def reflectance(self, x, solver=None, quad_pts=None):
        s = solver or self.solver
        self.evaluations[s] = self.evaluations.get(s, 0) + 1
        return self.full.reflectance(self._full(x), solver, quad_pts)


def _palette(model):
    from nmmm.matching.recipe_match import _FRACTION_KEY

    return [i for i, b in enumerate(model.bounds) if _FRACTION_KEY.match(b.key)]


def select_colourants(model, max_colourants: int, target_reflectance=None, target_lab=None, mode: str = "colorimetric",
                      illuminant: str = "D65", test_illuminants=("A", "F11"), observer: str = "2", n_finish: int = 3,
                      metamerism_weight: float = 0.0, tolerance_de00: float = 1.0, progress: bool = False) -> list:
    """The subsets of at most ``max_colourants`` of ``model``'s palette (its varied fraction keys),
    ranked (module docstring); a list of :class:`SubsetMatch`, best first. When even the best subset
    ends above ``tolerance_de00``, a warning says the palette cannot reach the target: how far the
    best is and which direction (ΔL*, ΔC*, hue in words) is missing."""
    import warnings

    from scipy.optimize import least_squares
    from tqdm import tqdm

    from nmmm.colour import delta_e2000, spectra_to_lab
    from nmmm.colour.illuminants import canonical_illuminant
    from nmmm.matching.metamerism import delta_e2000_residuals, delta_lch, metamerism_index
    from nmmm.matching.recipe_match import _check_target, _lab_function, match_recipe

    palette = _palette(model)
    k = len(palette)
    if isinstance(max_colourants, bool) or not isinstance(max_colourants, (int, np.integer)):
        raise InvalidInputError(f"--max-colourants must be a whole number, got {max_colourants!r}")
    if k == 0:
        raise InvalidInputError("colourant selection needs a palette: --vary pigments.<i>.fraction=LO:HI for each colourant")
    if not 1 <= max_colourants <= k:
        raise InvalidInputError(f"--max-colourants {max_colourants}: choose 1 to {k} (the palette has {k} colourants: "
                                f"{[model.bounds[i].key for i in palette]})")
    w = model.wavelength_nm
    Rt = None if target_reflectance is None else _check_target(target_reflectance, w)
    if Rt is None and target_lab is None:
        raise InvalidInputError("give a target spectrum or a target CIELAB")
    lab_t = spectra_to_lab(w, Rt, illuminant, observer) if Rt is not None else np.asarray(target_lab, float)
    lab_of = _lab_function(w, illuminant, observer)  # the weighting factors once (= spectra_to_lab, tested)
    tests = tuple(test_illuminants) if Rt is not None else ()
    others = [i for i in range(len(model.bounds)) if i not in palette]
    subsets = [tuple(c) for n in range(1, max_colourants + 1) for c in itertools.combinations(palette, n)]

    def km_fit(sub):
        lo = np.array([b.lo for b in sub.bounds])
        span = np.array([b.hi - b.lo for b in sub.bounds])

        def res(u):
            R = np.clip(sub.reflectance(lo + np.clip(u, 0, 1) * span, "km"), 0, None)
            parts = [delta_e2000_residuals(lab_t, lab_of(R))]
            if Rt is not None:
                parts.append((0.1 if mode == "colorimetric" else 1.0) * (R - Rt) * 100 / np.sqrt(w.size))
            return np.concatenate(parts)

        r = least_squares(res, np.full(lo.size, 0.5), bounds=(0.0, 1.0), method="trf", diff_step=1e-4, max_nfev=60)
        x = lo + r.x * span
        R = np.clip(sub.reflectance(x, "km"), 0, None)
        return x, R

    t0 = time.perf_counter()
    ranked = []
    for keep in tqdm(subsets, desc="colourant subsets", disable=not progress, leave=False, unit="subset"):
        sub = _SubsetModel(model, sorted(keep + tuple(others)))
        x, R = km_fit(sub)
        lab = spectra_to_lab(w, R, illuminant, observer)
        ranked.append((float(delta_e2000(lab_t, lab)), keep, sub, x, R, lab))
    ranked.sort(key=lambda t: t[0])
    out = []
    names = [b.key for b in model.bounds]
    for j, (de, keep, sub, x, R, lab) in enumerate(ranked):
        colourants = tuple(names[i] for i in keep)
        if j < max(1, n_finish):
            with warnings.catch_warnings():  # a poor subset's "cannot reach" is expected; the ranking says it
                warnings.simplefilter("ignore")
                res = match_recipe(sub, Rt, None if Rt is not None else lab_t, mode=mode, illuminant=illuminant,
                                   test_illuminants=tests, observer=observer, metamerism_weight=metamerism_weight)
            vals = dict(zip(names, sub._full(np.array(list(res.values.values())))))
            out.append(SubsetMatch(colourants, {k_: float(v) for k_, v in vals.items()}, res.de00, dict(res.metamerism),
                                   res.dlch, "ad", res, res.reflectance, dict(res.evaluations)))
        else:
            mi = {canonical_illuminant(t): float(metamerism_index(w, Rt, R, t, illuminant, observer)) for t in tests}
            vals = dict(zip(names, sub._full(x)))
            out.append(SubsetMatch(colourants, {k_: float(v) for k_, v in vals.items()}, de, mi, delta_lch(lab_t, lab), "km",
                                   None, R, dict(sub.evaluations)))
    out.sort(key=lambda s: (s.stage != "ad", s.de00))
    if out and out[0].result is not None:
        out[0].result.time_s = time.perf_counter() - t0
    if out and out[0].de00 > tolerance_de00:
        from nmmm.matching.recipe_match import _missing_words

        best = out[0]
        lab_best = best.result.lab if best.result is not None else None
        warnings.warn(f"the palette cannot reach the target: the best subset of at most {max_colourants} "
                      f"({' + '.join(best.colourants)}) is ΔE00 = {best.de00:.2f} (> {tolerance_de00:g}) — "
                      f"{_missing_words(best.dlch, lab_t if lab_best is not None else None, lab_best)} (add a colourant that supplies the missing "
                      "direction, allow more colourants, or widen the bounds)", UserWarning, stacklevel=2)
    return out


def subset_rows(selection, illuminant: str = "D65") -> list:
    """``matches.csv`` rows (one per subset, ranked): a column per varied key, ``dE00``,
    ``metamerism_index_<illuminant>``, the illuminant, ΔL*/ΔC*/ΔH*, the colourants and the stage."""
    from nmmm.colour.illuminants import canonical_illuminant

    tests = sorted({t for s in selection for t in s.metamerism})
    rows = []
    for s in selection:
        rows.append(dict(**s.values, dE00=float(s.de00),
                         **{f"metamerism_index_{t}": float(s.metamerism.get(t, float("nan"))) for t in tests},
                         illuminant=canonical_illuminant(illuminant),
                         **dict(zip(("dL", "dC", "dH"), (float(v) for v in s.dlch))),
                         colourants=" + ".join(s.colourants), stage=s.stage))
    return rows
