"""Effect paints built from a simulated microstructure: the flakes of a deposit, both as a
discrete list (sparkle, glints) and, averaged, as the statistical BRDF.

- :func:`grey_metallic_coat` — the seed paper's grey metallic paint (example 3) as an
  :class:`nmmm.appearance.effect_coat.EffectCoat`: Al flakes (Rakić) of 20 µm mean diameter
  (log-normal, σ = 6 µm), 300 nm thick, 0.8 % of a 20 µm basecoat (n = 1.5), deposited in the
  seed's 450 µm × 450 µm × 20 µm cell (:func:`nmmm.microstructure.flake_deposit`), under a
  30 µm clear coat, over a grey primer (internal reflectance 0.35). The shipped recipe
  ``grey_metallic`` holds the same numbers.
- :func:`grey_metallic_from_deposit` — ``(PaintBRDF, FlakeList)`` of that coat.

References
----------
- E. Couka, F. Willot, D. Jeulin, "A mixed Boolean and deposit model for the modeling of metal
  pigments in paint layers", Image Anal. Stereol. 32(2), 2012.
"""

from __future__ import annotations

__all__ = ["grey_metallic_coat", "grey_metallic_from_deposit"]


def grey_metallic_coat(seed: int = 1, fraction: float = 0.008, tilt_std_deg: float = 6.0,
                       base_reflectance: float = 0.35, coat_thickness_nm: float = 30e3):
    """The seed's grey metallic paint as an :class:`~nmmm.appearance.effect_coat.EffectCoat`
    (module docstring); ``coat_thickness_nm`` is the clear coat above the 20 µm basecoat."""
    from nmmm.appearance.effect_coat import EffectCoat, FlakeSpec

    flakes = FlakeSpec("aluminium", diameter_um=20.0, diameter_std_um=6.0, thickness_nm=300.0, fraction=fraction,
                       tilt_std_deg=tilt_std_deg)
    return EffectCoat(flakes, binder=1.5, coat_thickness_nm=20e3, clear_coat_nm=coat_thickness_nm,
                      substrate_reflectance=base_reflectance, derive="deposit", seed=seed, name="grey metallic paint")


def grey_metallic_from_deposit(seed: int = 1, fraction: float = 0.008, tilt_std_deg: float = 6.0,
                               base_reflectance: float = 0.35, coat_thickness_nm: float = 30e3, wavelength_nm=None):
    """(paint BRDF, flake list) of the seed's grey metallic paint (:func:`grey_metallic_coat`):
    the flakes of one deposit give both."""
    coat = grey_metallic_coat(seed, fraction, tilt_std_deg, base_reflectance, coat_thickness_nm)
    return coat.brdf(wavelength_nm)
