"""Looyenga (Landau–Lifshitz–Looyenga) mixing rule: cube roots of ε add linearly.

- :func:`looyenga` — ``eps^(1/3) = Σ_i f_i eps_i^(1/3)``, n phases or the two-phase form.

Notes
-----
Symmetric in the phases; derived for small contrast (|eps_i − eps_j| ≪ |eps|), where it
agrees with Bruggeman and Maxwell Garnett to second order; it is often used for porous
dielectrics. The principal cube root is the right branch: for Im ε_i >= 0 every cube root
lies in the sector 0 <= arg <= π/3, so their mean does too and its cube has Im ε >= 0.

References
----------
- H. Looyenga, "Dielectric constants of heterogeneous mixtures", Physica 31, 401 (1965),
  doi:10.1016/0031-8914(65)90045-5.
- L. D. Landau, E. M. Lifshitz, Electrodynamics of Continuous Media (Pergamon 1960), §9.
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import ArrayLike

from nmmm.ema._validation import as_eps, as_fraction, broadcast_inputs, passive
from nmmm.errors import InvalidInputError


def looyenga(eps_phases: ArrayLike, fractions: ArrayLike, fraction: ArrayLike | None = None) -> np.ndarray:
    """Looyenga effective permittivity: ``eps = (Σ_i f_i eps_i^(1/3))³``.

    Call forms as :func:`nmmm.ema.bruggeman_rule`: ``looyenga([eps_1, ...], [f_1, ...])`` or
    ``looyenga(eps_inclusion, eps_host, fraction)``.

    >>> round(float(looyenga(1.0, 8.0, 0.5).real), 6)   # ((1 + 2)/2)³
    3.375
    """
    if fraction is not None:
        e1, e2 = as_eps(eps_phases, "eps_inclusion"), as_eps(fractions, "eps_host")
        p = as_fraction(fraction)
        broadcast_inputs(eps_inclusion=e1, eps_host=e2, fraction=p)
        # the cube roots are taken on the (usually per-wavelength) inputs, before broadcasting
        return _looyenga_two_phase_ufunc(np.power(e1, 1 / 3), np.power(e2, 1 / 3), p)
    if not isinstance(eps_phases, (list, tuple)) or not isinstance(fractions, (list, tuple)) \
            or len(eps_phases) != len(fractions) or not eps_phases:
        raise InvalidInputError("looyenga takes a list of phase permittivities and a list of as many "
                                "fractions, or (eps_inclusion, eps_host, fraction)")
    total = 0
    acc = 0
    for i, (e, f) in enumerate(zip(eps_phases, fractions)):
        e = as_eps(e, f"eps_phases[{i}]")
        f = as_fraction(f, f"fractions[{i}]")
        total = total + f
        acc = acc + f * np.power(e, 1 / 3)
    if np.any(np.abs(np.asarray(total) - 1) > 1e-6):
        raise InvalidInputError("Looyenga fractions must sum to 1 (list every phase)")
    return passive(acc**3)


@numba.vectorize(["complex128(complex128, complex128, float64)"], cache=True)
def _looyenga_two_phase_ufunc(c1, c2, p):
    """``(p c1 + (1 − p) c2)³`` and :func:`passive` in one broadcasting pass, ``c = ε^(1/3)``
    (the NumPy expression makes five temporaries of the full broadcast size, issue 22)."""
    z = p * c1 + (1 - p) * c2
    e = z * z * z
    if e.imag < 0:
        e = e.real + 0j
    return e


__all__ = ["looyenga"]
