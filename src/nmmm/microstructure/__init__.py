"""nmmm.microstructure — random microstructures, SEM image analysis, RVE.

Models (seeded, periodic, physical units in nm, 2-D and 3-D):

- Boolean models: :func:`boolean_spheres`, :func:`boolean_cubes`, :func:`boolean_discs`,
  :func:`boolean_particles` (p = 1 − exp(−θ E[V])).
- Hard-core (RSA) models with exclusion zones: :func:`hardcore_spheres`,
  :func:`hardcore_pseudocubes`, :func:`hardcore_particles`; :data:`RSA_JAMMING`.
- Aggregates (cluster point process): :func:`aggregates`.
- Metal flakes (mixed Boolean/deposit): :func:`flake_deposit` → :class:`FlakeDeposit`.

Containers: :class:`Microstructure` (voxel labels + ``voxel_nm`` + ``periodic``),
:class:`ParticleSet` (analytic list, ``.rasterize(voxel_nm | shape)``),
:class:`SizeDistribution`.

Image analysis: :func:`read_image`, :func:`binarize`, :func:`area_fraction`,
:func:`covariance`, :func:`covariance_profile`, :func:`integral_range`,
:func:`granulometry`, :func:`particle_statistics`, :func:`nearest_neighbour_distances`,
:func:`exclusion_radius`, :func:`estimate_boolean`, :func:`estimate_hardcore`,
:func:`estimate_aggregates` (cluster model from particle centres' g(r)),
:func:`estimate_flakes` (flake model from cross-sections), :func:`analyze_image`.

RVE (Kanit et al. 2003): :func:`fit_rve`, :class:`RVEFit`, :func:`rve_study`.

Files: :func:`save_microstructure`, :func:`load_microstructure` (.tif / .npz).
"""

from nmmm.microstructure.aggregation import aggregate_particles, aggregates
from nmmm.microstructure.analysis import (
    ImageAnalysis,
    ParticleStatistics,
    analyze_image,
    area_fraction,
    binarize,
    covariance,
    covariance_profile,
    estimate_boolean,
    estimate_hardcore,
    exclusion_radius,
    granulometry,
    integral_range,
    label_particles,
    nearest_neighbour_distances,
    particle_statistics,
    read_image,
)
from nmmm.microstructure.base import Microstructure, SizeDistribution, as_size_distribution, random_rotations
from nmmm.microstructure.boolean import (
    boolean_covariance,
    boolean_cubes,
    boolean_discs,
    boolean_fraction,
    boolean_integral_range,
    boolean_intensity,
    boolean_particles,
    boolean_spheres,
    covariogram_ratio,
)
from nmmm.microstructure.estimation import (
    cluster_pair_correlation,
    disc_diameters_from_chords,
    estimate_aggregates,
    estimate_flakes,
    flake_sections,
    pair_correlation,
    particle_centres,
)
from nmmm.microstructure.flakes import SEED_METALLIC_CELL_NM, FlakeDeposit, flake_deposit
from nmmm.microstructure.hardcore import (
    RSA_JAMMING,
    hardcore_particles,
    hardcore_pseudocubes,
    hardcore_spheres,
    max_hardcore_fraction,
    rsa_centres,
)
from nmmm.microstructure.io import load_microstructure, save_microstructure
from nmmm.microstructure.particles import ParticleSet, rasterize_particles
from nmmm.microstructure.rve import RVEFit, fit_rve, rve_study

__all__ = [
    "Microstructure",
    "ParticleSet",
    "SizeDistribution",
    "FlakeDeposit",
    "ImageAnalysis",
    "ParticleStatistics",
    "RVEFit",
    "RSA_JAMMING",
    "SEED_METALLIC_CELL_NM",
    "aggregate_particles",
    "aggregates",
    "analyze_image",
    "area_fraction",
    "as_size_distribution",
    "binarize",
    "boolean_covariance",
    "boolean_cubes",
    "boolean_discs",
    "boolean_fraction",
    "boolean_integral_range",
    "boolean_intensity",
    "boolean_particles",
    "boolean_spheres",
    "covariance",
    "covariance_profile",
    "covariogram_ratio",
    "cluster_pair_correlation",
    "disc_diameters_from_chords",
    "estimate_aggregates",
    "estimate_boolean",
    "estimate_flakes",
    "flake_sections",
    "pair_correlation",
    "particle_centres",
    "estimate_hardcore",
    "exclusion_radius",
    "fit_rve",
    "flake_deposit",
    "granulometry",
    "hardcore_particles",
    "hardcore_pseudocubes",
    "hardcore_spheres",
    "integral_range",
    "label_particles",
    "load_microstructure",
    "max_hardcore_fraction",
    "nearest_neighbour_distances",
    "particle_statistics",
    "random_rotations",
    "rasterize_particles",
    "read_image",
    "rsa_centres",
    "rve_study",
    "save_microstructure",
]
