"""CIELAB (CIE 1976 L*a*b*) of tristimulus values and of spectra.

- :func:`xyz_to_lab` — CIELAB of XYZ relative to the white of the same illuminant.
- :func:`spectra_to_lab` — reflectance / transmittance spectra (last axis = wavelength) to
  CIELAB under an explicit illuminant, white normalised to Y = 100.

References
----------
- CIE 015:2018 Colorimetry, 4th ed. (CIELAB, white normalisation Y = 100).
- T. Mansencal et al., Colour 0.4.7, Zenodo, https://doi.org/10.5281/zenodo.3757045
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from nmmm.colour.tristimulus import (_fused_applies, _fused_xyz_or_lab, _split_spectral, spectra_to_xyz,
                                     weighting_factors, white_point)


def xyz_to_lab(xyz: ArrayLike, white_xyz: ArrayLike) -> np.ndarray:
    """CIELAB (CIE 015:2018) of XYZ relative to the white ``white_xyz`` (same scale)."""
    import colour

    white = np.asarray(white_xyz, dtype=float)
    return colour.XYZ_to_Lab(np.asarray(xyz) / white[1], colour.XYZ_to_xy(white / white[1]))


def spectra_to_lab(wavelength_nm: ArrayLike, values: ArrayLike | None = None, illuminant: str = "D65",
                   observer: str = "2") -> np.ndarray:
    """CIELAB (last axis L*, a*, b*) of one spectrum or a stack (last axis = wavelength),
    white normalised to Y = 100 under the same illuminant; or of a colour-science
    SpectralDistribution / MultiSpectralDistributions given alone (``spectra_to_lab(sd)``).

    >>> import numpy as np
    >>> w = np.arange(380, 781, 5.0)
    >>> np.round(spectra_to_lab(w, np.ones_like(w)), 6) + 0.0
    array([ 100.,    0.,    0.])
    """
    wavelength_nm, values = _split_spectral(wavelength_nm, values)
    if _fused_applies(values, np.size(wavelength_nm)):
        # a large stack: checks, sums and CIELAB in one parallel read (the values as xyz_to_lab's)
        lab = _fused_xyz_or_lab(values, weighting_factors(wavelength_nm, illuminant, observer), lab=True)
        if lab is not None:
            return lab
    xyz = spectra_to_xyz(wavelength_nm, values, illuminant, observer)
    return xyz_to_lab(xyz, white_point(wavelength_nm, illuminant, observer))
