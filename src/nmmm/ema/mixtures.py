"""Multi-level effective media: each level's result is a Material for the next level.

- :class:`Inclusion` — a population of inclusions: material, volume fraction, shape,
  optional radius (nm).
- :func:`mix` — host + inclusions -> :class:`~nmmm.materials.material.DerivedMaterial`
  (isotropic), by ``method`` ("maxwell_garnett", "maxwell_garnett_mie", "bruggeman",
  "looyenga").
- :func:`mix_tensor` — aligned inclusions -> the three principal-axis Materials (x, y, z).

Nesting levels is composing calls, as in the seed's homogenization chain::

    particles = mix(binder, [Inclusion(hematite, 0.30, Shape.cube())])        # aggregates
    layer = mix(binder, [Inclusion(particles, 0.10)], method="bruggeman")      # the layer

The results are evaluated lazily, on the wavelengths asked for, and carry their
components (``.components``) and a description (``.metadata``); their wavelength range
is the intersection of the components' ranges.

Size checks: when an :class:`Inclusion` has ``radius_nm``, quasi-static methods warn
(:class:`~nmmm.ema.size.SizeValidityWarning`) at evaluation if x = 2π n_m r/λ > 0.2 and
``"maxwell_garnett_mie"`` if x > 1 or the neglected multipoles exceed 5 % of the extinction
(see :mod:`nmmm.ema.size`).

References: Maxwell Garnett (1904); Bruggeman (1935); Doyle (1989); Sihvola (1999) —
see the formula modules.
"""

from __future__ import annotations

from dataclasses import dataclass
from collections.abc import Sequence

import numpy as np

from nmmm.ema.bruggeman_rule import bruggeman
from nmmm.ema.looyenga_rule import looyenga
from nmmm.ema.maxwell_garnett_rule import maxwell_garnett_multi, maxwell_garnett_polarizability
from nmmm.ema.registry import canonical_method
from nmmm.ema.shapes import Shape
from nmmm.ema.size import (
    MAX_SIZE_PARAMETER_QUASI_STATIC,
    check_dipole_validity,
    _warn_size,
    dipole_polarizability_mie,
    size_parameter,
)
from nmmm.errors import InvalidInputError
from nmmm.materials.material import DerivedMaterial, Material, as_material
from nmmm.spectra import check_fraction

MIX_METHODS = ("maxwell_garnett", "maxwell_garnett_mie", "bruggeman", "looyenga")


@dataclass(frozen=True)
class Inclusion:
    """A population of inclusions in a host.

    ``material`` a :class:`~nmmm.materials.material.Material` (or a database key such as
    ``"main/Au/Johnson"``, or a constant complex n + ik),
    ``fraction`` its volume fraction in [0, 1] of the mixture, ``shape`` a
    :class:`~nmmm.ema.shapes.Shape` (default sphere), ``radius_nm`` the radius of a sphere of
    the same volume (optional; needed by "maxwell_garnett_mie", used for size warnings).
    """

    material: Material
    fraction: float
    shape: Shape = Shape.sphere()
    radius_nm: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "material", _material(self.material))
        object.__setattr__(self, "fraction", float(check_fraction(self.fraction)))
        if not isinstance(self.shape, Shape):
            raise InvalidInputError(f"shape must be an nmmm.ema.Shape, got {self.shape!r}")
        if self.radius_nm is not None and not (np.isfinite(self.radius_nm) and self.radius_nm > 0):
            raise InvalidInputError(f"radius_nm must be a positive number of nm, got {self.radius_nm!r}")


def _as_inclusions(inclusions) -> tuple[Inclusion, ...]:
    if isinstance(inclusions, Inclusion):
        inclusions = [inclusions]
    out = []
    for i, item in enumerate(inclusions):
        if isinstance(item, Inclusion):
            out.append(item)
        elif isinstance(item, (tuple, list)) and 2 <= len(item) <= 4:
            out.append(Inclusion(*item))
        else:
            raise InvalidInputError(
                f"inclusion {i} must be an Inclusion or a tuple (material, fraction[, shape[, radius_nm]]), "
                f"got {item!r}")
    if not out:
        raise InvalidInputError("give at least one inclusion")
    total = sum(inc.fraction for inc in out)
    if total > 1 + 1e-12:
        raise InvalidInputError(f"inclusion fractions sum to {total:.6g} > 1; the host takes the rest (1 − sum)")
    return tuple(out)


def _describe(host, incs, method):
    parts = ", ".join(f"{inc.fraction:g} {inc.material.name} ({inc.shape.name}"
                      + (f", r={inc.radius_nm:g} nm" if inc.radius_nm else "") + ")" for inc in incs)
    return f"{method}: {parts} in {host.name}"


