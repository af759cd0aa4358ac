"""Input checks shared by the effective-medium formulas (private).

Every formula takes complex permittivities (Im ε >= 0) and volume fractions in [0, 1]
that broadcast against each other; these helpers raise :class:`nmmm.InvalidInputError`
with a message that says what was wrong and what is expected.
"""

from __future__ import annotations

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.spectra import check_finite, check_fraction

#: Im ε may be this much below zero (relative to |ε|) before it is called gain and refused:
#: round-off of tabulated data converted from n, k.
_GAIN_TOLERANCE = 1e-9


def as_eps(eps, name: str = "eps") -> np.ndarray:
    """A finite complex permittivity array with Im ε >= 0 (passive media)."""
    e = check_finite(eps, name).astype(complex, copy=False)
    if np.any(e.imag < -_GAIN_TOLERANCE * np.maximum(np.abs(e), 1.0)):
        raise InvalidInputError(
            f"{name} has Im eps < 0 (min {e.imag.min():.3g}); nmmm uses eps = eps1 + i eps2 with "
            "eps2 >= 0 for absorbing media (exp(-i omega t)); pass eps = (n + ik)**2 with k >= 0"
        )
    return e


def as_host_eps(eps, name: str = "eps_host") -> np.ndarray:
    """:func:`as_eps` for a host (matrix): ε = 0 is refused, since every mixing rule divides by
    it (Maxwell Garnett returns 0, Bruggeman an arbitrary root, instead of an error)."""
    e = as_eps(eps, name)
    if np.any(np.abs(e) < 1e-12):
        raise InvalidInputError(f"{name} = 0 (|eps| < 1e-12): a host medium has eps != 0 (vacuum and air have "
                                "eps = 1); at a metal's epsilon-near-zero wavelength use a full-wave model, not an EMA")
    return e


def broadcast_inputs(**arrays) -> None:
    """Refuse inputs whose shapes do not broadcast, naming them (instead of numpy's ValueError)."""
    try:
        np.broadcast_shapes(*(np.shape(a) for a in arrays.values()))
    except ValueError:
        shapes = ", ".join(f"{k} {np.shape(v)}" for k, v in arrays.items())
        raise InvalidInputError(f"shapes do not broadcast: {shapes}; give arrays of one shape (or scalars), "
                                "e.g. one value per wavelength") from None


def as_fraction(fraction, name: str = "fraction") -> np.ndarray:
    """A volume fraction array in [0, 1] (not percent)."""
    return check_fraction(fraction, name)


def as_depolarization(depolarization, name: str = "depolarization") -> np.ndarray:
    """Depolarization factors (..., 3): each in [0, 1], summing to 1 along the last axis."""
    L = check_finite(depolarization, name)
    if np.iscomplexobj(L):
        raise InvalidInputError(f"{name} must be real")
    L = L.astype(float, copy=False)
    if L.ndim == 0 or L.shape[-1] != 3:
        raise InvalidInputError(
            f"{name} must have a last axis of length 3 (L1, L2, L3 of the ellipsoid's axes), "
            f"got shape {L.shape}"
        )
    if np.any((L < 0) | (L > 1)):
        raise InvalidInputError(f"{name} must lie in [0, 1], got values in [{L.min():g}, {L.max():g}]")
    total = L.sum(axis=-1)
    if np.any(np.abs(total - 1) > 1e-6):
        bad = total.ravel()[np.argmax(np.abs(total.ravel() - 1))]
        raise InvalidInputError(
            f"{name} must sum to 1 over the three axes (L1 + L2 + L3 = 1 for any ellipsoid), "
            f"got a sum of {bad:.6g}; a sphere has (1/3, 1/3, 1/3)"
        )
    return L


def check_orientation(orientation: str) -> str:
    """'aligned' (tensor result, last axis 3) or 'random' (isotropic scalar result)."""
    if orientation not in ("aligned", "random"):
        raise InvalidInputError(f"orientation must be 'aligned' or 'random', got {orientation!r}")
    return orientation


def passive(eps) -> np.ndarray:
    """Clear the round-off Im ε < 0 (~1e-16) that mixing formulas can leave on lossless
    inputs: with passive phases (checked on input) the exact result is passive (Milton 1981),
    so a negative imaginary part can only be round-off."""
    e = np.asarray(eps, dtype=complex)
    neg = e.imag < 0
    if np.any(neg):
        e = np.where(neg, e.real + 0j, e)
    return e
