"""Bruggeman (symmetric) effective medium for any number of phases, with the physical root.

- :func:`bruggeman` — n phases, ``Σ_i f_i (eps_i − eps) / (eps_i + 2 eps) = 0``; or the
  two-phase form ``bruggeman(eps_inclusion, eps_host, fraction)``.
- :func:`bruggeman_residual` — the left-hand side, to check a solution.

Notes
-----
Clearing denominators gives a polynomial of degree n in ε (a quadratic for two phases).
Which root is physical is a known pitfall: taking the principal square root of the
quadratic's discriminant jumps between roots across wavelengths for metal–dielectric
mixtures (a negative-loss, discontinuous ε). nmmm selects the root by the *limiting
absorption principle*: the phases are given a vanishing extra loss ``i δ`` (δ = 1e-7·max|ε_i|),
for which exactly one root has Im ε > 0 (Milton 1981: the Bruggeman ε is a Herglotz
function of the phase permittivities; checked by random sampling in the tests), and the root
of the unperturbed polynomial nearest to it is returned. The result is continuous in
wavelength, has Im ε >= 0 and, for lossless dielectrics, is the real root between the phases'
permittivities. Two phases use the closed-form quadratic; more phases the eigenvalues of the
batched companion matrices (no Python loop over wavelengths or fractions).

Spherical inclusions; the percolation threshold of a conducting phase is p = 1/3.

References
----------
- D. A. G. Bruggeman, "Berechnung verschiedener physikalischer Konstanten von heterogenen
  Substanzen", Ann. Phys. 416, 636 (1935), doi:10.1002/andp.19354160705.
- G. W. Milton, "Bounds on the complex permittivity of a two-component composite material",
  J. Appl. Phys. 52, 5286 (1981).
- D. E. Aspnes, "Optical properties of thin films", Thin Solid Films 89, 249 (1982).
- T. G. Mackay, A. Lakhtakia, "Modern Analytical Electromagnetic Homogenization",
  Morgan & Claypool (2015), ch. 3 (root selection).
"""

from __future__ import annotations

import numpy as np

from nmmm.ema._validation import as_eps, as_fraction, passive
from nmmm.errors import InvalidInputError

#: Relative loss added to every phase to select the physical root.
_DELTA = 1e-7


def _phases(eps_phases, fractions):
    if isinstance(eps_phases, np.ndarray) or not isinstance(eps_phases, (list, tuple)):
        raise InvalidInputError(
            "bruggeman takes either a list of phase permittivities and a list of fractions, "
            "bruggeman([eps1, eps2, ...], [f1, f2, ...]), or the two-phase form "
            "bruggeman(eps_inclusion, eps_host, fraction)")
    if not isinstance(fractions, (list, tuple)) or len(fractions) != len(eps_phases):
        raise InvalidInputError(
            f"give one fraction per phase: {len(eps_phases)} phases but fractions={fractions!r}")
    if len(eps_phases) < 1:
        raise InvalidInputError("give at least one phase")
    eps = [as_eps(e, f"eps_phases[{i}]") for i, e in enumerate(eps_phases)]
    fr = [as_fraction(f, f"fractions[{i}]") for i, f in enumerate(fractions)]
    total = sum(fr)
    if np.any(np.abs(total - 1) > 1e-6):
        raise InvalidInputError(
            f"Bruggeman fractions must sum to 1 (every phase of the mixture listed), got sums in "
            f"[{np.min(total):.6g}, {np.max(total):.6g}]")
    shape = np.broadcast_shapes(*[e.shape for e in eps], *[f.shape for f in fr])
    eps = np.stack([np.broadcast_to(e, shape) for e in eps], axis=-1)
    fr = np.stack([np.broadcast_to(f, shape) for f in fr], axis=-1)
    return eps, fr / fr.sum(-1, keepdims=True)


def _quadratic_coefficients(e, f):
    """2 ε² + b ε + c = 0 for two phases (e, f with last axis 2)."""
    ea, eb = e[..., 0], e[..., 1]
    fa = f[..., 0]
    b = (2 - 3 * fa) * eb + (3 * fa - 1) * ea
    return -b, -ea * eb  # 2ε² − bε − ea·eb = 0 written as 2ε² + (−b)ε + (−ea eb)


