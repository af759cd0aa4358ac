"""Colour differences between CIELAB coordinates.

- :func:`delta_e2000` — the CIEDE2000 colour difference, broadcasting.

References
----------
- G. Sharma, W. Wu, E. N. Dalal, Color Res. Appl. 30, 21 (2005) — CIEDE2000,
  https://doi.org/10.1002/col.20070
- T. Mansencal et al., Colour 0.4.7, Zenodo, https://doi.org/10.5281/zenodo.3757045
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from nmmm.colour._validation import _check_triplets
from nmmm.errors import InvalidInputError


def delta_e2000(lab1: ArrayLike, lab2: ArrayLike) -> np.ndarray:
    """CIEDE2000 colour difference (Sharma, Wu & Dalal 2005), broadcasting."""
    import colour

    lab1, lab2 = _check_triplets(lab1, "lab1"), _check_triplets(lab2, "lab2")
    for lab, name in ((lab1, "lab1"), (lab2, "lab2")):
        if np.any(lab[..., 0] < -1e-6):
            raise InvalidInputError(f"{name} has L* = {float(lab[..., 0].min()):g} < 0; CIELAB lightness is >= 0 "
                                    "(L* = 0 is black), check the coordinates or their order (L*, a*, b*)")
    return colour.delta_E(lab1, lab2, method="CIE 2000")
