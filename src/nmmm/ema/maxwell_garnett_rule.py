"""Maxwell Garnett effective media: inclusions dilute in a host, from spheres to ellipsoids.

- :func:`maxwell_garnett` — eq. (2) of the seed paper (spheres), exactly as written there.
- :func:`maxwell_garnett_ellipsoid` — ellipsoidal inclusions with depolarization factors,
  aligned (diagonal tensor, last axis 3) or randomly oriented (scalar).
- :func:`maxwell_garnett_polarizability` — the Clausius–Mossotti form for any inclusion
  whose polarizability per unit volume is known (cubes, size-corrected spheres).
- :func:`maxwell_garnett_shape` — the same with a :class:`~nmmm.ema.shapes.Shape`.
- :func:`maxwell_garnett_multi` — several inclusion populations in one host.

All arguments broadcast (e.g. ε of shape (401, 1) against fractions of shape (1000,)).
Complex ε with Im ε >= 0; fractions in [0, 1].

Notes
-----
Maxwell Garnett treats the inclusions as isolated dipoles in the host, the host's local
field being the Lorentz field; it is exact for the Hashin coated-sphere assemblage and
equals the Hashin–Shtrikman bound whose reference is the host
(:func:`nmmm.ema.bounds.hashin_shtrikman_bounds`). It is asymmetric (host and inclusions
play different roles) and meant for low fractions (p ≲ 0.3) of small inclusions (size ≪ λ;
see :mod:`nmmm.ema.size` otherwise).

References
----------
- J. C. Maxwell Garnett, "Colours in metal glasses and in metallic films",
  Phil. Trans. R. Soc. Lond. A 203, 385 (1904), doi:10.1098/rsta.1904.0024.
- A. Sihvola, Electromagnetic Mixing Formulas and Applications (IEE 1999), §4.4–4.5
  (aligned and randomly oriented ellipsoids; multiphase mixtures).
- R. W. Cohen, G. D. Cody, M. D. Coutts, B. Abeles, "Optical properties of granular
  silver and gold films", Phys. Rev. B 8, 3689 (1973) (ellipsoidal MG).
- C. F. Bohren, D. R. Huffman, Absorption and Scattering of Light by Small Particles
  (Wiley 1983), §8.5.
"""

from __future__ import annotations

from collections.abc import Sequence

import numba
import numpy as np
from numpy.typing import ArrayLike

from nmmm.ema._validation import (as_depolarization, as_eps, as_fraction, as_host_eps, broadcast_inputs,
                                  check_orientation, passive)
from nmmm.errors import InvalidInputError


def maxwell_garnett(eps_inclusion: ArrayLike, eps_host: ArrayLike, fraction: ArrayLike) -> np.ndarray:
    """Maxwell Garnett effective permittivity of spheres in a host, eq. (2) of the seed paper:

    ``eps_e = eps_m ((1 + 2p) eps_i + 2(1 - p) eps_m) / ((1 - p) eps_i + (2 + p) eps_m)``

    Parameters
    ----------
    eps_inclusion, eps_host : array_like, complex
        Permittivities ε_i of the inclusions and ε_m of the host (Im ε >= 0).
    fraction : array_like
        Volume fraction p of the inclusions, in [0, 1].

    Returns
    -------
    numpy.ndarray, complex — the broadcast shape of the inputs.

    References
    ----------
    Maxwell Garnett (1904); Born & Wolf, Principles of Optics, §2.3.

    Examples
    --------
    Air voids (p = 0.2) in glass of ε = 2.25 — the Hashin–Shtrikman upper bound
    2.25·(1 + 2·0.2·β)/(1 − 0.2·β) with β = (1 − 2.25)/(1 + 4.5):

    >>> round(float(maxwell_garnett(1.0, 2.25, 0.2).real), 6)
    1.956522
    """
    ei = as_eps(eps_inclusion, "eps_inclusion")
    em = as_host_eps(eps_host, "eps_host")
    p = as_fraction(fraction)
    broadcast_inputs(eps_inclusion=ei, eps_host=em, fraction=p)
    return _maxwell_garnett_ufunc(ei, em, p)


@numba.vectorize(["complex128(complex128, complex128, float64)"], cache=True)
def _maxwell_garnett_ufunc(ei, em, p):
    """Eq. (2) and :func:`passive` in one broadcasting pass (the NumPy expression makes ~10
    temporaries of the full broadcast size, issue 22)."""
    e = em * ((1 + 2 * p) * ei + 2 * (1 - p) * em) / ((1 - p) * ei + (2 + p) * em)
    if e.imag < 0:
        e = e.real + 0j
    return e


def maxwell_garnett_polarizability(eps_host: ArrayLike, fraction: ArrayLike, polarizability: ArrayLike) -> np.ndarray:
    """Maxwell Garnett (Clausius–Mossotti) medium from a polarizability per unit volume:

    ``eps_e = eps_m (1 + 2 p alpha / 3) / (1 − p alpha / 3)``

    where ``alpha`` is the inclusion's dipole polarizability divided by its volume and by
    ε_m (dimensionless; a sphere has ``alpha = 3 (eps_i − eps_m)/(eps_i + 2 eps_m)``, which
    gives back eq. (2)). Used for cubes and for size-corrected spheres (:mod:`nmmm.ema.size`).
    """
    em = as_eps(eps_host, "eps_host")
    p = as_fraction(fraction)
    a = np.asarray(polarizability, dtype=complex)
    if not np.all(np.isfinite(a)):
        raise InvalidInputError("polarizability contains NaN or infinite values")
    return passive(em * (1 + 2 * p * a / 3) / (1 - p * a / 3))


