"""Facet normals of flakes with rough faces: the flake tilt distribution composed with a GGX
microfacet distribution of each face (used by
:meth:`nmmm.appearance.flakes.TiltDistribution.roughened`).

Both are isotropic densities per steradian; composing a flake tilt and a facet offset as tilt
vectors (θ(cos φ, sin φ), small-angle) makes the density per unit tilt-vector area the 2-D
convolution of the two, done here by FFT on a 512² grid over ±90° (0.35° spacing) and
averaged on rings.

References
----------
- B. Walter, S. R. Marschner, H. Li, K. E. Torrance, EGSR 2007 — GGX D(h), normalised so that
  ∫ D(h) cos θ_h dω_h = 1.
"""

from __future__ import annotations

import numpy as np


def facet_normal_density(tilt_deg, density, a: float):
    """Density per sr of the facet normals (on 0–90° in 0.25° steps, unnormalised) of flakes
    whose normals have ``density`` (per sr, at ``tilt_deg``) and whose faces are GGX of
    roughness ``a``: ``(grid_deg, density)``."""
    tilt_deg = np.asarray(tilt_deg, float)
    density = np.asarray(density, float)
    # both densities per unit tilt-vector area on a 2-D grid, convolved by FFT (zero-padded)
    n_grid = 512
    half = np.pi / 2
    x = (np.arange(n_grid) - n_grid // 2) * (2 * half / n_grid)
    X, Y = np.meshgrid(x, x, indexing="ij")
    R = np.hypot(X, Y)
    tt = np.radians(tilt_deg)
    jac = np.where(R > 0, np.sin(np.minimum(R, np.pi)) / np.maximum(R, 1e-300), 1.0)  # per sr -> per tilt area
    # the centre node stands for its cell: a density with a 1/θ peak per tilt area (half-normal
    # tilts: finite per unit θ at 0) has the cell mean p(0.2805 Δ) (∫∫ dA / R over a square of
    # side Δ = 4 ln(1 + √2) Δ); sampled at θ = 0 it put +43 % at 0.5° (S, session 4)
    dx = 2 * half / n_grid
    p_flat = np.interp(np.where(R > 0, R, 0.2805 * dx), tt, density, right=0.0) * jac
    c = np.cos(np.minimum(R, half))
    d = c * c * (a * a - 1.0) + 1.0
    q_flat = np.where(R < half, a * a / (np.pi * d * d) * c, 0.0) * jac  # GGX D(h) cos θ_h, per sr
    shape = (2 * n_grid, 2 * n_grid)
    conv = np.fft.irfft2(np.fft.rfft2(p_flat, shape) * np.fft.rfft2(q_flat, shape), shape)
    conv = conv[n_grid // 2:n_grid // 2 + n_grid, n_grid // 2:n_grid // 2 + n_grid]
    # azimuthal average on rings of the output grid
    grid = np.linspace(0.0, 90.0, 361)
    edges = np.radians(np.concatenate([[0.0], 0.5 * (grid[1:] + grid[:-1]), [90.0 + 0.125]]))
    k = np.clip(np.searchsorted(edges, R.ravel(), side="right") - 1, 0, grid.size)
    inside = R.ravel() < edges[-1]
    sums = np.bincount(k[inside], weights=np.maximum(conv.ravel()[inside], 0.0), minlength=grid.size)
    cnt = np.bincount(k[inside], minlength=grid.size)
    ring = np.where(cnt[:grid.size] > 0, sums[:grid.size] / np.maximum(cnt[:grid.size], 1), 0.0)
    t = np.radians(grid)
    dens = ring * np.where(t > 0, t / np.maximum(np.sin(t), 1e-300), 1.0)
    return grid, dens
