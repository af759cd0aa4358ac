"""Deprecated: colorimetry moved to the ground floor, :mod:`nmmm.colour`.

``nmmm.appearance.colorimetry`` re-exports :mod:`nmmm.colour`'s names for one release and warns on
import; write ``from nmmm.colour import spectra_to_lab`` (or ``from nmmm.appearance import ...``,
which stays).
"""

import warnings

from nmmm.colour import (  # noqa: F401  (re-exported)
    DELTA_E_METHODS,
    MIN_CMF_COVERAGE,
    OBSERVERS,
    as_spectral_distributions,
    delta_e,
    delta_e2000,
    delta_lch,
    spectra_to_lab,
    spectra_to_srgb,
    spectra_to_xyz,
    weighting_factors,
    white_point,
    within_tolerance,
    xyz_to_lab,
    xyz_to_srgb,
)

warnings.warn(
    "nmmm.appearance.colorimetry is deprecated and will be removed in the next release; "
    "import from nmmm.colour instead (e.g. 'from nmmm.colour import spectra_to_lab')",
    DeprecationWarning, stacklevel=2)

__all__ = [
    "DELTA_E_METHODS",
    "MIN_CMF_COVERAGE",
    "OBSERVERS",
    "as_spectral_distributions",
    "delta_e",
    "delta_e2000",
    "delta_lch",
    "spectra_to_lab",
    "spectra_to_srgb",
    "spectra_to_xyz",
    "weighting_factors",
    "white_point",
    "within_tolerance",
    "xyz_to_lab",
    "xyz_to_srgb",
]
