"""Bounds on the effective permittivity: Wiener, Hashin–Shtrikman, Bergman–Milton regions.

- :func:`wiener_bounds` — the harmonic and arithmetic means (any microstructure, n phases).
- :func:`hashin_shtrikman_bounds` — the bounds for isotropic 3-D mixtures (n phases, real ε;
  two phases, complex ε: the two Maxwell Garnett end points).
- :func:`bergman_milton_bounds` — for complex ε of two phases, the lens-shaped regions of
  the complex plane bounded by two circular arcs that contain every possible effective ε:
  ``kind="wiener"`` (fraction known, any microstructure) or ``kind="hashin_shtrikman"``
  (fraction known, isotropic). Returns a :class:`BoundingRegion` with ``contains(eps)``.

Notes
-----
Real, positive ε: Wiener ``(Σ f_i/eps_i)^-1 <= eps <= Σ f_i eps_i``; Hashin–Shtrikman
``eps_HS(eps_ref) = (Σ_i f_i/(eps_i + 2 eps_ref))^-1 − 2 eps_ref`` with eps_ref = min eps_i
(lower) and max eps_i (upper). For two phases eps_HS(eps_host) is Maxwell Garnett with
that host.

Complex ε (two phases a, b, fraction f of a, Δ = eps_a − eps_b). With the Bergman
spectral representation, the extreme microstructures are one-pole functions, whose values
lie on circular arcs:

- Wiener region: bounded by the aligned Maxwell Garnett media of a in b and of b in a with
  depolarization factor L ∈ [0, 1] (confocal coated ellipsoids), each arc running from the
  arithmetic mean (L = 0, parallel layers) to the harmonic mean (L = 1, series layers).
- Hashin–Shtrikman region (isotropic): bounded by the arcs
  ``eps = eps_arith − f(1−f) Δ² / (3 (eps_b + t Δ))``, t ∈ [(1−f)/3, 1 − f/3], and
  ``1/eps = rho_arith − (2/3) f(1−f) Δρ² / (rho_b + t Δρ)`` (ρ = 1/ε),
  t ∈ [2(1−f)/3, 1 − 2f/3]; both join the two Maxwell Garnett points (the HS points).

References
----------
- O. Wiener, "Die Theorie des Mischkörpers für das Feld der stationären Strömung",
  Abh. Math.-Phys. Kl. Sächs. Ges. Wiss. 32, 509 (1912).
- Z. Hashin, S. Shtrikman, "A variational approach to the theory of the effective magnetic
  permeability of multiphase materials", J. Appl. Phys. 33, 3125 (1962).
- D. J. Bergman, "Exactly solvable microscopic geometries and rigorous bounds for the
  complex dielectric constant of a two-component composite material",
  Phys. Rev. Lett. 44, 1285 (1980).
- G. W. Milton, "Bounds on the complex dielectric constant of a composite material",
  Appl. Phys. Lett. 37, 300 (1980); J. Appl. Phys. 52, 5286 and 5294 (1981).
- D. E. Aspnes, "Bounds on allowed values of the effective dielectric function of
  two-component composites at finite frequencies", Phys. Rev. B 25, 1358 (1982).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from nmmm.ema._validation import as_eps, as_fraction
from nmmm.errors import InvalidInputError


def _stack(eps_phases, fractions, need_real=False):
    if not isinstance(eps_phases, (list, tuple)) or not isinstance(fractions, (list, tuple)) \
            or len(eps_phases) != len(fractions) or len(eps_phases) < 1:
        raise InvalidInputError("give a list of phase permittivities and a list of as many fractions")
    eps = [as_eps(e, f"eps_phases[{i}]") for i, e in enumerate(eps_phases)]
    fr = [as_fraction(f, f"fractions[{i}]") for i, f in enumerate(fractions)]
    shape = np.broadcast_shapes(*[e.shape for e in eps], *[f.shape for f in fr])
    e = np.stack([np.broadcast_to(x, shape) for x in eps], -1)
    f = np.stack([np.broadcast_to(x, shape) for x in fr], -1)
    if np.any(np.abs(f.sum(-1) - 1) > 1e-6):
        raise InvalidInputError("fractions must sum to 1 (list every phase)")
    if need_real:
        if np.any(np.abs(e.imag) > 0) or np.any(e.real <= 0):
            raise InvalidInputError(
                "these bounds are orderings of real, positive permittivities; for complex eps of two "
                "phases use bergman_milton_bounds (regions of the complex plane)")
        e = e.real
    return e, f


def wiener_bounds(eps_phases: ArrayLike, fractions: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Wiener bounds ``(lower, upper) = ((Σ f_i/eps_i)^-1, Σ f_i eps_i)``.

    For complex ε these are the series and parallel laminates (the two end points of the
    complex Wiener region, see :func:`bergman_milton_bounds`).

    >>> [round(float(x.real), 4) for x in wiener_bounds([1.0, 4.0], [0.5, 0.5])]
    [1.6, 2.5]
    """
    e, f = _stack(eps_phases, fractions)
    return 1 / np.sum(f / e, -1), np.sum(f * e, -1)


