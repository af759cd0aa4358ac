"""Spectral rendering of flat painted plates with discrete flakes (glints), mono or stereo.

A plate lies in the plane z = 0 of its frame (centre at the origin, x along its width,
z its normal, lengths in mm). Its paint is a spectral BRDF (:class:`nmmm.appearance.brdf.
PaintBRDF`, or :class:`LambertianBRDF`) and, for effect paints, a **flake unit cell**
(:class:`nmmm.appearance.flakes.FlakeList`, e.g. 450 µm × 450 µm) tiled periodically over
the plate (the seed's 15 cm × 10 cm plate holds 332 × 240 cells), so memory stays bounded
whatever the plate size.

Per pixel, the radiance is

    L(λ) = Σ_lights f_smooth(ωi, ωo, λ) E_i(λ) cos θi  +  a(ωo, λ) L_env(λ)  +  L_glints(λ)

(for a lat-long environment map the second term is ∫ f L_env cos dω, plus the coat's
mirror image F(θo, λ) L_env(mirror of ωo)).

- ``f_smooth`` — the paint BRDF without its statistical flake term (coat specular lobe,
  diffuse base seen through the flakes, multiple scattering) when discrete flakes are
  rendered, the full BRDF otherwise. It is smooth over the image: evaluated on a coarse
  grid of pixels (every ``coarse_step`` pixels) and interpolated bilinearly.
- ``a(ωo)`` — the directional albedo (reciprocity: a uniform sky of radiance L_env is
  reflected as a(ωo) L_env), Dirac of a smooth coat included. A point-like light's mirror
  image in a smooth coat has zero area and is not drawn; lamps of finite size
  (``DirectionalLight.angular_diameter_deg``, ``PointLight.radius_mm``) appear as
  F(θ, λ) L_lamp(λ) where the mirrored view ray meets them.
- ``L_glints`` — each flake in the pixel's footprint that mirrors a light towards the
  camera (Snell in and out of the coat, Fresnel transmission T_i T_o, flake reflectance at
  its local angle, mean-field attenuation by the flakes above it, exactly as
  :func:`nmmm.appearance.brdf.flake_list_reflection`) adds

      ΔL = E_plane a_f |m·ω'i| / ω'iz · R T_i T_o e^{−τ_e S ζ} · g(ωo) / (Ω_pix d²)

  where g is a normalised Gaussian lobe (per sr, width ``glint_spread_deg``: the
  angular size of the light and the flakes' own roughness) around the flake's mirror
  direction, Ω_pix the pixel solid angle and d the distance (Ω_pix d² = footprint area ×
  cos θo). Averaged over many flakes this is the statistical ``"flakes"`` term of the
  BRDF. Candidate flakes per tile are found from a grid of flake normals around the
  tile's half vector, so the cost scales with the number of glints, not of flakes.
  Deterministic: the same flakes, cameras and lights give the same image.
  A flake wider than a pixel on the image (close-up and macro views) spreads this power
  over the pixels its projected ellipse covers, in proportion to the covered area
  (``render_plate(area_splat=True)``), conserving Σ L Ω_pix.

Modules (one per concept; the names below are importable from this package)
---------------------------------------------------------------------------
- :mod:`~nmmm.appearance.render.plate.scene` — the plate, its paint and flake cell.
- :mod:`~nmmm.appearance.render.plate.spectral_image` — the image and its colour.
- :mod:`~nmmm.appearance.render.plate.renderer` — :func:`render_plate`, :func:`render_stereo_plate`.
- :mod:`~nmmm.appearance.render.plate.coarse_grid` — the smooth part's coarse grid.
- :mod:`~nmmm.appearance.render.plate.environment` — lat-long environment quadrature, mirror image.
- :mod:`~nmmm.appearance.render.plate.glints` — tilt variants, the glint driver;
  :mod:`~nmmm.appearance.render.plate.glint_search` — tiles × flakes × lights (Numba);
  :mod:`~nmmm.appearance.render.plate.footprint` — a flake's projected ellipse;
  :mod:`~nmmm.appearance.render.plate.splatting` — glint records onto the image.

Public objects
--------------
- :class:`LambertianBRDF` — ideal diffuser f = ρ/π (reference plate).
- :class:`PaintedPlate` — paint, flake unit cell and size; :func:`seed_metallic_plate`
  (Poisson flakes), :func:`deposit_metallic_plate` (the microstructure deposit model).
- :class:`SpectralImage` — radiance (H, W, L), ``to_xyz``, ``to_srgb`` (exposure),
  ``to_display_rgb`` (sRGB / Display P3), ``write_png``, ``write_exr`` (Fichet et al. 2021 layout).
- :func:`render_plate`, :func:`render_stereo_plate`.
- :class:`ViewingBooth` — the seed's viewing scene: a grey booth (walls and floor of stated
  reflectance) and a D65 source overhead or at 45°: ``lights()`` and ``environment(w)``
  for :func:`render_plate`.

References
----------
- S. Ershov, K. Kolchin, K. Myszkowski, Computer Graphics Forum 20(3) (2001) 227 — flakes
  as oriented mirrors in a paint layer.
- W. Jakob, M. Hašan, L.-Q. Yan, J. Lawrence, R. Ramamoorthi, S. Marschner, "Discrete
  stochastic microfacet models", ACM TOG 33(4) (2014) — glints as discrete facets
  integrated over a pixel footprint and a light's solid angle.
- Couka, Willot, Jeulin, Image Anal. Stereol. 32(2) (2012) — flake unit cells of paints.
- M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed. (2023) §4.1
  (radiance, irradiance, pinhole measurement).
"""

# private helpers other modules and tests use through this path
from nmmm.appearance.render.plate.environment import ViewingBooth
from nmmm.appearance.render.plate.glints import _render_glints, _tilt_variants  # noqa: F401
from nmmm.appearance.render.plate.renderer import (  # noqa: F401
    _light_at,
    _plate_hits,
    render_plate,
    render_stereo_plate,
)
from nmmm.appearance.render.plate.scene import (
    LambertianBRDF,
    PaintedPlate,
    deposit_metallic_plate,
    seed_metallic_plate,
)
from nmmm.appearance.render.plate.spectral_image import SpectralImage

__all__ = [
    "LambertianBRDF",
    "PaintedPlate",
    "SpectralImage",
    "seed_metallic_plate",
    "deposit_metallic_plate",
    "render_plate",
    "render_stereo_plate",
    "ViewingBooth",
]
