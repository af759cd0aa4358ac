"""nmmm.appearance — macro scale: colorimetry, BRDFs of paints, multi-angle colour, rendering.

- :mod:`~nmmm.appearance.colorimetry` — spectra → XYZ → CIELAB, ΔE2000, sRGB.
"""

from nmmm.appearance.colorimetry import (
    delta_e2000,
    spectra_to_lab,
    spectra_to_srgb,
    spectra_to_xyz,
    weighting_factors,
    white_point,
    xyz_to_lab,
    xyz_to_srgb,
)

__all__ = [
    "delta_e2000",
    "spectra_to_lab",
    "spectra_to_srgb",
    "spectra_to_xyz",
    "weighting_factors",
    "white_point",
    "xyz_to_lab",
    "xyz_to_srgb",
]
