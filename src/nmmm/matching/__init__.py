"""nmmm.matching — from a measured colour to a recipe: measured files, metamerism, matching.

Floor: above :mod:`nmmm.recipes` (a match varies a recipe's keys and runs its coat stack), below
:mod:`nmmm.demo` and the CLI. The measured-file readers live here rather than on the ground
floor because only matching (and later calibration) consumes them.

- :mod:`~nmmm.matching.measured_files` — CGATS.17, CxF3 and CSV spectra in and out
  (:class:`MeasuredSpectra`, :func:`read_measured`, :func:`write_cgats`, :func:`write_cxf`).
- :mod:`~nmmm.matching.metamerism` — the CIEDE2000 residual vector and the CIE special
  metamerism index for a change of illuminant.
- :mod:`~nmmm.matching.recipe_match` — :func:`match_recipe` over a :class:`RecipeModel`.
- :mod:`~nmmm.matching.calibration` — :func:`calibrate_colourant`: a smooth correction of a compound's
  k(λ) (Kramers–Kronig-consistent n, :mod:`~nmmm.matching.k_correction`) and its size fitted on a measured ladder.
- :mod:`~nmmm.matching.empirical_km` — :func:`calibrate_empirical`: the industry's two-constant
  Kubelka–Munk K, S per unit concentration (Duncan mixing, Saunderson) on the same ladder.
- :mod:`~nmmm.matching.colourant_selection` — :func:`select_colourants`: the best subsets of at most
  N colourants of a palette (KM ranking of every subset, adding–doubling finish of the best).
- :mod:`~nmmm.matching.batch_correction` — :func:`correct_batch`: additions that bring a made
  batch onto its target (offset held, the model's sensitivity at the recipe point).
- :mod:`~nmmm.matching.outputs` — the ``nmmm match`` result folder.
"""

from nmmm.matching.batch_correction import BatchCorrection, correct_batch
from nmmm.matching.calibration import CalibrationResult, LadderSample, calibrate_colourant, write_calibrated_material
from nmmm.matching.empirical_km import EmpiricalCalibration, calibrate_empirical
from nmmm.matching.colourant_selection import SubsetMatch, select_colourants
from nmmm.matching.measured_files import (
    MeasuredSpectra,
    cxf_geometries,
    read_cgats,
    read_cxf,
    read_measured,
    read_spectra_csv,
    write_cgats,
    write_cxf,
)
from nmmm.matching.metamerism import delta_e2000_residuals, delta_lch, metamerism_index
from nmmm.matching.recipe_match import MatchResult, RecipeModel, match_recipe, parse_bound

__all__ = [
    "BatchCorrection",
    "CalibrationResult",
    "EmpiricalCalibration",
    "LadderSample",
    "MatchResult",
    "MeasuredSpectra",
    "RecipeModel",
    "SubsetMatch",
    "calibrate_colourant",
    "calibrate_empirical",
    "correct_batch",
    "cxf_geometries",
    "delta_e2000_residuals",
    "delta_lch",
    "match_recipe",
    "metamerism_index",
    "parse_bound",
    "read_cgats",
    "read_cxf",
    "read_measured",
    "read_spectra_csv",
    "select_colourants",
    "write_calibrated_material",
    "write_cgats",
    "write_cxf",
]
