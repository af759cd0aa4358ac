"""nmmm.layers — meso scale: pigment scattering (Mie), radiative transfer in the
pigmented film (Kubelka–Munk with Saunderson, adding–doubling), thin-film interference.

Shared by two authors: each adds the import lines of their own modules below, and their names to
``__all__`` (tests/test_public_names.py checks each resolves to one object, never a module).
"""
from nmmm.layers.fresnel_equations import brewster_angle, critical_angle, fresnel, n_cos_theta  # noqa: E402,F401  (thin films)
from nmmm.layers.thinfilm import Layer, Stack, StackResult  # noqa: E402,F401  (thin films)
from nmmm.layers.mie_scattering import MieResult, mie, mie_coated, mie_multilayer  # noqa: E402,F401  (Mie)
from nmmm.layers.distributions import (  # noqa: E402,F401  (Mie: sizes, shapes, structure factor)
    PigmentOptics,
    SizeDistribution,
    equivalent_sphere_diameter,
    histogram,
    lognormal,
    monodisperse,
    percus_yevick_structure_factor,
    pigment_optics,
)
from nmmm.layers.kubelka_munk import (  # noqa: E402,F401  (radiative transfer, fast)
    hiding_thickness,
    km_coefficients,
    km_r_infinity,
    km_reflectance,
    km_transmittance,
    saunderson,
    saunderson_k1,
    saunderson_k2,
)
from nmmm.layers.adding_doubling_method import ADResult, adding_doubling  # noqa: E402,F401  (radiative transfer, reference)
from nmmm.layers.paint import PaintFilm, compare_km_ad, film_coefficients, paint_reflectance  # noqa: E402,F401  (paint film)
from nmmm.layers.pigment_mixture import Component, MixtureOptics, mixture_optics, percus_yevick_mixture  # noqa: E402,F401  (multi-component films)
from nmmm.layers.coat_stack import Coat, CoatStack, Substrate, stack_reflectance  # noqa: E402,F401  (coat stacks)
from nmmm.layers.geometries import GEOMETRIES  # noqa: E402,F401  (instrument geometries)
from nmmm.layers.formulation import contrast_ratio, formulator_quantities, tinting_strength  # noqa: E402,F401  (formulator)

__all__ = [
    "brewster_angle", "critical_angle", "fresnel", "n_cos_theta",
    "Layer", "Stack", "StackResult",
    "MieResult", "mie", "mie_coated", "mie_multilayer",
    "PigmentOptics", "SizeDistribution", "equivalent_sphere_diameter", "histogram", "lognormal", "monodisperse",
    "percus_yevick_structure_factor", "pigment_optics",
    "hiding_thickness", "km_coefficients", "km_r_infinity", "km_reflectance", "km_transmittance", "saunderson",
    "saunderson_k1", "saunderson_k2",
    "ADResult", "adding_doubling",
    "PaintFilm", "compare_km_ad", "film_coefficients", "paint_reflectance",
    "Component", "MixtureOptics", "mixture_optics", "percus_yevick_mixture",
    "Coat", "CoatStack", "Substrate", "stack_reflectance", "GEOMETRIES",
    "contrast_ratio", "formulator_quantities", "tinting_strength",
]
