"""One entry point for two-phase effective media, with a method registry.

- :data:`EFFECTIVE_PERMITTIVITY_METHODS` — name -> function ``f(eps_inclusion, eps_host,
  fraction, **kwargs)``.
- :func:`effective_permittivity` — the dispatcher,
  ``effective_permittivity(eps_inclusion, eps_host, fraction, method="bruggeman")``.

Method names are case-insensitive; spaces and hyphens count as underscores; a few
usual aliases are accepted ("MG", "EMA", "LLL", ...). Adding a method is adding a
function and a registry line (the colour-science pattern).

References: see each method's module (:mod:`~nmmm.ema.maxwell_garnett_rule`,
:mod:`~nmmm.ema.bruggeman_rule`, :mod:`~nmmm.ema.looyenga_rule`, :mod:`~nmmm.ema.size`,
:mod:`~nmmm.ema.bounds`).
"""

from __future__ import annotations

import inspect

import numpy as np
from numpy.typing import ArrayLike

from nmmm.ema.bounds import wiener_bounds
from nmmm.ema.bruggeman_rule import bruggeman
from nmmm.ema.looyenga_rule import looyenga
from nmmm.ema.maxwell_garnett_rule import maxwell_garnett, maxwell_garnett_ellipsoid, maxwell_garnett_shape
from nmmm.ema.size import maxwell_garnett_mie
from nmmm.errors import InvalidInputError
from nmmm.spectra import check_fraction


def _bruggeman(eps_inclusion, eps_host, fraction, shapes=None):
    """Bruggeman symmetric medium of two phases (spheres, or shapes=[Shape, Shape]), physical root."""
    return bruggeman(eps_inclusion, eps_host, fraction, shapes=shapes)


def _looyenga(eps_inclusion, eps_host, fraction):
    """Looyenga: cube roots of eps mix linearly (small contrast)."""
    return looyenga(eps_inclusion, eps_host, fraction)


def _wiener_parallel(eps_inclusion, eps_host, fraction):
    """Layers parallel to the field: the arithmetic mean (upper Wiener bound)."""
    f = check_fraction(fraction)
    return wiener_bounds([eps_inclusion, eps_host], [f, 1 - f])[1]


def _wiener_series(eps_inclusion, eps_host, fraction):
    """Layers across the field: the harmonic mean (lower Wiener bound)."""
    f = check_fraction(fraction)
    return wiener_bounds([eps_inclusion, eps_host], [f, 1 - f])[0]


#: name -> function(eps_inclusion, eps_host, fraction, **kwargs)
EFFECTIVE_PERMITTIVITY_METHODS = {
    "maxwell_garnett": maxwell_garnett,
    "maxwell_garnett_ellipsoid": maxwell_garnett_ellipsoid,  # depolarization=, orientation=
    "maxwell_garnett_shape": maxwell_garnett_shape,          # shape=
    "maxwell_garnett_mie": maxwell_garnett_mie,              # radius_nm=, wavelength_nm=
    "bruggeman": _bruggeman,
    "looyenga": _looyenga,
    "wiener_parallel": _wiener_parallel,  # layers parallel to the field (arithmetic mean)
    "wiener_series": _wiener_series,      # layers across the field (harmonic mean)
}

_ALIASES = {
    "mg": "maxwell_garnett",
    "maxwellgarnett": "maxwell_garnett",
    "ema": "bruggeman",
    "bruggeman_ema": "bruggeman",
    "lll": "looyenga",
    "landau_lifshitz_looyenga": "looyenga",
    "doyle": "maxwell_garnett_mie",
    "mg_mie": "maxwell_garnett_mie",
    "parallel": "wiener_parallel",
    "series": "wiener_series",
}


def canonical_method(method: str) -> str:
    """The registry key for ``method`` (case-insensitive, aliases resolved)."""
    key = str(method).strip().lower().replace(" ", "_").replace("-", "_")
    key = _ALIASES.get(key, key)
    if key not in EFFECTIVE_PERMITTIVITY_METHODS:
        raise InvalidInputError(
            f"unknown effective-medium method {method!r}; choose one of "
            f"{sorted(EFFECTIVE_PERMITTIVITY_METHODS)} (aliases: {sorted(_ALIASES)})")
    return key


def effective_permittivity(eps_inclusion: ArrayLike, eps_host: ArrayLike, fraction: ArrayLike,
                           method: str = "maxwell_garnett", **kwargs: object) -> np.ndarray:
    """Effective permittivity of inclusions (``fraction``) in a host by the named method.

    Parameters
    ----------
    eps_inclusion, eps_host : array_like, complex (Im >= 0)
    fraction : array_like in [0, 1]
    method : str
        A key of :data:`EFFECTIVE_PERMITTIVITY_METHODS` or an alias.
    **kwargs
        Passed to the method (``depolarization=``/``orientation=`` for
        ``maxwell_garnett_ellipsoid``, ``shape=`` for ``maxwell_garnett_shape``,
        ``shapes=[inclusion_shape, host_shape]`` for ``bruggeman``,
        ``radius_nm=``/``wavelength_nm=`` for ``maxwell_garnett_mie``).

    Examples
    --------
    >>> round(float(effective_permittivity(1.0, 4.0, 0.5, method="Bruggeman").real), 6)
    2.171165
    """
    key = canonical_method(method)
    function = EFFECTIVE_PERMITTIVITY_METHODS[key]
    accepted = [name for name, p in list(inspect.signature(function).parameters.items())[3:]
                if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
    unknown = sorted(set(kwargs) - set(accepted))
    if unknown:
        raise InvalidInputError(
            f"method {key!r} takes no argument(s) {unknown}; it takes {accepted or 'no options'}")
    return function(eps_inclusion, eps_host, fraction, **kwargs)


__all__ = ["EFFECTIVE_PERMITTIVITY_METHODS", "canonical_method", "effective_permittivity"]
