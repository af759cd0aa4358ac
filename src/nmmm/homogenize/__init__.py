"""FFT homogenization: the effective permittivity of a periodic microstructure.

Public API
----------
- :func:`fft_permittivity` — labels + {label: ε} -> :class:`FFTHomogenization`
  (``.tensor``, ``.iterations``, residual histories, local fields on request).
- :func:`homogenize` — Microstructure + {phase: Material} -> :class:`HomogenizedMaterial`
  (a :class:`nmmm.materials.material.DerivedMaterial`, possibly anisotropic).
- :func:`extrapolate_resolution`, :func:`richardson` — first-order extrapolation to zero voxel size.
- Green operators: :data:`GREEN_OPERATORS`, :func:`green_operator`.
- Solvers: :data:`SOLVERS` (COCG default; BiCGStab, GMRES fallbacks; Eyre-Milton reference).
- Validity: :func:`check_periodicity`, :func:`periodize_mirror`, :func:`check_quasistatic`,
  :func:`size_parameter`, :class:`QuasiStaticWarning`.
"""

from nmmm.homogenize.fft import FFTHomogenization, fft_permittivity
from nmmm.homogenize.material import HomogenizedMaterial, apparent_property, homogenize
from nmmm.homogenize.resolution import ResolutionStudy, extrapolate_resolution, richardson
from nmmm.homogenize.green import GREEN_OPERATORS, GreenOperator, green_operator
from nmmm.homogenize.solvers import SOLVERS
from nmmm.homogenize.validity import (
    PeriodicityWarning,
    QuasiStaticWarning,
    check_periodicity,
    check_quasistatic,
    feature_size_nm,
    periodize_mirror,
    size_parameter,
)

__all__ = [
    "fft_permittivity",
    "FFTHomogenization",
    "homogenize",
    "HomogenizedMaterial",
    "apparent_property",
    "extrapolate_resolution",
    "richardson",
    "ResolutionStudy",
    "GREEN_OPERATORS",
    "GreenOperator",
    "green_operator",
    "SOLVERS",
    "check_periodicity",
    "check_quasistatic",
    "feature_size_nm",
    "periodize_mirror",
    "size_parameter",
    "QuasiStaticWarning",
    "PeriodicityWarning",
]
