"""Input checks shared by the colour modules."""

from __future__ import annotations

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.spectra import check_finite


def _check_triplets(x, name: str) -> np.ndarray:
    """Finite colour coordinates with a last axis of 3 (L*, a*, b* or X, Y, Z)."""
    a = check_finite(x, name).astype(float, copy=False)
    if a.ndim == 0 or a.shape[-1] != 3:
        raise InvalidInputError(f"{name} must have a last axis of 3 colour coordinates, got shape {a.shape}")
    return a
