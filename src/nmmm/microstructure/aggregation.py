"""Aggregates: clusters of particles (a Neyman–Scott cluster point process).

Aggregate centres ("parents") are placed either as a Poisson process or, by default, as a
hard-core (RSA) process so that aggregates do not interpenetrate; each aggregate has its
own radius (a size distribution) and holds 1 + Poisson(μ − 1) particles whose centres
are uniform in the aggregate's ball (a Matérn cluster process; Jeulin 2021, ch. 4).
Particles are spheres or randomly oriented pseudo-cubes; within an aggregate they may
overlap (contacts), so the measured fraction is slightly below the nominal one
(Σ V_particles / V_cell), which is what ``fraction`` sets.

- :func:`aggregate_particles` — analytic :class:`ParticleSet`.
- :func:`aggregates` — voxelised :class:`Microstructure`.

References
----------
- Neyman, J., Scott, E. L. (1958). Statistical approach to problems of cosmology.
  J. R. Stat. Soc. B 20, 1–43.
- Matérn, B. (1960/1986). Spatial Variation. Springer.
- Jeulin, D. (2021). Morphological Models of Random Structures. Springer.
- Couka, E., Willot, F., Jeulin, D., et al. (2015). J. Nanosci. Nanotechnol. 15(5), 3515
  (multiscale dispersion: aggregates of hematite nanoparticles).
"""

from __future__ import annotations


import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.microstructure.base import Microstructure, as_box_nm, as_size_distribution, seed_param
from nmmm.microstructure.boolean import cell_box_nm
from nmmm.microstructure.hardcore import grain_geometry, rsa_centres, unit_grain_geometry
from nmmm.microstructure.particles import ParticleSet
from nmmm.spectra import check_fraction, check_positive

__all__ = ["aggregate_particles", "aggregates"]


def aggregate_particles(
    box_nm,
    particle_size_nm=50.0,
    aggregate_radius_nm=200.0,
    particles_per_aggregate: float = 10.0,
    fraction: float = 0.05,
    shape: str = "sphere",
    exponent: float = 8.0,
    hardcore_aggregates: bool = True,
    seed=None,
    periodic: bool = True,
    label: int = 1,
    phase: str = "particles",
) -> ParticleSet:
    """Clusters of particles as an analytic particle list.

    Parameters
    ----------
    box_nm : tuple
        Cell (nm), 2 or 3 entries.
    particle_size_nm : float or SizeDistribution
        Sphere radius, or pseudo-cube large diagonal.
    aggregate_radius_nm : float or SizeDistribution
        Radius of the ball holding each aggregate's particle centres.
    particles_per_aggregate : float
        Mean number of particles per aggregate (≥ 1).
    fraction : float
        Nominal volume fraction of particles.
    hardcore_aggregates : bool
        Aggregates placed by RSA (no interpenetration) or as a Poisson process.
    """
    box = as_box_nm(box_nm)
    ndim = len(box)
    p = float(check_fraction(fraction))
    mu = float(check_positive(particles_per_aggregate, "particles_per_aggregate"))
    if mu < 1:
        raise InvalidInputError("particles_per_aggregate must be >= 1 (mean number per aggregate)")
    pdist = as_size_distribution(particle_size_nm, "particle_size_nm")
    adist = as_size_distribution(aggregate_radius_nm, "aggregate_radius_nm")
    if shape not in ("sphere", "pseudocube"):
        raise InvalidInputError(f"shape must be 'sphere' or 'pseudocube', got {shape!r}")
    vol_unit, circ_unit = unit_grain_geometry(shape, exponent, ndim)
    rng = np.random.default_rng(seed)
    vcell = float(np.prod(box))
    n_agg = int(rng.poisson(p * vcell / (mu * vol_unit * pdist.moment(ndim))))
    if n_agg * mu > 20_000_000:
        raise InvalidInputError("too many particles for this cell; use a smaller cell")
    ra = np.sort(adist.sample(rng, n_agg))[::-1]
    if hardcore_aggregates:
        rex = ra + circ_unit * pdist.max_nm
        parents = rsa_centres(box, rex, seed=rng, periodic=periodic)
    else:
        parents = np.zeros((n_agg, 3))
        parents[:, :ndim] = rng.random((n_agg, ndim)) * np.array(box)
    counts = 1 + rng.poisson(mu - 1, n_agg)
    n = int(counts.sum())
    owner = np.repeat(np.arange(n_agg), counts)
    # uniform points in a ball (disc in 2-D): direction x radius^(1/d)
    g = rng.normal(size=(n, ndim))
    g /= np.linalg.norm(g, axis=1, keepdims=True)
    rad = ra[owner] * rng.random(n) ** (1.0 / ndim)
    c = parents[owner].copy()
    c[:, :ndim] += g * rad[:, None]
    if periodic:
        c[:, :ndim] = np.mod(c[:, :ndim], np.array(box))
    sizes = pdist.sample(rng, n)
    rot, half, kinds, expo = grain_geometry(rng, sizes, shape, exponent, ndim)
    params = {
        "model": "aggregates",
        "shape": shape,
        "particle_size_nm": pdist.to_dict(),
        "aggregate_radius_nm": adist.to_dict(),
        "particles_per_aggregate": mu,
        "n_aggregates": n_agg,
        "nominal_fraction": p,
        "hardcore_aggregates": bool(hardcore_aggregates),
        "seed": seed_param(seed),
        "box_nm": list(box),
    }
    return ParticleSet(c, rot, half, kinds, expo, np.full(n, int(label)), box, periodic,
                       {0: "matrix", int(label): phase}, params)


def aggregates(shape, voxel_nm, particle_size_nm=50.0, aggregate_radius_nm=200.0, particles_per_aggregate=10.0,
               fraction=0.05, particle_shape="sphere", exponent=8.0, hardcore_aggregates=True, seed=None,
               periodic=True, phase="particles") -> Microstructure:
    """Voxelised aggregates of particles (see :func:`aggregate_particles`)."""
    box = cell_box_nm(shape, voxel_nm)
    ps = aggregate_particles(box, particle_size_nm, aggregate_radius_nm, particles_per_aggregate, fraction,
                             particle_shape, exponent, hardcore_aggregates, seed, periodic, phase=phase)
    return ps.rasterize(shape=shape)
