"""Display encoding: tristimulus values and spectra to sRGB.

- :func:`xyz_to_srgb` — encoded sRGB (IEC 61966-2-1) of XYZ, chromatically adapted from the
  adopted white (the illuminant's) to sRGB's D65 with CAT02.
- :func:`spectra_to_srgb` — reflectance / transmittance spectra seen under an illuminant to sRGB.

References
----------
- IEC 61966-2-1:1999 — Multimedia systems and equipment, colour measurement and management:
  default RGB colour space sRGB.
- CIE 159:2004 — A colour appearance model for colour management systems: CIECAM02 (CAT02).
- T. Mansencal et al., Colour 0.4.7, Zenodo, https://doi.org/10.5281/zenodo.3757045
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from nmmm.colour._validation import _check_triplets
from nmmm.colour.tristimulus import _split_spectral, spectra_to_xyz, white_point
from nmmm.errors import InvalidInputError


def xyz_to_srgb(xyz: ArrayLike, white_xyz: ArrayLike | None = None, clip: bool = True,
                exposure: float = 1.0) -> np.ndarray:
    """Encoded sRGB in [0, 1] of XYZ (scale: white Y = 100).

    ``white_xyz`` is the adopted white (the illuminant's, default D65); colours are adapted
    from it to sRGB's D65 with CAT02. ``exposure`` multiplies the linear values first.
    """
    import colour

    xyz = _check_triplets(xyz, "xyz") / 100.0 * exposure
    if white_xyz is None:
        xy_w = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    else:
        white = _check_triplets(white_xyz, "white_xyz")
        if white.ndim != 1 or not white[1] > 0:
            raise InvalidInputError(f"white_xyz must be one XYZ triplet with Y > 0, got {white.tolist()}")
        xy_w = colour.XYZ_to_xy(white / white[1])
    rgb = colour.XYZ_to_sRGB(xyz, illuminant=xy_w, chromatic_adaptation_transform="CAT02")
    return np.clip(rgb, 0.0, 1.0) if clip else rgb


def spectra_to_srgb(wavelength_nm: ArrayLike, values: ArrayLike | None = None, illuminant: str = "D65",
                    observer: str = "2", exposure: float = 1.0) -> np.ndarray:
    """Encoded sRGB in [0, 1] of reflectance / transmittance spectra seen under ``illuminant``
    (arrays, or a colour-science SpectralDistribution / MultiSpectralDistributions given alone)."""
    wavelength_nm, values = _split_spectral(wavelength_nm, values)
    xyz = spectra_to_xyz(wavelength_nm, values, illuminant, observer)
    return xyz_to_srgb(xyz, white_point(wavelength_nm, illuminant, observer), exposure=exposure)
