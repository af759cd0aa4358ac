"""nmmm.colour — ground floor: colorimetry used by every scale above.

- :mod:`~nmmm.colour.illuminants` — illuminants (by name, data or values on the grid) and the
  standard observers with their aliases (``"2"``, ``"10"``); industry illuminant names (``F11``,
  ``TL84``, ``CWF``) through :func:`~nmmm.colour.illuminants.canonical_illuminant`.
- :mod:`~nmmm.colour.tristimulus` — CIE weighting factors (ASTM E308 through colour-science),
  spectra → XYZ, white point; :func:`as_spectral_distributions` (spectra as colour-science objects).
  Every spectra entry point also takes a ``colour.SpectralDistribution`` /
  ``MultiSpectralDistributions`` alone (``spectra_to_lab(sd)``).
- :mod:`~nmmm.colour.cielab` — XYZ and spectra → CIELAB.
- :mod:`~nmmm.colour.difference` — colour differences (ΔE*ab, ΔE94, CMC(l:c), ΔE00 with kL:kC:kH; registry
  :data:`DELTA_E_METHODS`, :func:`delta_e`), ΔL*/ΔC*/ΔH*, pass/fail against a tolerance.
- :mod:`~nmmm.colour.display` — XYZ and spectra → sRGB (CAT02 from the illuminant's white to D65).

It depends only on :mod:`nmmm.errors`, :mod:`nmmm.spectra` and colour-science, so that
``nmmm.layers``, ``nmmm.ema`` and the rest import colour downward.
"""

from nmmm.colour.cielab import spectra_to_lab, xyz_to_lab
from nmmm.colour.difference import DELTA_E_METHODS, delta_e, delta_e2000, delta_lch, within_tolerance
from nmmm.colour.display import spectra_to_srgb, xyz_to_srgb
from nmmm.colour.illuminants import OBSERVERS
from nmmm.colour.tristimulus import (
    MIN_CMF_COVERAGE,
    as_spectral_distributions,
    spectra_to_xyz,
    weighting_factors,
    white_point,
)

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