def _combine(em, terms, orientation):
    """Σ over populations of p_k alpha_kj and p_k L_kj alpha_kj -> effective ε.

    terms: list of (p, alpha (...,3), L_local (...,3)). Aligned: per axis; random: mean
    over the three axes (Sihvola 1999, eq. 4.37 generalized to several populations).
    """
    num = 0
    den = 0
    for p, alpha, L in terms:
        num = num + p[..., None] * alpha
        den = den + p[..., None] * L * alpha
    if orientation == "aligned":
        return passive(em[..., None] * (1 + num / (1 - den)))  # ε_m + ε_m Σ p α / (1 − Σ p L α)
    return passive(em * (1 + num.mean(-1) / (1 - den.mean(-1))))


def maxwell_garnett_ellipsoid(eps_inclusion: ArrayLike, eps_host: ArrayLike, fraction: ArrayLike,
                              depolarization: ArrayLike, orientation: str = "random") -> np.ndarray:
    """Maxwell Garnett medium of ellipsoidal inclusions.

    With ``alpha_j = (eps_i − eps_m) / (eps_m + L_j (eps_i − eps_m))`` along axis j:

    - ``orientation="aligned"``: ``eps_j = eps_m + p eps_m alpha_j / (1 − p L_j alpha_j)``,
      i.e. ``eps_m + p eps_m (eps_i − eps_m) / (eps_m + (1 − p) L_j (eps_i − eps_m))``;
      returns the diagonal of the tensor, shape (..., 3).
    - ``orientation="random"``:
      ``eps = eps_m + eps_m (p/3) Σ_j alpha_j / (1 − (p/3) Σ_j L_j alpha_j)``; scalar.

    Both reduce to eq. (2) for L = (1/3, 1/3, 1/3). ``depolarization`` has a last axis of
    length 3 summing to 1 (see :mod:`nmmm.ema.shapes`) and broadcasts with the rest.

    References
    ----------
    Sihvola (1999), eqs. 4.29 and 4.37; Cohen et al., Phys. Rev. B 8, 3689 (1973).
    """
    check_orientation(orientation)
    ei = as_eps(eps_inclusion, "eps_inclusion")
    em = as_eps(eps_host, "eps_host")
    p = as_fraction(fraction)
    L = as_depolarization(depolarization)
    d = ei[..., None] - em[..., None]
    alpha = d / (em[..., None] + L * d)
    em_b = np.broadcast_to(em, np.broadcast_shapes(em.shape, ei.shape, p.shape, L.shape[:-1]))
    return _combine(em_b, [(p, alpha, L)], orientation)


def maxwell_garnett_shape(eps_inclusion: ArrayLike, eps_host: ArrayLike, fraction: ArrayLike,
                          shape: str) -> np.ndarray:
    """Maxwell Garnett medium for a :class:`~nmmm.ema.shapes.Shape` (ellipsoid or the cube
    approximation). Aligned shapes return (..., 3), random ones a scalar array."""
    return maxwell_garnett_multi(eps_host, [(eps_inclusion, fraction, shape)],
                                 orientation=shape.orientation)


def maxwell_garnett_multi(eps_host: ArrayLike, inclusions: Sequence[tuple],
                          orientation: str = "random") -> np.ndarray:
    """Maxwell Garnett medium with several inclusion populations in one host.

    ``inclusions`` is a sequence of ``(eps_inclusion, fraction, shape)`` (``shape`` a
    :class:`~nmmm.ema.shapes.Shape`, or ``None`` for spheres). With alpha_kj the
    polarizability per volume of population k along axis j and L_kj its local-field
    factor (the depolarization factor for ellipsoids, 1/3 — the Lorentz cavity — for the
    cube approximation):

    ``eps = eps_m + eps_m Σ_k p_k <alpha_k> / (1 − Σ_k p_k <L_k alpha_k>)``

    with <·> the mean over the three axes for ``orientation="random"`` and each axis
    separately (result (..., 3)) for ``"aligned"``. The fractions must sum to ≤ 1.

    Reference: Sihvola (1999), §4.5 (multiphase Maxwell Garnett).
    """
    from nmmm.ema.shapes import Shape

    check_orientation(orientation)
    em = as_eps(eps_host, "eps_host")
    terms = []
    total = 0
    for i, item in enumerate(inclusions):
        try:
            eps_i, frac, shape = item
        except (TypeError, ValueError):
            raise InvalidInputError(
                f"inclusion {i} must be a tuple (eps_inclusion, fraction, shape), got {item!r}") from None
        shape = Shape.sphere() if shape is None else shape
        if not isinstance(shape, Shape):
            raise InvalidInputError(f"inclusion {i}: shape must be an nmmm.ema.Shape or None, got {shape!r}")
        ei = as_eps(eps_i, f"eps_inclusion[{i}]")
        p = as_fraction(frac, f"fraction[{i}]")
        total = total + p
        alpha = shape.polarizability(ei, em)
        L = (np.full(3, 1 / 3) if shape.kind == "cube" else np.asarray(shape.depolarization))
        terms.append((p, alpha, L))
    if not terms:
        raise InvalidInputError("give at least one inclusion (eps_inclusion, fraction, shape)")
    if np.any(np.asarray(total) > 1 + 1e-12):
        raise InvalidInputError(f"inclusion fractions sum to {np.max(total):.6g} > 1; the host takes the rest")
    shape_all = np.broadcast_shapes(em.shape, *[np.shape(t[0]) for t in terms],
                                    *[t[1].shape[:-1] for t in terms])
    return _combine(np.broadcast_to(em, shape_all), terms, orientation)


__all__ = [
    "maxwell_garnett",
    "maxwell_garnett_ellipsoid",
    "maxwell_garnett_multi",
    "maxwell_garnett_polarizability",
    "maxwell_garnett_shape",
]