def _eps_function(host, incs, method, orientation):
    def eps(w_nm):
        em = host.eps(w_nm)
        epss = [inc.material.eps(w_nm) for inc in incs]
        for inc, e_inc in zip(incs, epss):
            if inc.radius_nm is not None:
                x = size_parameter(inc.radius_nm, w_nm, em)
                if method == "maxwell_garnett_mie":
                    check_dipole_validity(e_inc, em, inc.radius_nm, w_nm, stacklevel=5)
                else:
                    _warn_size(x, MAX_SIZE_PARAMETER_QUASI_STATIC,
                               f"the quasi-static '{method}' formula (try method='maxwell_garnett_mie')", 4)
        if method == "maxwell_garnett":
            return maxwell_garnett_multi(em, [(e, inc.fraction, inc.shape) for e, inc in zip(epss, incs)],
                                         orientation=orientation)
        if method == "maxwell_garnett_mie":
            alpha = sum(inc.fraction * dipole_polarizability_mie(e, em, inc.radius_nm, w_nm)
                        for e, inc in zip(epss, incs))
            return maxwell_garnett_polarizability(em, 1.0, alpha)
        fr = [inc.fraction for inc in incs]
        if method == "bruggeman":
            return bruggeman([em, *epss], [1 - sum(fr), *fr], shapes=[None, *[inc.shape for inc in incs]])
        return looyenga([em, *epss], [1 - sum(fr), *fr])
    return eps


def _material(value) -> Material:
    """A Material from a Material, a database key ('main/Au/Johnson') or a constant n + ik."""
    if isinstance(value, str):
        from nmmm.materials.database import get

        return get(value)
    return as_material(value)


def mix(host: object, inclusions: Sequence[tuple], method: str = "maxwell_garnett",
        name: str | None = None) -> DerivedMaterial:
    """The effective medium of ``inclusions`` in ``host`` as a Material (isotropic).

    Parameters
    ----------
    host : Material, database key (e.g. "main/SiO2/Malitson") or complex n + ik
    inclusions : Inclusion, or a sequence of Inclusion / tuples (material, fraction[, shape[, radius_nm]])
        Fractions are of the whole mixture; the host fills 1 − Σ fractions.
    method : {"maxwell_garnett", "maxwell_garnett_mie", "bruggeman", "looyenga"}
        Maxwell Garnett handles several populations, ellipsoids (randomly oriented) and cubes;
        "maxwell_garnett_mie" needs spheres with ``radius_nm``; Bruggeman treats every phase
        (host included, as spheres) symmetrically, the inclusions with their shapes
        (Polder–van Santen); Looyenga is for spheres.
    name : str, optional

    Returns
    -------
    DerivedMaterial — ``.eps(wavelength_nm)``, ``.nk(...)``, usable wherever a Material is.
    """
    host = _material(host)
    incs = _as_inclusions(inclusions)
    method = canonical_method(method)
    if method not in MIX_METHODS:
        raise InvalidInputError(f"mix supports the methods {MIX_METHODS}, got {method!r}")
    for inc in incs:
        if inc.shape.orientation == "aligned":
            raise InvalidInputError("aligned inclusions give an anisotropic medium: use mix_tensor "
                                    "(or Shape(..., orientation='random') for an isotropic mixture)")
        is_sphere = inc.shape.kind == "ellipsoid" and np.allclose(inc.shape.depolarization, 1 / 3, atol=1e-9)
        if method in ("looyenga", "maxwell_garnett_mie") and not is_sphere:
            raise InvalidInputError(f"method {method!r} is for spheres; use method='maxwell_garnett' for "
                                    f"{inc.shape.name}")
        if method == "maxwell_garnett_mie" and inc.radius_nm is None:
            raise InvalidInputError("method 'maxwell_garnett_mie' needs Inclusion(..., radius_nm=...)")
    desc = _describe(host, incs, method)
    result = DerivedMaterial(
        name=name or desc,
        eps_function=_eps_function(host, incs, method, "random"),
        components=(host, *[inc.material for inc in incs]),
        reference=f"nmmm.ema.mixtures — {desc}",
        metadata={"method": method, "host": host.name,
                  "inclusions": [{"material": inc.material.name, "fraction": inc.fraction,
                                  "shape": inc.shape.name, "radius_nm": inc.radius_nm} for inc in incs]},
    )
    result.range_nm  # noqa: B018 - components whose ranges do not overlap: OutOfRangeError now, not at first use
    return result


def mix_tensor(host: object, inclusions: Sequence[tuple],
               name: str | None = None) -> tuple[DerivedMaterial, DerivedMaterial, DerivedMaterial]:
    """Aligned inclusions (Maxwell Garnett): the principal permittivities as three Materials
    (along the inclusions' axes 1, 2, 3 — for spheroids, 3 is the symmetry axis, so the
    first and third are the ordinary and extraordinary media of a uniaxial layer)."""
    host = _material(host)
    incs = _as_inclusions(inclusions)
    f = _eps_function(host, incs, "maxwell_garnett", "aligned")
    base = name or _describe(host, incs, "maxwell_garnett (aligned)")
    out = []
    for axis in range(3):
        out.append(DerivedMaterial(
            name=f"{base} [axis {axis + 1}]",
            eps_function=(lambda w, a=axis: f(w)[..., a]),
            components=(host, *[inc.material for inc in incs]),
            reference=f"nmmm.ema.mix_tensor — {base}, principal axis {axis + 1}",
            metadata={"method": "maxwell_garnett", "orientation": "aligned", "axis": axis + 1},
        ))
    out[0].range_nm  # noqa: B018 - disjoint component ranges: OutOfRangeError now
    return tuple(out)


__all__ = ["MIX_METHODS", "Inclusion", "mix", "mix_tensor"]
