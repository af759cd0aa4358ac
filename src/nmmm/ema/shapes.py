"""Inclusion shapes: depolarization factors of ellipsoids, spheroids and (approximately) cubes.

A homogeneous ellipsoid in a uniform field polarizes uniformly; along its axis j the
field inside is set by the depolarization factor L_j (L1 + L2 + L3 = 1, sphere 1/3 each).
The quasi-static polarizability per unit volume along axis j is
``(eps_i - eps_m) / (eps_m + L_j (eps_i - eps_m))``.

- :func:`ellipsoid_depolarization` — L1, L2, L3 of an ellipsoid with semi-axes a, b, c
  (Carlson's symmetric elliptic integral R_D, exact).
- :func:`spheroid_depolarization` — (L_eq, L_eq, L_polar) from the aspect ratio polar /
  equatorial: > 1 prolate (rods, needles), < 1 oblate (discs, platelets).
- :data:`CUBE_DEPOLARIZATION` — a documented *approximation* for cubes.
- :class:`Shape` — a small frozen description (depolarization factors + orientation).

Notes
-----
Cubes are not ellipsoids: their internal field is not uniform and their plasmon response
splits into several modes. nmmm approximates a cube by a sphere-like isotropic inclusion
with the *effective* depolarization factor ``L_cube = 1 / 3.6442 = 0.2744`` chosen so that
the polarizability is exact in both limits eps_i -> eps_m (any shape: ``(eps_i - eps_m) V``)
and eps_i -> infinity (perfectly conducting cube: ``3.6442 V``, Sihvola et al. 2007).
Between the two limits it is an interpolation; it shifts a metal cube's main resonance
to the red of a sphere's, as the full computations do, but does not reproduce the
secondary cube modes.

References
----------
- J. A. Osborn, "Demagnetizing factors of the general ellipsoid", Phys. Rev. 67, 351 (1945).
- C. F. Bohren, D. R. Huffman, Absorption and Scattering of Light by Small Particles
  (Wiley 1983), §5.3 (eqs. 5.32–5.35).
- B. C. Carlson, "Numerical computation of real or complex elliptic integrals",
  Numer. Algorithms 10, 13 (1995) (R_D); the demagnetizing factors as R_D:
  L_a = (abc/3) R_D(b², c², a²).
- A. Sihvola, P. Ylä-Oijala, S. Järvenpää, J. Avelin, "Polarizabilities of Platonic solids",
  IEEE Trans. Antennas Propag. 55, 2226 (2007), doi:10.1109/TAP.2007.901866.
- A. Sihvola, Electromagnetic Mixing Formulas and Applications (IEE 1999), ch. 4.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import elliprd

from nmmm.ema._validation import as_depolarization, check_orientation
from nmmm.spectra import check_positive

#: Normalized polarizability alpha / V of a perfectly conducting cube (Sihvola et al. 2007).
CUBE_CONDUCTING_POLARIZABILITY = 3.6442

#: Effective depolarization factor of a cube (approximation, see the module notes).
CUBE_DEPOLARIZATION = 1.0 / CUBE_CONDUCTING_POLARIZABILITY

#: Depolarization factors of a sphere.
SPHERE_DEPOLARIZATION = (1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0)


def ellipsoid_depolarization(a: ArrayLike, b: ArrayLike, c: ArrayLike) -> np.ndarray:
    """Depolarization factors (L_a, L_b, L_c) of an ellipsoid with semi-axes a, b, c.

    ``L_a = (abc/2) ∫_0^∞ ds / ((s + a²) sqrt((s + a²)(s + b²)(s + c²)))
    = (abc/3) R_D(b², c², a²)`` (Osborn 1945; Carlson 1995), and cyclically.
    Semi-axes in any common unit, > 0; they broadcast; the result has a last axis of 3.

    >>> ellipsoid_depolarization(1.0, 1.0, 1.0).round(6).tolist()
    [0.333333, 0.333333, 0.333333]
    """
    a = check_positive(a, "a")
    b = check_positive(b, "b")
    c = check_positive(c, "c")
    a, b, c = np.broadcast_arrays(a, b, c)
    # scale so that the largest semi-axis is 1 (R_D is homogeneous of degree -3/2)
    s = np.maximum(np.maximum(a, b), c)
    a, b, c = a / s, b / s, c / s
    a2, b2, c2 = a * a, b * b, c * c
    abc3 = a * b * c / 3.0
    La = abc3 * elliprd(b2, c2, a2)
    Lb = abc3 * elliprd(c2, a2, b2)
    Lc = abc3 * elliprd(a2, b2, c2)
    L = np.stack([La, Lb, Lc], axis=-1)
    return L / L.sum(axis=-1, keepdims=True)  # remove the last ulp of round-off


def spheroid_depolarization(aspect_ratio: ArrayLike) -> np.ndarray:
    """Depolarization factors (L_eq, L_eq, L_polar) of a spheroid.

    ``aspect_ratio`` = polar semi-axis / equatorial semi-axis: > 1 prolate (rods; needles
    as it grows, L_polar -> 0), 1 sphere, < 1 oblate (discs; platelets as it shrinks,
    L_polar -> 1). The polar (symmetry) axis is the third one. Broadcasts.

    >>> spheroid_depolarization(1.0).round(6).tolist()
    [0.333333, 0.333333, 0.333333]
    """
    r = check_positive(aspect_ratio, "aspect_ratio")
    return ellipsoid_depolarization(np.ones_like(r), np.ones_like(r), r)


def ellipsoid_polarizability(eps_inclusion: ArrayLike, eps_host: ArrayLike, depolarization: ArrayLike) -> np.ndarray:
    """Quasi-static polarizability per unit volume of an ellipsoid, along each axis,
    relative to the host: ``alpha_j = (eps_i - eps_m) / (eps_m + L_j (eps_i - eps_m))``
    (Bohren & Huffman 1983, eq. 5.32, divided by eps_m V). Last axis of the result: 3.
    """
    from nmmm.ema._validation import as_eps

    ei = as_eps(eps_inclusion, "eps_inclusion")[..., None]
    em = as_eps(eps_host, "eps_host")[..., None]
    L = as_depolarization(depolarization)
    d = ei - em
    return d / (em + L * d)


def cube_polarizability(eps_inclusion: ArrayLike, eps_host: ArrayLike) -> np.ndarray:
    """Approximate polarizability per unit volume of a cube relative to the host:
    ``(eps_i - eps_m) / (eps_m + L_cube (eps_i - eps_m))`` with ``L_cube = 1/3.6442``
    (exact for eps_i -> eps_m and eps_i -> infinity, Sihvola et al. 2007; an
    interpolation in between — see the module notes)."""
    from nmmm.ema._validation import as_eps

    ei = as_eps(eps_inclusion, "eps_inclusion")
    em = as_eps(eps_host, "eps_host")
    d = ei - em
    return d / (em + CUBE_DEPOLARIZATION * d)


@dataclass(frozen=True)
class Shape:
    """An inclusion shape for the effective-medium formulas.

    ``kind`` is ``"ellipsoid"`` (exact quasi-static theory; ``depolarization`` are the
    factors (L1, L2, L3) along its axes, summing to 1) or ``"cube"`` (the documented
    effective-depolarization approximation, always isotropic). ``orientation`` is
    ``"random"`` (isotropic medium, scalar ε) or ``"aligned"`` (inclusions share their
    axes with the laboratory frame: diagonal tensor ε, last axis of length 3).
    """

    depolarization: tuple[float, float, float] = SPHERE_DEPOLARIZATION
    orientation: str = "random"
    name: str = "sphere"
    kind: str = "ellipsoid"

    def __post_init__(self):
        from nmmm.errors import InvalidInputError

        check_orientation(self.orientation)
        if self.kind == "cube":
            object.__setattr__(self, "depolarization", (CUBE_DEPOLARIZATION,) * 3)
            return
        if self.kind != "ellipsoid":
            raise InvalidInputError(f"Shape.kind must be 'ellipsoid' or 'cube', got {self.kind!r}")
        L = as_depolarization(self.depolarization)
        if L.shape != (3,):
            raise InvalidInputError("Shape holds one set of three depolarization factors; "
                                    "for arrays of shapes call the formulas with depolarization arrays")
        object.__setattr__(self, "depolarization", tuple(float(x) for x in L))

    @classmethod
    def sphere(cls) -> "Shape":
        """A sphere (L = 1/3 on every axis)."""
        return cls(SPHERE_DEPOLARIZATION, "random", "sphere")

    @classmethod
    def spheroid(cls, aspect_ratio: float, orientation: str = "random") -> "Shape":
        """A spheroid with ``aspect_ratio`` = polar / equatorial semi-axis (see
        :func:`spheroid_depolarization`)."""
        L = spheroid_depolarization(float(aspect_ratio))
        kind = "prolate" if aspect_ratio > 1 else ("oblate" if aspect_ratio < 1 else "sphere")
        return cls(tuple(L), orientation, f"{kind} spheroid (aspect ratio {aspect_ratio:g})")

    @classmethod
    def ellipsoid(cls, a: float, b: float, c: float, orientation: str = "random") -> "Shape":
        """A general ellipsoid with semi-axes a, b, c."""
        return cls(tuple(ellipsoid_depolarization(a, b, c)), orientation, f"ellipsoid ({a:g}:{b:g}:{c:g})")

    @classmethod
    def cube(cls) -> "Shape":
        """A cube, **approximated** (see the module notes): isotropic, with the effective
        depolarization factor :data:`CUBE_DEPOLARIZATION`."""
        return cls((CUBE_DEPOLARIZATION,) * 3, "random", "cube (effective-depolarization approximation)", "cube")

    def polarizability(self, eps_inclusion, eps_host) -> np.ndarray:
        """Polarizability per unit volume relative to the host, last axis 3 (one per axis)."""
        if self.kind == "cube":
            a = cube_polarizability(eps_inclusion, eps_host)
            return np.repeat(a[..., None], 3, axis=-1)
        return ellipsoid_polarizability(eps_inclusion, eps_host, self.depolarization)


__all__ = [
    "cube_polarizability",
    "ellipsoid_polarizability",
    "CUBE_CONDUCTING_POLARIZABILITY",
    "CUBE_DEPOLARIZATION",
    "SPHERE_DEPOLARIZATION",
    "Shape",
    "ellipsoid_depolarization",
    "spheroid_depolarization",
]