def hashin_shtrikman_bounds(eps_phases: ArrayLike, fractions: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Hashin–Shtrikman bounds ``(lower, upper)`` for an isotropic 3-D mixture.

    Real positive ε, n phases: ``eps_HS(eps_ref) = (Σ f_i/(eps_i + 2 eps_ref))^-1 − 2 eps_ref``
    with eps_ref the smallest (lower) and largest (upper) phase ε (Hashin & Shtrikman 1962).
    Complex ε, two phases: the two Maxwell Garnett points (phase 1 in 2, phase 2 in 1),
    returned in that order — the corners of the complex HS region.

    >>> [round(float(x), 4) for x in hashin_shtrikman_bounds([1.0, 4.0], [0.5, 0.5])]
    [2.0, 2.2857]
    """
    try:
        e, f = _stack(eps_phases, fractions, need_real=True)
    except InvalidInputError:
        e, f = _stack(eps_phases, fractions)
        if e.shape[-1] != 2:
            raise InvalidInputError("complex Hashin–Shtrikman bounds are given for two phases; "
                                    "use bergman_milton_bounds") from None
        from nmmm.ema.maxwell_garnett_rule import maxwell_garnett

        return (maxwell_garnett(e[..., 0], e[..., 1], f[..., 0]),
                maxwell_garnett(e[..., 1], e[..., 0], f[..., 1]))

    def hs(ref):
        return 1 / np.sum(f / (e + 2 * ref[..., None]), -1) - 2 * ref

    return hs(e.min(-1)), hs(e.max(-1))


@dataclass(frozen=True)
class BoundingRegion:
    """A lens of the complex plane bounded by two circular arcs (arrays (..., n_points)),
    both running between the same two end points."""

    kind: str
    arc_1: np.ndarray
    arc_2: np.ndarray

    @property
    def boundary(self) -> np.ndarray:
        """The closed boundary: arc_1 then arc_2 reversed, (..., 2 n_points)."""
        return np.concatenate([self.arc_1, self.arc_2[..., ::-1]], axis=-1)

    def contains(self, eps, rtol: float = 1e-6) -> np.ndarray:
        """True where ``eps`` (broadcast against the leading axes) lies inside or on the lens
        (within ``rtol`` of its size, since the arcs are sampled)."""
        z = np.asarray(eps, dtype=complex)[..., None]
        poly = self.boundary
        a, b = poly, np.roll(poly, -1, axis=-1)
        # ray casting to +infinity along the real axis
        cond = (a.imag > z.imag) != (b.imag > z.imag)
        with np.errstate(divide="ignore", invalid="ignore"):
            x_cross = a.real + (z.imag - a.imag) * (b.real - a.real) / (b.imag - a.imag)
        inside = np.sum(cond & (z.real < x_cross), axis=-1) % 2 == 1
        # distance to the boundary segments (points on the boundary and flat lenses)
        ab = b - a
        t = np.clip(np.real((z - a) * np.conj(ab)) / np.maximum(np.abs(ab) ** 2, 1e-300), 0, 1)
        dist = np.min(np.abs(z - (a + t * ab)), axis=-1)
        size = np.max(np.abs(poly - poly[..., :1]), axis=-1) + np.abs(poly[..., 0])
        # the sampled arc is a chord polygon: allow its sagitta
        n = self.arc_1.shape[-1]
        sag = size * (np.pi / max(n - 1, 1)) ** 2
        return inside | (dist <= rtol * size + sag)


def bergman_milton_bounds(eps_a: ArrayLike, eps_b: ArrayLike, fraction: ArrayLike, kind: str = "hashin_shtrikman",
                          n_points: int = 201) -> BoundingRegion:
    """Bergman–Milton bounding region of the complex effective ε of phases a (fraction f)
    and b (see the module notes for the arcs). ``kind`` is ``"hashin_shtrikman"``
    (isotropic composites) or ``"wiener"`` (any microstructure). Arrays broadcast; the arcs
    get a last axis of ``n_points``.
    """
    ea = as_eps(eps_a, "eps_a")[..., None]
    eb = as_eps(eps_b, "eps_b")[..., None]
    f = as_fraction(fraction)[..., None]
    s = np.linspace(0.0, 1.0, int(n_points))
    d = ea - eb
    if kind == "wiener":
        L = s
        arc1 = eb + f * eb * d / (eb + (1 - f) * L * d)            # a in b, L from 0 to 1
        arc2 = ea - (1 - f) * ea * d / (ea - f * L * d)            # b in a, L from 0 to 1
    elif kind == "hashin_shtrikman":
        arith = f * ea + (1 - f) * eb
        t1 = (1 - f) / 3 + s * ((1 - f / 3) - (1 - f) / 3)
        arc1 = arith - f * (1 - f) * d * d / (3 * (eb + t1 * d))
        ra, rb = 1 / ea, 1 / eb
        dr = ra - rb
        rho_arith = f * ra + (1 - f) * rb
        t2 = 2 * (1 - f) / 3 + s * ((1 - 2 * f / 3) - 2 * (1 - f) / 3)
        arc2 = 1 / (rho_arith - 2 * f * (1 - f) * dr * dr / (3 * (rb + t2 * dr)))
    else:
        raise InvalidInputError(f"kind must be 'hashin_shtrikman' or 'wiener', got {kind!r}")
    return BoundingRegion(kind, arc1, arc2)


__all__ = ["BoundingRegion", "bergman_milton_bounds", "hashin_shtrikman_bounds", "wiener_bounds"]
