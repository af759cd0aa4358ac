"""What a formulator reads from a film or a stack: over white and over black, masstone,
contrast ratio, hiding thickness and spreading rate, tinting strength.

- :func:`formulator_quantities` — all of them for a :class:`~nmmm.layers.coat_stack.CoatStack`
  whose *top* coat is the paint under test (:class:`FormulatorQuantities`).
- :func:`contrast_ratio` — Y over black / Y over white (ISO 6504-3:2019; ASTM D2805-11).
- :func:`hiding_thickness_for` — the top coat's thickness for a contrast ratio (0.98 by default)
  and :func:`spreading_rate_m2_per_L` = 10⁶ / thickness_nm (dry film).
- :func:`tinting_strength` — relative tinting strength of a colour pigment against a reference
  in the same white, ISO 787-24:1985 style, from K/S at the wavelength of maximum absorption.

Conventions: the white and black backgrounds are Lambertian reflectances 0.80 and 0.0 (ISO
6504-3 asks for a white chart of Y = 80 ± 2 and a black of Y ≤ 1); Y is CIE 1931 2° under D65
(ISO 6504-3 allows D65/10° or C/2°: the observer changes CR by < 1e-3 for near-neutral whites);
the masstone is the opaque film (infinite thickness); the geometry is the instrument's
(:mod:`nmmm.layers.geometries`). Tinting strength: the variant of ISO 787-24 §8.3 "from K/S
at the wavelength of maximum absorption": K/S = (1 − R∞)²/(2R∞) (Kubelka–Munk) of the opaque
reductions, R∞ the body reflectance recovered from the SCE reading by inverting Saunderson's
equation (k2 of the binder), at the wavelength where the reference reduction reflects least;
strength = 100 · (K/S)_test / (K/S)_ref %.

References
----------
- ISO 6504-3:2019 Paints and varnishes — Determination of hiding power — Part 3: contrast
  ratio of light-coloured paints at a fixed spreading rate.
- ASTM D2805-11 Standard test method for hiding power of paints by reflectometry.
- ISO 787-24:1985 General methods of test for pigments and extenders — Part 24: relative
  tinting strength of coloured pigments and relative scattering power of white pigments —
  photometric methods.
- P. Kubelka, F. Munk, Z. Tech. Phys. 12, 593 (1931); J. L. Saunderson, JOSA 32, 727 (1942).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from nmmm.errors import InvalidInputError
from nmmm.layers.coat_stack import CoatStack, Substrate, coat_optics, stack_reflectance

__all__ = ["FormulatorQuantities", "formulator_quantities", "contrast_ratio", "hiding_thickness_for",
           "spreading_rate_m2_per_L", "tinting_strength", "WHITE_CHART", "BLACK_CHART"]

#: ISO 6504-3 chart reflectances (Lambertian): white Y = 0.80, black 0
WHITE_CHART = 0.80
BLACK_CHART = 0.0


def _Y(w, R):
    from nmmm.colour import spectra_to_xyz

    white = spectra_to_xyz(w, np.ones_like(w))
    return np.asarray(spectra_to_xyz(w, R))[..., 1] / np.asarray(white)[..., 1]


def contrast_ratio(wavelength_nm: ArrayLike, over_black: ArrayLike, over_white: ArrayLike) -> float:
    """Y(over black) / Y(over white), CIE 1931 2° under D65 (ISO 6504-3; ASTM D2805)."""
    w = np.asarray(wavelength_nm, float)
    return float(_Y(w, np.asarray(over_black, float)) / _Y(w, np.asarray(over_white, float)))


def spreading_rate_m2_per_L(thickness_nm) -> float:
    """Area covered by one litre at a dry film thickness: 10⁻³ m³ / (thickness · 10⁻⁹ m) = 10⁶/thickness_nm."""
    t = float(thickness_nm)
    if not t > 0:
        raise InvalidInputError(f"thickness_nm must be > 0, got {thickness_nm!r}")
    return 1e6 / t


@dataclass(frozen=True)
class FormulatorQuantities:
    wavelength_nm: np.ndarray
    over_white: np.ndarray
    over_black: np.ndarray
    masstone: np.ndarray
    contrast_ratio: float
    hiding_thickness_nm: float  # CR = target; inf if never reached below 10 mm
    spreading_rate_m2_per_L: float
    target_contrast_ratio: float
    geometry: str
    solver: str


def _with(stack, thickness, substrate):
    coats = (stack.coats[0].with_thickness(thickness),) + stack.coats[1:]
    return stack.replace(coats=coats, substrate=substrate)


def hiding_thickness_for(stack: CoatStack, wavelength_nm, target: float = 0.98, solver: str = "ad",
                         geometry: str = "de:8", optics=None, max_thickness_nm: float = 1e7) -> float:
    """Thickness (nm) of the top coat at which the contrast ratio reaches ``target``, by bisection
    in log thickness (CR rises monotonically with thickness); inf when not reached below
    ``max_thickness_nm``."""
    if not 0 < target < 1:
        raise InvalidInputError(f"target contrast ratio must lie in (0, 1), got {target!r}")
    w = np.asarray(wavelength_nm, float)
    opts = tuple(coat_optics(c, w) for c in stack.coats) if optics is None else optics

    def cr(t):
        b = stack_reflectance(_with(stack, t, Substrate(reflectance=BLACK_CHART)), w, solver, geometry, optics=opts)
        wh = stack_reflectance(_with(stack, t, Substrate(reflectance=WHITE_CHART)), w, solver, geometry, optics=opts)
        return contrast_ratio(w, b.reflectance, wh.reflectance)

    hi = float(max_thickness_nm)
    if cr(hi) < target:
        return float("inf")
    lo = 10.0
    for _ in range(40):
        mid = np.sqrt(lo * hi)
        if cr(mid) >= target:
            hi = mid
        else:
            lo = mid
        if hi / lo < 1.01:  # 1 % in thickness
            break
    return float(hi)


def formulator_quantities(stack: CoatStack, wavelength_nm: ArrayLike, solver: str = "ad", geometry: str = "de:8",
                          target: float = 0.98, hiding: bool = True) -> FormulatorQuantities:
    """Over white (0.80) and over black, masstone, contrast ratio, hiding thickness and spreading
    rate of the top coat of ``stack`` at its thickness (module docstring)."""
    w = np.asarray(wavelength_nm, float)
    opts = tuple(coat_optics(c, w) for c in stack.coats)
    t = stack.coats[0].thickness_nm
    wh = stack_reflectance(_with(stack, t, Substrate(reflectance=WHITE_CHART)), w, solver, geometry, optics=opts).reflectance
    bl = stack_reflectance(_with(stack, t, Substrate(reflectance=BLACK_CHART)), w, solver, geometry, optics=opts).reflectance
    mass = stack_reflectance(_with(stack, np.inf, Substrate(reflectance=BLACK_CHART)), w, solver, geometry,
                             optics=opts).reflectance
    cr = contrast_ratio(w, bl, wh)
    h = hiding_thickness_for(stack, w, target, solver, geometry, optics=opts) if hiding else float("nan")
    sr = spreading_rate_m2_per_L(h) if np.isfinite(h) else 0.0
    return FormulatorQuantities(w, wh, bl, mass, cr, h, sr, target, geometry, solver)


def _k_over_s(R_sce, n_binder):
    from nmmm.layers.kubelka_munk import saunderson_k1, saunderson_k2

    k1, k2 = saunderson_k1(n_binder), saunderson_k2(n_binder)
    x = np.asarray(R_sce, float) / ((1 - k1) * (1 - k2))
    Rinf = np.clip(x / (1 + k2 * x), 1e-9, 1 - 1e-12)  # inverse of R = (1-k1)(1-k2) Rb/(1-k2 Rb)
    return (1 - Rinf) ** 2 / (2 * Rinf)


def tinting_strength(wavelength_nm: ArrayLike, test_masstone_sce: ArrayLike, reference_masstone_sce: ArrayLike,
                     n_binder: ArrayLike) -> dict:
    """Relative tinting strength (%) of a test reduction against a reference reduction (both
    opaque, SCE readings, the same white and ratio): ISO 787-24 style from K/S at the
    wavelength of maximum absorption of the reference (module docstring)."""
    w = np.asarray(wavelength_nm, float)
    ref = np.asarray(reference_masstone_sce, float)
    i = int(np.argmin(ref))
    nb = np.broadcast_to(np.asarray(n_binder, float), w.shape)
    ks_t = _k_over_s(np.asarray(test_masstone_sce, float)[i], nb[i])
    ks_r = _k_over_s(ref[i], nb[i])
    return {"tinting_strength_percent": float(100 * ks_t / ks_r), "wavelength_nm": float(w[i]),
            "k_over_s_test": float(ks_t), "k_over_s_reference": float(ks_r)}