def _quadratic_roots(e, f):
    B, C = _quadratic_coefficients(e, f)
    disc = np.sqrt(B * B - 8 * C)
    return np.stack([(-B + disc) / 4, (-B - disc) / 4], axis=-1)


def _poly_coefficients(e, f):
    """Coefficients (highest degree first) of Σ_i f_i (e_i − ε) Π_{j≠i} (e_j + 2ε)."""
    n = e.shape[-1]
    coef = np.zeros(e.shape[:-1] + (n + 1,), dtype=complex)  # ascending powers
    for i in range(n):  # loop over phases only (n is 2–5)
        term = np.zeros_like(coef)
        term[..., 0] = f[..., i] * e[..., i]
        term[..., 1] = -f[..., i]
        deg = 1
        for j in range(n):
            if j == i:
                continue
            new = np.zeros_like(coef)
            new[..., : deg + 1] += e[..., j, None] * term[..., : deg + 1]
            new[..., 1 : deg + 2] += 2 * term[..., : deg + 1]
            term, deg = new, deg + 1
        coef += term
    return coef[..., ::-1]


def _poly_roots(e, f):
    c = _poly_coefficients(e, f)
    n = c.shape[-1] - 1
    lead = c[..., 0:1]
    comp = np.zeros(c.shape[:-1] + (n, n), dtype=complex)
    comp[..., 0, :] = -c[..., 1:] / lead
    if n > 1:
        comp[..., np.arange(1, n), np.arange(0, n - 1)] = 1.0
    return np.linalg.eigvals(comp)


def _roots(e, f):
    return _quadratic_roots(e, f) if e.shape[-1] == 2 else _poly_roots(e, f)


def bruggeman_residual(eps_effective, eps_phases, fractions) -> np.ndarray:
    """``Σ_i f_i (eps_i − eps) / (eps_i + 2 eps)`` — zero for a Bruggeman solution."""
    e, f = _phases(eps_phases, fractions)
    eff = np.asarray(eps_effective, dtype=complex)[..., None]
    return np.sum(f * (e - eff) / (e + 2 * eff), axis=-1)


def bruggeman(eps_phases, fractions, fraction=None) -> np.ndarray:
    """Bruggeman symmetric effective permittivity of spherical grains of n phases.

    Solves ``Σ_i f_i (eps_i − eps) / (eps_i + 2 eps) = 0`` for the physical root (see the
    module notes).

    Call forms
    ----------
    ``bruggeman([eps_1, ..., eps_n], [f_1, ..., f_n])`` — lists of broadcastable arrays;
    the fractions must sum to 1.

    ``bruggeman(eps_inclusion, eps_host, fraction)`` — two phases, the inclusions at
    ``fraction`` (the result is symmetric: exchanging the phases and using 1 − fraction
    gives the same medium).

    Returns
    -------
    numpy.ndarray, complex, Im >= 0; the broadcast shape of the inputs.

    Examples
    --------
    Equal parts of ε = 1 and ε = 4: 4ε² − 5ε − 8 = 0, ε = (5 + sqrt(153))/8:

    >>> round(float(bruggeman(1.0, 4.0, 0.5).real), 6)
    2.171165
    """
    if fraction is not None:
        eps_phases, fractions = [eps_phases, fractions], [fraction, 1 - as_fraction(fraction)]
    e, f = _phases(eps_phases, fractions)
    if e.shape[-1] == 1:
        return e[..., 0].copy()
    scale = np.max(np.abs(e), axis=-1, keepdims=True)
    scale = np.where(scale > 0, scale, 1.0)
    guide = _roots(e + 1j * _DELTA * scale, f)
    pick = np.take_along_axis(guide, np.argmax(guide.imag, axis=-1)[..., None], axis=-1)
    roots = _roots(e, f)
    nearest = np.argmin(np.abs(roots - pick), axis=-1)[..., None]
    out = np.take_along_axis(roots, nearest, axis=-1)[..., 0]
    return passive(out)


__all__ = ["bruggeman", "bruggeman_residual"]
