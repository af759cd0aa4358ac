"""Effect paints built from a simulated microstructure: the flakes of a deposit, both as a
discrete list (sparkle, glints) and, averaged, as the statistical BRDF.

- :func:`grey_metallic_from_deposit` — the seed paper's grey metallic paint (example 3) from a
  :func:`nmmm.microstructure.flake_deposit` in its 450 µm × 450 µm × 20 µm unit cell.

References
----------
- E. Couka, F. Willot, D. Jeulin, "A mixed Boolean and deposit model for the modeling of metal
  pigments in paint layers", Image Anal. Stereol. 32(2), 2012.
"""

from __future__ import annotations

__all__ = ["grey_metallic_from_deposit"]


def grey_metallic_from_deposit(seed: int = 1, fraction: float = 0.008, tilt_std_deg: float = 6.0,
                               base_reflectance: float = 0.35, coat_thickness_nm: float = 30e3):
    """(paint BRDF, flake list) of the seed's grey metallic paint: Al flakes (Rakić) of
    20 µm mean diameter, 300 nm thick, deposited in a 450 × 450 × 20 µm cell
    (:func:`nmmm.microstructure.flake_deposit`), under a 30 µm clear coat (n = 1.5), over
    a grey pigmented base of internal reflectance ``base_reflectance``."""
    from nmmm.appearance.brdf import ClearCoat, PaintBRDF
    from nmmm.appearance.flakes import FlakeList, aluminium_flakes
    from nmmm.microstructure import flake_deposit

    dep = flake_deposit(box_nm=(450e3, 450e3, 20e3), fraction=fraction, tilt_std_deg=tilt_std_deg, seed=seed)
    flakes = FlakeList.from_deposit(dep, aluminium_flakes(), n_binder=1.5, coat_thickness_nm=coat_thickness_nm)
    paint = PaintBRDF(ClearCoat(1.5, 0.0), base_reflectance, flakes.to_flake_layer(), name="grey metallic paint")
    return paint, flakes
