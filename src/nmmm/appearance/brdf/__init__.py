"""Spectral BRDFs of clear-coated paints: opaque (solid), metallic and interference.

One model, :class:`PaintBRDF`, covers the three families. A paint is

    air | clear coat (index n, smooth or GGX-rough top) | flake layer (optional) | base

where the base is a pigmented film seen from inside the binder through its **internal
diffuse reflectance** ρ(λ) (Kubelka–Munk R∞, or the reflectance of a finite film on its
substrate, *without* any air-interface (Saunderson) correction: this module adds the
interface). Coat and binder are in optical contact and share the index n.

Evaluation: ``brdf(wavelength_nm, wi, wo)`` (alias of :meth:`PaintBRDF.evaluate`) takes
unit direction vectors ``(..., 3)`` in the surface frame (z = surface normal, both
pointing away from the surface) and returns ``(..., n_wavelengths)`` in 1/sr,
vectorised over directions and wavelengths (tables are prepared once per wavelength grid
and cached). A smooth coat's mirror reflection is a Dirac and is returned separately by
:meth:`PaintBRDF.specular_reflectance` (its weight, the Fresnel reflectance, in the
mirror direction ``(-wi_x, -wi_y, wi_z)``).

The BRDF is the sum of four terms (all reciprocal, f(wi, wo) = f(wo, wi)):

1. **coat specular** — Fresnel reflection at the air/coat interface; with roughness
   α > 0 the GGX microfacet lobe f = D G F / (4 μi μo) (Walter et al. 2007) with
   separable Smith shadowing.
2. **flakes (single scattering)** — light refracted into the coat (Snell, Fresnel
   transmission T(θ) = 1 − E_s(θ)) is mirrored by one flake of normal m = h' (the
   internal half vector) and refracted out. For flakes of projected-area optical depth
   τ spread uniformly in depth, with normal density p(m) per sr and mean projected area
   a(u) = ∫ p(m)|u·m| dω_m,

       f_flake = T_i T_o / n² · τ p(h') R_flake(i'·h') / (4 μi' μo')
                 · (1 − exp(−τ_e S)) / (τ_e S),     S = a(i')/μi' + a(o')/μo',

   the single-scattering solution of a slab of oriented mirrors (derived as in
   Chandrasekhar's single-scattering slab, Ershov et al. 2001 for flakes). Semi-transparent
   (interference) flakes let light through unscattered: τ_e a(u)/μ becomes τ a(μ)(1 − T̄(μ, λ))/μ,
   T̄(μ) their transmission averaged over the normals a ray along u meets (issue 18: with the
   hemispherical mean T̄ for every direction a TiO2/mica paint was 0.04 too bright against the
   photon tracer of tests/appearance/test_brdf_montecarlo.py). The discrete flakes
   (:func:`flake_list_reflection`), the plate renderer's glints and the sparkle prediction dim
   each flake by the flakes above it with the same extinction per direction
   (``_Tables.optical_path`` / ``ext_tab``).
3. **diffuse base** — the base reflects diffusely (Lambertian inside the binder), seen
   through the flakes (transmission t(u) = exp(−τ_e a(u)/μ)) and the coat, with the
   internal reflections at the coat/air interface summed as a geometric series:

       f_base = T_i T_o / (π n²) · ρ t(i') t(o') / (1 − ρ r_t),
       r_t = 2∫ t(μ')² R_int(μ') μ' dμ'   (R_int = 1 beyond the critical angle).

   With no flakes this is the Williams–Clapper (1953) / Saunderson (1942) result.
4. **multiple scattering** — everything the single-scattering terms miss (flake–flake
   and flake–base interreflections, flake light trapped by total internal reflection)
   enters as a diffuse lobe built so that a **lossless** paint (R_flake + T_flake = 1,
   ρ = 1) reflects exactly all the light (Kulla & Conty 2017, after Kelemen &
   Szirmay-Kalos 2001):

       f_ms = (1 − E⁰(θi))(1 − E⁰(θo)) / (π (1 − Ē⁰)) · F_ms,
       F_ms = F̄² Ē⁰ / (1 − F̄ (1 − Ē⁰)),

   where E⁰ is the directional albedo of terms 1–3 for the lossless paint, Ē⁰ its
   cosine-weighted hemispherical mean, and F̄ the mean per-event albedo (actual over
   lossless subsurface albedo).

With these, the white-furnace test holds exactly for lossless layers, the directional
albedo never exceeds 1, and without flakes and pigment the BRDF is the Fresnel
reflection of a clear dielectric.

For renderers
-------------
``f = paint(wavelength_nm, wi, wo)``: ``wi``/``wo`` unit vectors ``(..., 3)``, z = surface
normal, both pointing away from the surface; result ``(..., L)`` in 1/sr (no cos factor);
~10^7–10^8 (pair × wavelength) evaluations per second on 2 cores (Numba kernel, see
``benchmarks/bench_brdf.py``); ``dtype=np.float32`` to halve memory;
``below_surface="zero"`` to get 0 rather than an error for directions under the horizon.
Add the smooth coat's mirror Dirac ``paint.specular_reflectance(wavelength_nm, wi)``
(weight in the direction ``(-wi_x, -wi_y, wi_z)``). ``components=("flakes",)`` etc.
select terms — e.g. render the discrete flakes of a
:class:`~nmmm.appearance.flakes.FlakeList` (:func:`flake_list_reflection`: per-flake
mirror direction and spectral power) on top of ``components=("specular", "base",
"multiple")`` to get sparkle without double counting the smooth flake lobe.
``paint.albedo(wavelength_nm, wi)`` is the directional–hemispherical reflectance.

Modules (one per concept; every public name is importable from this package)
-----------------------------------------------------------------------------
- :mod:`~nmmm.appearance.brdf.clear_coat` — :class:`ClearCoat`, the GGX lobe (term 1).
- :mod:`~nmmm.appearance.brdf.paint_brdf` — :class:`PaintBRDF`, :data:`COMPONENTS`.
- :mod:`~nmmm.appearance.brdf.tables` — per-wavelength-grid tables and the NumPy path;
  :mod:`~nmmm.appearance.brdf.fused_kernel` — the Numba path;
  :mod:`~nmmm.appearance.brdf.interpolation` — the angle grids.
- :mod:`~nmmm.appearance.brdf.flake_lobe` — the flakes' single-scattering albedo (term 2).
- :mod:`~nmmm.appearance.brdf.multiple_scattering` — F_ms by adding–doubling (term 4);
  :mod:`~nmmm.appearance.brdf.ms_azimuth` — its azimuthal Fourier modes.
- :mod:`~nmmm.appearance.brdf.spectral_inputs` — the base reflectance ρ(λ) on a grid.
- :mod:`~nmmm.appearance.brdf.coat_medium` — :class:`CoatMedium`, pigments between and above
  the flakes (μa, μs, g per nm, coat thickness); :mod:`~nmmm.appearance.brdf.effect_tables`
  — the paint with that medium (radiative transfer in the coat, its own kernel);
  :mod:`~nmmm.appearance.brdf.coat_transport` — adding–doubling of the pigmented coat with
  its flake band.
- :mod:`~nmmm.appearance.brdf.builders` — paints by family.
- :mod:`~nmmm.appearance.brdf.discrete_flakes` — discrete flakes ↔ the statistical lobe.
- :mod:`~nmmm.appearance.brdf.table_export` — Rusinkiewicz tables for renderers.

Public objects
--------------
- :class:`ClearCoat`, :class:`PaintBRDF`, :class:`CoatMedium` (``PaintBRDF(..., medium=)``:
  pigments in the basecoat around the flakes, ``FlakeLayer.depth_range`` their band)
- :func:`clear_dielectric`, :func:`opaque_paint`, :func:`metallic_paint`,
  :func:`interference_paint`, :func:`grey_metallic_paint`
- :func:`body_reflectance_from_film`, :func:`opaque_paint_from_film` — the base from a
  :class:`nmmm.layers.paint.PaintFilm` (Mie + Kubelka–Munk, no surface correction)
- :func:`ggx_distribution`, :func:`smith_g1_ggx`
- :func:`flake_list_reflection`, :func:`binned_flake_brdf` — the discrete flakes'
  reflection, and the BRDF estimated from them on angular bins (statistical = mean of the
  discrete flakes as their number grows).
- :func:`rusinkiewicz_to_directions`, :func:`brdf_table`, :func:`write_brdf_table` —
  export over (θ_h, θ_d, λ) for renderers.

Limitations
-----------
Depolarised (unpolarised Fresnel at every interface); non-absorbing clear coat (absorption
and scattering of the basecoat's binder and pigments go in a :class:`CoatMedium`); the
refraction geometry uses the coat index averaged over the wavelength grid (Fresnel
factors use n(λ)); roughness of the coat only shapes its own specular lobe (light
enters and leaves through the mean plane); flake edges and diffraction are neglected
(flakes ≫ λ).

Notes
-----
Checked against an independent photon tracer of the same model
(``tests/appearance/test_brdf_montecarlo.py``: Al flakes, σ = 12°, ρ = 0.3, τ = 1 and 2,
450–650 nm). The single-scattering terms agree to < 0.002 and, since F_ms comes from
adding–doubling of the flake layer, the directional albedo to ≤ 0.004 at 0–75°
incidence (the earlier single-scattering bounce model overestimated it by 0.02 at τ = 1
and 0.11 at τ = 2). The *angular shape* of the multiple-scattering lobe: the separable
(1 − E⁰(θi))(1 − E⁰(θo)) is its azimuthal mean; its Fourier modes m = 1–6 in the azimuth
from the mirror direction (:mod:`~nmmm.appearance.brdf.ms_azimuth`, adding–doubling per
mode) make it brighter towards the specular side as the traced light is: at θi = 45°,
θo = 60–80°, the bin averages agree with the tracer to ≤ 4 % for |φo| < 60° and > 120°
(without the modes they were 9–13 % too low and 46–86 % too high).

References
----------
- M. Born, E. Wolf, *Principles of Optics*, 7th ed. (1999) §1.5 — Fresnel formulae.
- J. L. Saunderson, J. Opt. Soc. Am. 32 (1942) 727 — interface correction.
- F. R. Williams, F. R. Clapper, J. Opt. Soc. Am. 43 (1953) 595 — multiple internal
  reflections in photographic materials (the 1/n² and 1/(1 − ρ r_i) factors).
- B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet models for refraction
  through rough surfaces", EGSR 2007 — GGX distribution, Smith G1.
- S. Ershov, K. Kolchin, K. Myszkowski, Computer Graphics Forum 20(3) (2001) 227 —
  flakes as oriented mirrors in a paint layer.
- S. Chandrasekhar, *Radiative Transfer* (1960) — single scattering from a slab.
- C. Kelemen, L. Szirmay-Kalos, Eurographics 2001 short papers — energy-compensated
  coupled specular/diffuse BRDF.
- C. Kulla, A. Conty, "Revisiting physically based shading at Imageworks", SIGGRAPH
  2017 course — multiple-scattering compensation lobe F_ms.
- S. Rusinkiewicz, "A new change of variables for efficient BRDF representation",
  EGWR 1998 — (θ_h, θ_d, φ_d) coordinates.
- W. Matusik, H. Pfister, M. Brand, L. McMillan, ACM TOG 22(3) (2003) 759 — MERL
  tables (θ_h sampled as the square of a uniform variable).
"""

from nmmm.appearance.brdf.builders import (
    body_reflectance_from_film,
    clear_dielectric,
    grey_metallic_paint,
    interference_paint,
    metallic_paint,
    opaque_paint,
    opaque_paint_from_film,
)
from nmmm.appearance.brdf.clear_coat import ClearCoat, ggx_distribution, smith_g1_ggx
from nmmm.appearance.brdf.coat_medium import CoatMedium
from nmmm.appearance.brdf.discrete_flakes import binned_flake_brdf, flake_list_reflection
from nmmm.appearance.brdf.paint_brdf import COMPONENTS, PaintBRDF
from nmmm.appearance.brdf.table_export import brdf_table, rusinkiewicz_to_directions, write_brdf_table

__all__ = [
    "ClearCoat",
    "CoatMedium",
    "PaintBRDF",
    "clear_dielectric",
    "opaque_paint",
    "metallic_paint",
    "interference_paint",
    "grey_metallic_paint",
    "body_reflectance_from_film",
    "opaque_paint_from_film",
    "ggx_distribution",
    "smith_g1_ggx",
    "flake_list_reflection",
    "binned_flake_brdf",
    "rusinkiewicz_to_directions",
    "brdf_table",
    "write_brdf_table",
    "COMPONENTS",
]
