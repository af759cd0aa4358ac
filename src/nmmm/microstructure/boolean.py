"""Boolean models of spheres, cubes and discs (Matheron), with their analytic statistics.

A Boolean model is the union of independent random grains (spheres, cubes with random
orientations, discs/platelets) centred on the points of a Poisson process of intensity θ
(grains per nm^d). Its volume fraction is

    p = 1 − exp(−θ · E[V])                       (Matheron 1975, eq. 3-4-3)

and its covariance C(h) = P(x ∈ A, x + h ∈ A) is

    C(h) = 1 − 2q + q^(2 − r(h)),  q = 1 − p,  r(h) = K̄(h) / K̄(0)

with K̄ the mean geometric covariogram of the grain (Matheron 1975; Jeulin 2021, ch. 9).

- :func:`boolean_particles` — a realisation as an analytic :class:`ParticleSet`.
- :func:`boolean_spheres`, :func:`boolean_cubes`, :func:`boolean_discs` — voxelised
  realisations (:class:`Microstructure`), 2-D or 3-D, periodic, seeded.
- :func:`boolean_fraction`, :func:`boolean_intensity` — p ↔ θ.
- :func:`covariogram_ratio` — r(h) for spheres (3-D) and discs (2-D).
- :func:`boolean_covariance` — the analytic covariance above.
- :func:`boolean_integral_range` — integral range A = ∫(C(h) − p²) dh / (p(1 − p)).

References
----------
- Matheron, G. (1975). Random Sets and Integral Geometry. Wiley.
- Jeulin, D. (2021). Morphological Models of Random Structures. Springer.
  https://doi.org/10.1007/978-3-030-75452-5
- Lantuéjoul, C. (2002). Geostatistical Simulation: Models and Algorithms. Springer
  (integral range, section 2.3).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import integrate

from nmmm.errors import InvalidInputError
from nmmm.microstructure.base import (
    Microstructure,
    as_box_nm,
    as_size_distribution,
    as_voxel_nm,
    random_rotations,
    seed_param,
)
from nmmm.microstructure.particles import SHAPES, ParticleSet
from nmmm.spectra import check_fraction, check_positive

__all__ = [
    "GRAINS",
    "boolean_particles",
    "boolean_spheres",
    "boolean_cubes",
    "boolean_discs",
    "boolean_fraction",
    "boolean_intensity",
    "covariogram_ratio",
    "boolean_covariance",
    "boolean_integral_range",
    "cell_box_nm",
]

GRAINS = ("sphere", "cube", "disc")


def cell_box_nm(shape, voxel_nm) -> tuple:
    """Cell size in nm from a grid shape and voxel size."""
    shape = tuple(int(s) for s in np.atleast_1d(shape))
    if len(shape) not in (2, 3) or min(shape) < 1:
        raise InvalidInputError(f"shape must hold 2 or 3 positive voxel counts, got {shape}")
    v = as_voxel_nm(voxel_nm, len(shape))
    return tuple(s * x for s, x in zip(shape, v))


def boolean_fraction(intensity, mean_volume_nm):
    """Volume fraction p = 1 − exp(−θ E[V]) of a Boolean model (Matheron 1975).

    >>> round(float(boolean_fraction(1e-3, 100.0)), 6)
    0.095163
    """
    return 1.0 - np.exp(-np.asarray(intensity, float) * np.asarray(mean_volume_nm, float))


def boolean_intensity(fraction, mean_volume_nm):
    """Intensity θ = −ln(1 − p) / E[V] (grains per nm^d) giving volume fraction p.

    >>> round(float(boolean_intensity(0.095163, 100.0)), 6)
    0.001
    """
    p = check_fraction(fraction, "fraction")
    if np.any(p >= 1):
        raise InvalidInputError("a Boolean model reaches p = 1 only for infinite intensity; give fraction < 1")
    return -np.log1p(-p) / np.asarray(mean_volume_nm, float)


def covariogram_ratio(h_nm, radius_nm, grain: str = "sphere"):
    """r(h) = K(h)/K(0) of a sphere (3-D) or disc (2-D) of radius R, for |h| = h_nm.

    Sphere: r = 1 − 3u/2 + u³/2; disc: r = (2/π)(arccos u − u √(1 − u²)); u = h / 2R,
    r = 0 for u ≥ 1 (Matheron 1975). A planar section of a Boolean model of spheres has
    the sphere's r(h) along in-plane lags.
    """
    u = np.clip(np.abs(np.asarray(h_nm, float)) / (2.0 * float(radius_nm)), 0.0, 1.0)
    if grain == "sphere":
        return 1.0 - 1.5 * u + 0.5 * u**3
    if grain == "disc":
        return (2.0 / np.pi) * (np.arccos(u) - u * np.sqrt(1.0 - u * u))
    raise InvalidInputError(f"grain must be 'sphere' or 'disc' for covariogram_ratio, got {grain!r}")


def boolean_covariance(h_nm, fraction, radius_nm, grain: str = "sphere"):
    """Analytic covariance C(h) = 1 − 2q + q^(2 − r(h)) of a Boolean model of spheres/discs."""
    q = 1.0 - float(check_fraction(fraction))
    r = covariogram_ratio(h_nm, radius_nm, grain)
    return 1.0 - 2.0 * q + q ** (2.0 - r)


def boolean_integral_range(fraction, radius_nm, grain: str = "disc", ndim: int | None = None) -> float:
    """Integral range A = ∫ (C(h) − p²) dh / (p(1 − p)) of a Boolean model (quadrature).

    ``grain="disc"`` is the 2-D model of discs (A in nm²); ``"sphere"`` the 3-D model of
    spheres (A in nm³) or, with ``ndim=2``, a planar section of it (nm²).
    In the dilute limit A → E[V²]/E[V] (the grain volume for equal grains), since
    ∫ K(h) dh = V² — Lantuéjoul (2002).

    >>> round(boolean_integral_range(1e-6, 1.0, "disc") / math.pi, 4)
    1.0
    """
    p = float(check_fraction(fraction))
    R = float(check_positive(radius_nm, "radius_nm"))
    if not 0 < p < 1:
        raise InvalidInputError("integral range needs 0 < fraction < 1")
    q = 1 - p
    if ndim is None:
        ndim = 2 if grain == "disc" else 3

    def f(h):
        c = q * q * (q ** (-covariogram_ratio(h, R, grain)) - 1.0)
        return c * (2 * np.pi * h if ndim == 2 else 4 * np.pi * h * h)

    val, _ = integrate.quad(f, 0.0, 2 * R, limit=200)
    return val / (p * q)


def _orientations(rng, n, ndim, orientation):
    if orientation == "random":
        return random_rotations(rng, n, ndim)
    if orientation == "aligned":
        return np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
    raise InvalidInputError(f"orientation must be 'random' or 'aligned', got {orientation!r}")


def boolean_particles(
    box_nm,
    grain: str = "sphere",
    size_nm=50.0,
    fraction: float | None = None,
    intensity: float | None = None,
    thickness_nm=None,
    orientation: str = "random",
    exponent: float = 2.0,
    seed=None,
    periodic: bool = True,
    label: int = 1,
    phase: str = "particles",
) -> ParticleSet:
    """A Boolean model as an analytic particle list.

    Parameters
    ----------
    box_nm : tuple
        Cell size (nm), 2 or 3 entries.
    grain : {"sphere", "cube", "disc"}
        sphere: ``size_nm`` is the radius (a disc/circle in 2-D); cube: ``size_nm`` is the
        edge (square in 2-D), ``exponent`` > 2 gives rounded pseudo-cubes (superballs);
        disc: ``size_nm`` is the diameter, ``thickness_nm`` the platelet thickness (3-D).
    size_nm : float or SizeDistribution
    fraction, intensity : float
        Give one: the target volume fraction p, or θ (grains per nm^d).
    orientation : {"random", "aligned"}
        Random (uniform) or aligned with the cell axes (disc normals along z).
    seed : int or numpy Generator
    """
    box = as_box_nm(box_nm)
    ndim = len(box)
    if grain not in GRAINS:
        raise InvalidInputError(f"grain must be one of {GRAINS}, got {grain!r}")
    dist = as_size_distribution(size_nm, "size_nm")
    if grain == "sphere":
        ev = math.pi * dist.moment(2) if ndim == 2 else 4 / 3 * math.pi * dist.moment(3)
    elif grain == "cube":
        if not (exponent >= 2 or math.isinf(exponent)):
            raise InvalidInputError(f"exponent must be >= 2 (2 = sphere, inf = cube), got {exponent}")
        from nmmm.microstructure.particles import superball_volume

        unit = float(superball_volume(np.array([0.5, 0.5, 0.5]), exponent, ndim)) if exponent != np.inf else 1.0
        ev = unit * dist.moment(ndim)
    else:
        if ndim == 3:
            if thickness_nm is None:
                raise InvalidInputError("3-D Boolean discs need thickness_nm (platelet thickness, nm)")
            t = float(check_positive(thickness_nm, "thickness_nm"))
            ev = math.pi / 4 * dist.moment(2) * t
        else:
            ev = math.pi / 4 * dist.moment(2)
    if (fraction is None) == (intensity is None):
        raise InvalidInputError("give exactly one of fraction (volume fraction in [0, 1)) or intensity (grains per nm^d)")
    if fraction is not None:
        theta = float(boolean_intensity(fraction, ev))
    else:
        theta = float(check_positive(intensity, "intensity"))
    rng = np.random.default_rng(seed)
    vol = float(np.prod(box))
    n = int(rng.poisson(theta * vol))
    if n > 50_000_000:
        raise InvalidInputError(f"{n} grains requested: grains too small for the cell; use a smaller cell")
    c = np.zeros((n, 3))
    c[:, :ndim] = rng.random((n, ndim)) * np.array(box)
    sizes = dist.sample(rng, n)
    half = np.empty((n, 3))
    if grain == "sphere":
        rot = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
        half[:] = sizes[:, None]
        kinds = np.full(n, SHAPES["superball"])
        expo = np.full(n, 2.0)
    elif grain == "cube":
        rot = _orientations(rng, n, ndim, orientation)
        half[:] = sizes[:, None] / 2
        kinds = np.full(n, SHAPES["box"] if math.isinf(exponent) else SHAPES["superball"])
        expo = np.full(n, float(exponent))
    else:
        if ndim == 2:
            rot = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
            half[:] = sizes[:, None] / 2
            kinds = np.full(n, SHAPES["superball"])
            expo = np.full(n, 2.0)
        else:
            rot = _orientations(rng, n, ndim, orientation)
            half[:, 0] = half[:, 1] = sizes / 2
            half[:, 2] = t / 2
            kinds = np.full(n, SHAPES["cylinder"])
            expo = np.full(n, 2.0)
    params = {
        "model": f"boolean_{grain}s",
        "grain": grain,
        "size_nm": dist.to_dict(),
        "intensity_per_nm": theta,
        "mean_grain_volume_nm": ev,
        "target_fraction": float(boolean_fraction(theta, ev)),
        "orientation": orientation,
        "seed": seed_param(seed),
        "box_nm": list(box),
    }
    if grain == "cube":
        params["exponent"] = float(exponent)
    if grain == "disc" and ndim == 3:
        params["thickness_nm"] = t
    return ParticleSet(c, rot, half, kinds, expo, np.full(n, int(label)), box, periodic,
                       {0: "matrix", int(label): phase}, params)


def boolean_spheres(shape, voxel_nm, radius_nm, fraction=None, intensity=None, seed=None, periodic=True,
                    phase="particles") -> Microstructure:
    """Voxelised Boolean model of spheres (3-D) or discs (2-D grid), radius ``radius_nm``.

    >>> m = boolean_spheres((64, 64, 64), 2.0, radius_nm=8.0, fraction=0.2, seed=1)
    >>> abs(m.volume_fraction() - 0.2) < 0.05
    True
    """
    box = cell_box_nm(shape, voxel_nm)
    radius = as_size_distribution(radius_nm, "radius_nm")
    ps = boolean_particles(box, "sphere", radius, fraction, intensity, seed=seed, periodic=periodic, phase=phase)
    return ps.rasterize(shape=shape)


def boolean_cubes(shape, voxel_nm, edge_nm, fraction=None, intensity=None, exponent=np.inf, orientation="random",
                  seed=None, periodic=True, phase="particles") -> Microstructure:
    """Voxelised Boolean model of cubes (squares in 2-D) of edge ``edge_nm``, random orientations."""
    box = cell_box_nm(shape, voxel_nm)
    edge = as_size_distribution(edge_nm, "edge_nm")
    ps = boolean_particles(box, "cube", edge, fraction, intensity, orientation=orientation, exponent=exponent,
                           seed=seed, periodic=periodic, phase=phase)
    return ps.rasterize(shape=shape)


def boolean_discs(shape, voxel_nm, diameter_nm, fraction=None, intensity=None, thickness_nm=None,
                  orientation="random", seed=None, periodic=True, phase="particles") -> Microstructure:
    """Voxelised Boolean model of discs: circles on a 2-D grid, platelets (cylinders) in 3-D."""
    box = cell_box_nm(shape, voxel_nm)
    diameter = as_size_distribution(diameter_nm, "diameter_nm")
    ps = boolean_particles(box, "disc", diameter, fraction, intensity, thickness_nm=thickness_nm,
                           orientation=orientation, seed=seed, periodic=periodic, phase=phase)
    return ps.rasterize(shape=shape)
