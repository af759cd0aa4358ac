"""Paint BRDFs by family: clear dielectric, solid (opaque) paint — also from a
:class:`nmmm.layers.paint.PaintFilm` —, metallic and interference paints, and the seed
paper's grey metallic paint.
"""

from __future__ import annotations

import numpy as np

from nmmm.appearance.brdf.clear_coat import ClearCoat
from nmmm.appearance.brdf.paint_brdf import PaintBRDF
from nmmm.appearance.flakes import FlakeLayer, TiltDistribution, aluminium_flakes, gaussian_tilt, mica_pigment
from nmmm.spectra import as_wavelength_nm

__all__ = [
    "clear_dielectric", "opaque_paint", "body_reflectance_from_film", "opaque_paint_from_film",
    "metallic_paint", "interference_paint", "grey_metallic_paint",
]


def clear_dielectric(n=1.5, roughness: float = 0.0) -> PaintBRDF:
    """A clear dielectric half-space (no flakes, no pigment): Fresnel reflection only."""
    return PaintBRDF(ClearCoat(n, roughness), 0.0, None, name=f"clear dielectric n={n}")


def opaque_paint(body_reflectance, coat=1.5, roughness: float = 0.0, name: str = "opaque paint") -> PaintBRDF:
    """A solid (non-metallic) paint: clear coat over a diffusely reflecting pigmented film
    of internal reflectance ``body_reflectance`` (e.g. Kubelka–Munk R∞ from
    :mod:`nmmm.layers`)."""
    return PaintBRDF(ClearCoat(coat, roughness), body_reflectance, None, name=name)


def body_reflectance_from_film(film, wavelength_nm, km_method: str = "gate"):
    """Internal diffuse reflectance ρ(λ) of a pigmented film from :mod:`nmmm.layers`
    (a :class:`nmmm.layers.paint.PaintFilm`): Mie → K, S (``km_method``, Gate 1974 by
    default) → Kubelka's finite film over its substrate — **without** the Saunderson
    surface correction, which :class:`PaintBRDF` applies itself through the coat.
    Returns ``(wavelength_nm, ρ)`` ready for ``body_reflectance``. The film's clear-coat
    absorption is not included (the BRDF's coat is non-absorbing)."""
    from nmmm.layers.kubelka_munk import km_coefficients, km_reflectance
    from nmmm.layers.paint import film_coefficients

    w = as_wavelength_nm(np.atleast_1d(wavelength_nm)).ravel()
    co = film_coefficients(film, w)
    K, S = km_coefficients(co.mu_a_per_nm, co.mu_s_per_nm, co.g, method=km_method)
    sub = np.broadcast_to(np.asarray(film.substrate_reflectance, dtype=float), w.shape)
    thickness = film.thickness_nm if np.isfinite(film.thickness_nm) else 1e15
    return w, np.clip(np.asarray(km_reflectance(K, S, thickness, sub), float), 0.0, 1.0)


def opaque_paint_from_film(film, wavelength_nm, roughness: float = 0.0, name: str | None = None) -> PaintBRDF:
    """A solid paint whose base is a :class:`nmmm.layers.paint.PaintFilm` (pigment, grain
    size, fraction, thickness) and whose clear coat is the film's binder."""
    w, rho = body_reflectance_from_film(film, wavelength_nm)
    return PaintBRDF(ClearCoat(film.binder, roughness), (w, rho), None, name=name or "solid paint (layers film)")


def metallic_paint(optical_depth: float = 1.5, tilt: TiltDistribution | float = 12.0, optics=None,
                   body_reflectance=0.05, coat=1.5, roughness: float = 0.0, name: str = "metallic paint") -> PaintBRDF:
    """A metallic paint: aluminium flakes (``main/Al/Rakic`` unless ``optics`` given) with
    a Gaussian tilt of σ = ``tilt`` degrees (or a :class:`TiltDistribution`) and flake
    optical depth τ, over a base of internal reflectance ``body_reflectance``."""
    if not isinstance(tilt, TiltDistribution):
        tilt = gaussian_tilt(tilt)
    optics = aluminium_flakes() if optics is None else optics
    return PaintBRDF(ClearCoat(coat, roughness), body_reflectance, FlakeLayer(optics, tilt, optical_depth), name=name)


def interference_paint(tio2_thickness_nm: float = 120.0, mica_thickness_nm: float = 350.0, optical_depth: float = 1.0,
                       tilt: TiltDistribution | float = 10.0, body_reflectance=0.03, coat=1.5, roughness: float = 0.0,
                       name: str | None = None) -> PaintBRDF:
    """An interference (pearlescent) paint: TiO2-coated mica flakes over a dark base."""
    if not isinstance(tilt, TiltDistribution):
        tilt = gaussian_tilt(tilt)
    optics = mica_pigment(tio2_thickness_nm, mica_thickness_nm)
    return PaintBRDF(ClearCoat(coat, roughness), body_reflectance, FlakeLayer(optics, tilt, optical_depth),
                     name=name or f"interference paint ({optics.name})")


def grey_metallic_paint() -> PaintBRDF:
    """The seed paper's grey metallic paint (example 3) in statistical form: Al flakes
    (Rakić) with a Gaussian tilt of σ = 6°, optical depth τ = 0.5 (about what a 0.8 %
    volume fraction of 20 µm × 300 nm flakes gives in the 20 µm layer), under a smooth
    clear coat (n = 1.5) over a grey base (internal reflectance 0.35). For the version
    built from an actual flake deposit see
    :func:`nmmm.appearance.deposit.grey_metallic_from_deposit`."""
    return metallic_paint(optical_depth=0.5, tilt=6.0, body_reflectance=0.35, name="grey metallic paint")
