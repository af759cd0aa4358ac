"""nmmm.ema — effective-medium approximations: the nano scale of the homogenization chain.

Formulas (complex ε arrays that broadcast; fractions in [0, 1]):

- :func:`maxwell_garnett` — eq. (2) of the seed paper; :func:`maxwell_garnett_ellipsoid`,
  :func:`maxwell_garnett_shape`, :func:`maxwell_garnett_multi`,
  :func:`maxwell_garnett_polarizability`.
- :func:`bruggeman` — n phases, physical root; :func:`bruggeman_residual`.
- :func:`looyenga`.
- Bounds: :func:`wiener_bounds`, :func:`hashin_shtrikman_bounds`,
  :func:`bergman_milton_bounds` (complex-plane regions, :class:`BoundingRegion`).
- Shapes: :class:`Shape`, :func:`ellipsoid_depolarization`, :func:`spheroid_depolarization`,
  :data:`CUBE_DEPOLARIZATION` (approximation).
- Size: :func:`maxwell_garnett_mie` (Doyle 1989, first Mie coefficient :func:`mie_a1`),
  :func:`size_parameter`, :func:`check_quasi_static`, :class:`SizeValidityWarning`.
- Dispatcher: :func:`effective_permittivity` with :data:`EFFECTIVE_PERMITTIVITY_METHODS`.

Materials across scales: :func:`mix` (-> a Material), :func:`mix_tensor`, :class:`Inclusion`.
Causality: :func:`nmmm.ema.causality.kk_check_mixture`. Worked example:
:func:`nmmm.demo.gold_ruby.gold_ruby_demo`.

References
----------
See the module docstrings: Maxwell Garnett (1904), Bruggeman (1935), Looyenga (1965),
Hashin & Shtrikman (1962), Bergman (1980), Milton (1980, 1981), Doyle (1989),
Ruppin (2000), Sihvola (1999), Bohren & Huffman (1983).
"""

from nmmm.ema.bounds import BoundingRegion, bergman_milton_bounds, hashin_shtrikman_bounds, wiener_bounds
from nmmm.ema.bruggeman_rule import bruggeman, bruggeman_residual
from nmmm.ema.looyenga_rule import looyenga
from nmmm.ema.maxwell_garnett_rule import (
    maxwell_garnett,
    maxwell_garnett_ellipsoid,
    maxwell_garnett_multi,
    maxwell_garnett_polarizability,
    maxwell_garnett_shape,
)
from nmmm.ema.mixtures import Inclusion, mix, mix_tensor
from nmmm.ema.registry import EFFECTIVE_PERMITTIVITY_METHODS, effective_permittivity
from nmmm.ema.shapes import (
    CUBE_DEPOLARIZATION,
    Shape,
    cube_polarizability,
    ellipsoid_depolarization,
    ellipsoid_polarizability,
    spheroid_depolarization,
)
from nmmm.ema.size import (
    SizeValidityWarning,
    check_dipole_validity,
    check_quasi_static,
    dipole_polarizability_mie,
    maxwell_garnett_mie,
    mie_a1,
    mie_low_orders,
    neglected_multipole_fraction,
    size_parameter,
)

__all__ = [
    "BoundingRegion", "CUBE_DEPOLARIZATION", "EFFECTIVE_PERMITTIVITY_METHODS", "Inclusion", "Shape",
    "SizeValidityWarning", "bergman_milton_bounds", "bruggeman", "bruggeman_residual",
    "check_dipole_validity", "check_quasi_static", "mie_low_orders", "neglected_multipole_fraction", "cube_polarizability", "dipole_polarizability_mie", "effective_permittivity",
    "ellipsoid_depolarization", "ellipsoid_polarizability", "hashin_shtrikman_bounds", "looyenga",
    "maxwell_garnett", "maxwell_garnett_ellipsoid", "maxwell_garnett_mie", "maxwell_garnett_multi",
    "maxwell_garnett_polarizability", "maxwell_garnett_shape", "mie_a1", "mix", "mix_tensor",
    "size_parameter", "spheroid_depolarization", "wiener_bounds",
]
