"""Reference cells with known effective permittivity, for tests, benchmarks and examples.

Random models of real paint layers live in :mod:`nmmm.microstructure`; these are the simple
periodic cells whose answers are known in closed form:

- :func:`laminate` — layers normal to one axis (arithmetic / harmonic means, exact).
- :func:`checkerboard` — the 2-D two-phase checkerboard (ε* = sqrt(ε1 ε2), Dykhne 1971).
- :func:`coated_sphere` — one coated sphere (disc in 2-D) embedded in a third phase: when that
  phase has Hashin's value, the cell is neutral and ε* equals it (Hashin 1962).
- :func:`sphere` — one centred sphere (disc): the simple cubic (square) array of
  Rayleigh (1892).
- :func:`boolean_spheres` — a periodic Boolean model of spheres (random overlapping spheres),
  seeded, for convergence studies and benchmarks.

Each returns a uint8 label array; radii and sizes are in voxels (``*_vox``) or as fractions of
the cell.

References
----------
- Dykhne, A. M. (1971). Conductivity of a two-dimensional two-phase system. Sov. Phys. JETP
  32, 63-65.
- Hashin, Z., Shtrikman, S. (1962). A variational approach to the theory of the effective
  magnetic permeability of multiphase materials. J. Appl. Phys. 33, 3125-3131.
- Rayleigh, Lord (1892). On the influence of obstacles arranged in rectangular order upon the
  properties of a medium. Phil. Mag. 34, 481-502.
"""

from __future__ import annotations

import numpy as np

from nmmm.errors import InvalidInputError


def laminate(n: int, fraction: float = 0.5, axis: int = 0, ndim: int = 2, layers: int = 1) -> np.ndarray:
    """Layers normal to ``axis``: label 1 fills ``round(fraction * n)`` voxels of each period.

    ``layers`` periods of ``n`` voxels; the cell is ``n·layers`` voxels along ``axis`` and
    ``n`` along the others (at least 2).
    """
    k = int(round(fraction * n))
    profile = np.tile(np.r_[np.ones(k, np.uint8), np.zeros(n - k, np.uint8)], layers)
    shape = [max(2, n)] * ndim
    shape[axis] = profile.size
    idx = [None] * ndim
    idx[axis] = slice(None)
    return np.broadcast_to(profile[tuple(idx)], shape).copy()


def checkerboard(n: int, ndim: int = 2) -> np.ndarray:
    """The two-phase checkerboard with 2×2 squares of ``n/2`` voxels (``n`` even)."""
    if n % 2:
        raise InvalidInputError(f"checkerboard needs an even n, got {n}")
    h = n // 2
    i = (np.arange(n) >= h).astype(np.uint8)
    grids = np.meshgrid(*([i] * ndim), indexing="ij")
    return (sum(grids) % 2).astype(np.uint8)


def _radius_grid(n: int, ndim: int) -> np.ndarray:
    x = (np.arange(n) + 0.5) / n - 0.5
    grids = np.meshgrid(*([x] * ndim), indexing="ij")
    return np.sqrt(sum(g * g for g in grids))


def sphere(n: int, fraction: float, ndim: int = 3) -> np.ndarray:
    """One centred sphere (disc) of label 1 of nominal volume ``fraction`` in a cube of ``n`` voxels.

    Simple cubic (square) array of Rayleigh (1892). The voxelised fraction differs slightly
    from the nominal one; use the result's ``fractions``.
    """
    unit = np.pi if ndim == 2 else 4.0 * np.pi / 3.0
    r = (fraction / unit) ** (1.0 / ndim)
    if r > 0.5:
        raise InvalidInputError(f"a centred sphere cannot exceed radius 0.5 (fraction {fraction} too large)")
    return (_radius_grid(n, ndim) < r).astype(np.uint8)


def coated_sphere(n: int, outer_fraction: float, core_fraction: float, ndim: int = 3) -> np.ndarray:
    """Core (label 0) and shell (label 1) of a coated sphere in a matrix (label 2).

    ``outer_fraction`` is the volume fraction of the coated sphere in the cell,
    ``core_fraction`` the fraction of the core in the coated sphere.
    """
    unit = np.pi if ndim == 2 else 4.0 * np.pi / 3.0
    r2 = (outer_fraction / unit) ** (1.0 / ndim)
    r1 = r2 * core_fraction ** (1.0 / ndim)
    if r2 > 0.5:
        raise InvalidInputError(f"outer_fraction {outer_fraction} too large for one sphere per cell")
    rr = _radius_grid(n, ndim)
    lab = np.full(rr.shape, 2, np.uint8)
    lab[rr < r2] = 1
    lab[rr < r1] = 0
    return lab


def boolean_spheres(n: int, fraction: float, radius_vox: float, ndim: int = 3, seed: int = 0) -> np.ndarray:
    """Periodic Boolean model of spheres (label 1) of radius ``radius_vox`` voxels.

    The Poisson intensity is set from p = 1 − exp(−θ V) so that the *expected* fraction is
    ``fraction``; centres are uniform in the periodic cell.
    """
    rng = np.random.default_rng(seed)
    unit = np.pi if ndim == 2 else 4.0 * np.pi / 3.0
    v = unit * radius_vox**ndim
    theta = -np.log(1.0 - fraction) / v
    count = rng.poisson(theta * n**ndim)
    centres = rng.uniform(0, n, size=(count, ndim))
    lab = np.zeros((n,) * ndim, dtype=np.uint8)
    r = int(np.ceil(radius_vox))
    offs = np.arange(-r, r + 1)
    for c in centres:
        base = np.floor(c).astype(int)
        idx = [(base[a] + offs) % n for a in range(ndim)]
        d2 = sum(
            ((base[a] + offs + 0.5 - c[a]) ** 2).reshape([-1 if b == a else 1 for b in range(ndim)])
            for a in range(ndim)
        )
        mask = d2 < radius_vox**2
        sub = lab[np.ix_(*idx)]
        sub[mask] = 1
        lab[np.ix_(*idx)] = sub
    return lab


__all__ = ["laminate", "checkerboard", "sphere", "coated_sphere", "boolean_spheres"]
