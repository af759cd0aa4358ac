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
   Chandrasekhar's single-scattering slab, Ershov et al. 2001 for flakes). τ_e = τ (1 − T̄)
   lets light through semi-transparent (interference) flakes.
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

Public objects
--------------
- :class:`ClearCoat`, :class:`PaintBRDF`
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
Depolarised (unpolarised Fresnel at every interface); non-absorbing coat and binder; the
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
and 0.11 at τ = 2). The *angular shape* of the multiple-scattering lobe is approximate:
(1 − E⁰(θi))(1 − E⁰(θo)) has no azimuth dependence, whereas the traced multiply scattered
light is brighter towards the specular side: at θi = 45°, θo = 60–80°, the bin averages
are 9–13 % too low for |φo| < 60° and 46 % (τ = 1) to 86 % (τ = 2) too high for
|φo| > 120° (a small absolute error there, ~0.01–0.02 1/sr); within 20° of the normal
they agree to < 10 %.

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

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from nmmm.appearance.flakes import (
    FlakeLayer,
    FlakeList,
    TiltDistribution,
    aluminium_flakes,
    check_directions,
    fresnel_unpolarized,
    gaussian_tilt,
    mica_pigment,
    refract_in,
    refract_out,
)
from nmmm.errors import InvalidInputError, OutOfRangeError
from nmmm.spectra import as_wavelength_nm, check_finite

__all__ = [
    "ClearCoat",
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

#: the names of the BRDF terms, for ``evaluate(..., components=...)``
COMPONENTS = ("specular", "flakes", "base", "multiple")

_NT = 181  # angle nodes of the 1-D tables (0.5 deg)
_NA = 46  # incidence nodes of the albedo tables (2 deg)
_CHUNK = 16384


# --------------------------------------------------------------------------------------
# microfacet helpers


def ggx_distribution(cos_h, alpha):
    """GGX / Trowbridge–Reitz normal distribution D(h) per sr (Walter et al. 2007, eq. 33),
    normalised so that ∫ D(h) cos θ_h dω_h = 1."""
    c2 = np.asarray(cos_h, float) ** 2
    a2 = alpha * alpha
    d = c2 * (a2 - 1.0) + 1.0
    return np.where(c2 > 0, a2 / (np.pi * d * d), 0.0)


def smith_g1_ggx(cos_v, alpha):
    """Smith masking G1 for GGX (Walter et al. 2007, eq. 34)."""
    c = np.clip(np.asarray(cos_v, float), 1e-12, 1.0)
    t2 = (1.0 - c * c) / (c * c)
    return 2.0 / (1.0 + np.sqrt(1.0 + alpha * alpha * t2))


def _lerp_table_np(table, theta_deg, step_deg):
    x = np.clip(theta_deg / step_deg, 0.0, table.shape[0] - 1.000001)
    i = x.astype(np.intp)
    f = (x - i)[:, None]
    return table[i] * (1.0 - f) + table[i + 1] * f


def _lerp_table_loop(table, theta_deg, step_deg, out):
    n = table.shape[0]
    for p in range(theta_deg.shape[0]):
        x = min(max(theta_deg[p] / step_deg, 0.0), n - 1.000001)
        i = int(x)
        f = x - i
        for l in range(table.shape[1]):
            out[p, l] = table[i, l] * (1.0 - f) + table[i + 1, l] * f


def _lerp_table(table, theta_deg, step_deg):
    """Linear interpolation of ``table`` (NT, L) at angles ``theta_deg`` (P,) on a uniform
    grid of step ``step_deg`` -> (P, L)."""
    theta_deg = np.ascontiguousarray(theta_deg, dtype=float).ravel()
    if _lerp_nb is None or theta_deg.size * table.shape[1] < 4096:
        return _lerp_table_np(table, theta_deg, step_deg)
    out = np.empty((theta_deg.size, table.shape[1]))
    _lerp_nb(np.ascontiguousarray(table, dtype=float), theta_deg, float(step_deg), out)
    return out


def _lerp1(table, theta_deg, step_deg):
    x = np.clip(theta_deg / step_deg, 0.0, table.shape[0] - 1.000001)
    i = x.astype(np.intp)
    f = x - i
    return table[i] * (1.0 - f) + table[i + 1] * f


def _deg(mu):
    return np.degrees(np.arccos(np.clip(mu, 0.0, 1.0)))


def _phi_mean(x):
    """(1 − exp(−x))/x, 1 at x = 0."""
    x = np.asarray(x, float)
    small = x < 1e-8
    xs = np.where(small, 1.0, x)
    return np.where(small, 1.0 - 0.5 * x, -np.expm1(-xs) / xs)


# --------------------------------------------------------------------------------------
# spectral inputs


def _spectral_values(value, w, name):
    """A reflectance-like spectral input on the grid ``w``: scalar, callable of the
    wavelength (nm), ``(wavelength_nm, values)`` pair, an array already on ``w``, or an
    object with ``wavelength_nm`` and ``values``/``R`` attributes. Must lie in [0, 1]."""
    if value is None:
        v = np.zeros_like(w)
    elif callable(value) and not hasattr(value, "wavelength_nm"):
        v = np.asarray(value(w), float)
    elif hasattr(value, "wavelength_nm") and (hasattr(value, "values") or hasattr(value, "R")):
        wn = np.asarray(value.wavelength_nm, float)
        vals = np.asarray(getattr(value, "values", None) if hasattr(value, "values") else value.R, float)
        v = _interp_checked(wn, vals, w, name)
    elif isinstance(value, (tuple, list)) and len(value) == 2 and np.ndim(value[0]) == 1:
        v = _interp_checked(np.asarray(value[0], float), np.asarray(value[1], float), w, name)
    else:
        v = np.asarray(value, float)
        if v.ndim == 0:
            v = np.full_like(w, float(v))
        elif v.shape != w.shape:
            raise InvalidInputError(
                f"{name} has shape {v.shape} but the wavelength grid has {w.shape}; pass a scalar, a "
                "function of wavelength_nm, or a (wavelength_nm, values) pair"
            )
    v = check_finite(v, name).astype(float)
    if np.any((v < 0) | (v > 1)):
        raise InvalidInputError(f"{name} must lie in [0, 1]; got values in [{v.min():.4g}, {v.max():.4g}]")
    return np.broadcast_to(v, w.shape).astype(float)


def _interp_checked(wn, vals, w, name):
    if wn.ndim != 1 or vals.shape[-1] != wn.size:
        raise InvalidInputError(f"{name}: wavelength_nm and values must have the same length")
    if w.min() < wn.min() - 1e-9 or w.max() > wn.max() + 1e-9:
        raise OutOfRangeError(
            f"{name} is given on {wn.min():g}–{wn.max():g} nm but asked on {w.min():g}–{w.max():g} nm; "
            "give it on a grid covering the evaluation wavelengths"
        )
    return np.interp(w, wn, vals)


# --------------------------------------------------------------------------------------
# the model


@dataclass(frozen=True)
class ClearCoat:
    """The clear coat: a non-absorbing dielectric (a Material or a constant index) and
    the GGX roughness α of its top surface (0: optically smooth, a mirror Dirac)."""

    material: object = 1.5
    roughness: float = 0.0

    def __post_init__(self):
        a = float(check_finite(self.roughness, "roughness"))
        if not 0 <= a <= 1:
            raise InvalidInputError(f"coat roughness (GGX alpha) must lie in [0, 1], got {a!r}")
        object.__setattr__(self, "roughness", a)

    def index(self, wavelength_nm) -> np.ndarray:
        """Real refractive index n(λ) of the coat (k must be negligible)."""
        from nmmm.materials import as_material

        nk = np.asarray(as_material(self.material).nk(wavelength_nm), complex)
        if np.any(nk.imag > 1e-3):
            raise InvalidInputError(
                f"the clear coat absorbs (k up to {nk.imag.max():.3g}); PaintBRDF models a non-absorbing "
                "coat: put the absorption in the base reflectance instead"
            )
        if np.any(nk.real <= 1.0):
            raise InvalidInputError("the clear coat index must be > 1")
        if np.any(nk.real > 4.0):
            raise InvalidInputError(
                f"the clear coat index reaches {nk.real.max():.4g}; a clear coat or binder is a dielectric "
                "with n of about 1.3-2 (at most ~3): check the material's units (e.g. Cauchy B is in µm²)"
            )
        return nk.real


@dataclass(frozen=True, repr=False)
class PaintBRDF:
    """Spectral BRDF of a clear-coated paint (see the module docstring for the model).

    Parameters
    ----------
    coat : ClearCoat
        Index and roughness of the clear coat (shared with the binder).
    body_reflectance : scalar, callable, (wavelength_nm, values) or array on the grid
        Internal diffuse reflectance ρ(λ) ∈ [0, 1] of the pigmented base under the
        binder (no air-interface correction). 0: black or absent base.
    flakes : FlakeLayer or None
        Flake optics, tilt distribution and optical depth; None for a solid paint.
    name : str
    """

    coat: ClearCoat = field(default_factory=ClearCoat)
    body_reflectance: object = 0.0
    flakes: FlakeLayer | None = None
    name: str = "paint"
    _cache: dict = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self):
        if not isinstance(self.coat, ClearCoat):
            raise InvalidInputError("coat must be a ClearCoat")
        if self.flakes is not None and not isinstance(self.flakes, FlakeLayer):
            raise InvalidInputError("flakes must be a FlakeLayer or None")

    def __repr__(self):
        fl = "no flakes" if self.flakes is None else f"flakes tau={self.flakes.optical_depth:.3g} ({self.flakes.tilt.name})"
        return f"<PaintBRDF '{self.name}': coat alpha={self.coat.roughness:g}, {fl}>"

    # -- tables ------------------------------------------------------------------------
    def prepare(self, wavelength_nm) -> "_Tables":
        """Build (and cache) the tables for a wavelength grid (done automatically)."""
        w = as_wavelength_nm(wavelength_nm).ravel()
        key = w.tobytes()
        tab = self._cache.get(key)
        if tab is None:
            if len(self._cache) > 8:
                self._cache.clear()
            tab = _Tables(self, w)
            self._cache[key] = tab
        return tab

    # -- evaluation --------------------------------------------------------------------
    def evaluate(self, wavelength_nm, wi, wo, components=COMPONENTS, dtype=np.float64,
                 method: str = "numba", below_surface: str = "raise") -> np.ndarray:
        """f(λ, ωi, ωo) in 1/sr.

        ``wi``, ``wo``: unit vectors ``(..., 3)`` (broadcast together), z >= 0; a
        direction below the surface raises :class:`InvalidInputError`. Returns
        ``broadcast_shape + (n_wavelengths,)``. ``components`` selects terms among
        ``COMPONENTS = ("specular", "flakes", "base", "multiple")``. The Dirac of a smooth
        coat is not included (see :meth:`specular_reflectance`). ``method``: "numba" (a
        fused parallel kernel, default) or "numpy" (chunked array code, same equations).
        ``dtype=np.float32`` halves the memory of large evaluations.
        ``below_surface="zero"`` returns 0 for pairs with a direction below the surface
        instead of raising (for renderers whose samples may leave the hemisphere).
        """
        if method not in ("numba", "numpy"):
            raise InvalidInputError(f"method must be 'numba' or 'numpy', got {method!r}")
        if below_surface not in ("raise", "zero"):
            raise InvalidInputError(f"below_surface must be 'raise' or 'zero', got {below_surface!r}")
        tab = self.prepare(wavelength_nm)
        comps = _check_components(components)
        below = None
        if below_surface == "zero":
            wi = np.array(check_finite(wi, "wi"), dtype=float)
            wo = np.array(check_finite(wo, "wo"), dtype=float)
            shape = np.broadcast_shapes(wi.shape, wo.shape)
            wi, wo = np.broadcast_to(wi, shape).copy(), np.broadcast_to(wo, shape).copy()
            below = (wi[..., 2] < 0) | (wo[..., 2] < 0)
            wi[below] = (0.0, 0.0, 1.0)
            wo[below] = (0.0, 0.0, 1.0)
            below = below.reshape(-1)
        wi = check_directions(wi, "wi")
        wo = check_directions(wo, "wo")
        shape = np.broadcast_shapes(wi.shape, wo.shape)[:-1]
        wi = np.broadcast_to(wi, shape + (3,)).reshape(-1, 3)
        wo = np.broadcast_to(wo, shape + (3,)).reshape(-1, 3)
        out = np.empty((wi.shape[0], tab.L), dtype=dtype)
        if method == "numba" and _nb is not None:
            tab.evaluate_fast(wi, wo, comps, out)
        else:
            for s in range(0, wi.shape[0], _CHUNK):
                out[s:s + _CHUNK] = tab.evaluate(wi[s:s + _CHUNK], wo[s:s + _CHUNK], comps)
        if below is not None and below.any():
            out[below] = 0.0
        return out.reshape(shape + (tab.L,))

    __call__ = evaluate

    def specular_reflectance(self, wavelength_nm, wi) -> np.ndarray:
        """Weight of the mirror Dirac of a smooth coat (its Fresnel reflectance) for
        incidence ``wi`` (..., 3) -> (..., L); zeros for a rough coat (whose specular
        lobe is part of :meth:`evaluate`)."""
        tab = self.prepare(wavelength_nm)
        wi = check_directions(wi, "wi")
        shape = wi.shape[:-1]
        th = _deg(wi.reshape(-1, 3)[:, 2])
        if self.coat.roughness > 0:
            return np.zeros(shape + (tab.L,))
        return _lerp_table(tab.Fs, th, tab.step).reshape(shape + (tab.L,))

    def albedo(self, wavelength_nm, wi) -> np.ndarray:
        """Directional–hemispherical reflectance (all terms, Dirac included) for
        incidence ``wi`` (..., 3) -> (..., L), from the model's albedo tables."""
        tab = self.prepare(wavelength_nm)
        wi = check_directions(wi, "wi")
        shape = wi.shape[:-1]
        th = _deg(wi.reshape(-1, 3)[:, 2])
        a = _lerp_table(tab.E1, th, tab.astep) + _lerp_table(tab.Dms, th, tab.astep) * tab.Fms
        return a.reshape(shape + (tab.L,))

    def lossless_albedo(self, wavelength_nm, wi) -> np.ndarray:
        """Directional albedo of the same paint made lossless (flake absorption → reflection,
        ρ = 1): 1 by construction; exposed for checks."""
        tab = self.prepare(wavelength_nm)
        wi = check_directions(wi, "wi")
        th = _deg(wi.reshape(-1, 3)[:, 2])
        a = _lerp_table(tab.E10, th, tab.astep) + _lerp_table(tab.Dms, th, tab.astep)
        return a.reshape(wi.shape[:-1] + (tab.L,))

    def bin_average(self, wavelength_nm, wi, theta_edges_deg, phi_edges_deg, components=COMPONENTS,
                    n_quad: int = 8) -> np.ndarray:
        """Cosine-weighted mean of the BRDF over angular bins of outgoing directions
        (θ edges × φ edges, degrees): ∫_bin f cos θ dω / ∫_bin cos θ dω ->
        (nθ, nφ, L). Gauss–Legendre with ``n_quad``² nodes per bin."""
        te = np.radians(np.asarray(theta_edges_deg, float))
        pe = np.radians(np.asarray(phi_edges_deg, float))
        x, wx = np.polynomial.legendre.leggauss(n_quad)
        tl, th_ = te[:-1, None], te[1:, None]
        tq = 0.5 * (th_ - tl) * (x + 1) + tl  # (nt, q)
        wt = 0.5 * (th_ - tl) * wx
        pl, ph = pe[:-1, None], pe[1:, None]
        pq = 0.5 * (ph - pl) * (x + 1) + pl
        wp = 0.5 * (ph - pl) * wx
        T = tq[:, None, :, None]
        P = pq[None, :, None, :]
        dirs = np.stack(np.broadcast_arrays(np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)), axis=-1)
        f = self.evaluate(wavelength_nm, np.asarray(wi, float), dirs, components)
        wgt = (wt * np.sin(tq) * np.cos(tq))[:, None, :, None] * wp[None, :, None, :]
        num = np.einsum("abij,abijl->abl", wgt, f)
        den = wgt.sum(axis=(2, 3))
        return num / den[..., None]

    # -- derived -----------------------------------------------------------------------
    def with_(self, **changes) -> "PaintBRDF":
        """A copy with some fields changed (the table cache is not shared)."""
        from dataclasses import replace

        return replace(self, _cache={}, **changes)


def _check_components(components):
    if isinstance(components, str):
        components = (components,)
    comps = tuple(components)
    bad = [c for c in comps if c not in COMPONENTS]
    if bad:
        raise InvalidInputError(f"unknown BRDF component(s) {bad}; choose among {COMPONENTS}")
    return frozenset(comps)


class _Tables:
    """Per-wavelength-grid tables of a PaintBRDF (angles on uniform grids)."""

    def __init__(self, paint: PaintBRDF, w: np.ndarray):
        self.w = w
        self.L = w.size
        coat = paint.coat
        n_l = coat.index(w)
        self.n = float(np.mean(n_l))  # geometry index
        self.n2 = self.n * self.n
        self.alpha = coat.roughness
        self.step = 90.0 / (_NT - 1)
        th = np.linspace(0.0, 90.0, _NT)
        mu = np.cos(np.radians(th))
        # coat Fresnel (external incidence), (NT, L)
        self.Fs = fresnel_unpolarized(mu[:, None], 1.0, n_l[None, :])
        self.Fs[-1] = 1.0
        # specular albedo E_s and coat transmission T = 1 - E_s
        if self.alpha > 0:  # on a 1-degree grid, interpolated (smooth in θ)
            th_c = np.linspace(0.0, 90.0, _NA)
            es_c = self._ggx_albedo(np.cos(np.radians(th_c)))
            self.Es = np.stack([np.interp(th, th_c, es_c[:, j]) for j in range(self.L)], axis=-1)
        else:
            self.Es = self.Fs.copy()
        self.Tc = np.clip(1.0 - self.Es, 0.0, 1.0)
        self.rho = _spectral_values(paint.body_reflectance, w, "body_reflectance")
        # flakes
        fl = paint.flakes
        self.has_flakes = fl is not None and fl.optical_depth > 0
        if self.has_flakes:
            self.tau = fl.optical_depth
            self.tilt = fl.tilt
            c_loc = np.clip(mu, 1e-6, 1.0)
            R, T = fl.optics.rt(c_loc, w, self.n)
            self.Rf = np.asarray(R, float)  # (NT, L) over the local angle in the binder
            Tf = np.asarray(T, float)
            # lossless reference: absorption turned into reflection
            self.Rf0 = np.clip(1.0 - Tf, 0.0, 1.0)
            tbar = _hemi_mean(Tf, mu)  # cosine-weighted mean flake transmittance
            self.tau_e = self.tau * np.clip(1.0 - tbar, 0.0, 1.0)  # (L,)
            self.tau_e_const = bool(np.ptp(self.tau_e) <= 1e-12 * max(1.0, self.tau))
            self.a_tab = np.asarray(self.tilt.projected_mean(mu), float)  # over internal angle
        else:
            self.tau = 0.0
            self.tau_e = np.zeros(self.L)
            self.tau_e_const = True
        self._albedo_tables()

    # ------------------------------------------------------------------------------
    def _ggx_albedo(self, mu_nodes, n_u=64, n_phi=64):
        a = self.alpha
        x, wx = np.polynomial.legendre.leggauss(n_u)
        u = 0.5 * (x + 1)
        wu = 0.5 * wx
        t2 = a * a * u / (1 - u)
        ch = 1 / np.sqrt(1 + t2)
        sh = np.sqrt(1 - ch * ch)
        ph = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
        H = np.stack(np.broadcast_arrays(sh[:, None] * np.cos(ph), sh[:, None] * np.sin(ph), ch[:, None]), -1).reshape(-1, 3)
        W = np.broadcast_to(wu[:, None] / n_phi, (n_u, n_phi)).reshape(-1)
        out = np.empty((mu_nodes.size, self.L))
        for k, m in enumerate(mu_nodes):
            m = max(m, 1e-4)
            wi = np.array([np.sqrt(1 - m * m), 0.0, m])
            ih = H @ wi
            oz = 2 * ih * H[:, 2] - m
            ok = (ih > 0) & (oz > 0)
            g = smith_g1_ggx(m, a) * smith_g1_ggx(np.where(ok, oz, 1.0), a)
            F = _lerp_table(self.Fs, _deg(ih), self.step)
            wt = np.where(ok, W * g * ih / (m * H[:, 2]), 0.0)
            out[k] = wt @ F
        return out

    def _t(self, a_over_mu):
        """Transmission through the flake layer exp(−τ_e a/μ): (P,) -> (P, L)."""
        return np.exp(-np.outer(a_over_mu, self.tau_e))

    def _albedo_tables(self):
        """E1 (single-scattering albedo), E10 (same, lossless), multiple-scattering lobe."""
        n, L = self.n, self.L
        self.astep = 90.0 / (_NA - 1)
        tha = np.linspace(0.0, 90.0, _NA)
        mua = np.cos(np.radians(tha))
        # external cosine grid for hemispherical integrals (Gauss–Legendre in μ)
        xg, wg = np.polynomial.legendre.leggauss(128)
        mu_e = 0.5 * (xg + 1)
        w_e = 0.5 * wg
        th_e = _deg(mu_e)
        T_e = _lerp_table(self.Tc, th_e, self.step)  # (G, L)
        Es_e = _lerp_table(self.Es, th_e, self.step)
        self.Es_bar = 2 * (w_e * mu_e) @ Es_e  # (L,)
        # internal cosines corresponding to mu_e (Snell), and those beyond the critical angle
        mu_i_e = np.sqrt(1 - (1 - mu_e ** 2) / (n * n))
        mu_c = np.sqrt(1 - 1 / (n * n))
        xi = 0.5 * (xg + 1) * mu_c
        wi_ = 0.5 * wg * mu_c
        if self.has_flakes:
            a_mie = _lerp1(self.a_tab, _deg(mu_i_e), self.step) / mu_i_e
            a_tir = _lerp1(self.a_tab, _deg(xi), self.step) / np.maximum(xi, 1e-12)
            t_e = self._t(a_mie)
            t_tir = self._t(a_tir)
        else:
            t_e = np.ones((mu_e.size, L))
            t_tir = np.ones((xi.size, L))
        # r_t = 2∫_0^μc t² μ' dμ' + (2/n²)∫ t² E_s μ dμ
        self.r_t = 2 * (wi_ * xi) @ (t_tir ** 2) + 2 / (n * n) * (w_e * mu_e) @ (t_e ** 2 * Es_e)
        esc = 2 / (n * n) * (w_e * mu_e) @ (T_e * t_e)  # ∫ T_o t_o cos dω_o / (π n²) ... times π
        # per-incidence pieces
        Ti = _lerp_table(self.Tc, tha, self.step)  # (NA, L)
        Esi = _lerp_table(self.Es, tha, self.step)
        mu_ii = np.sqrt(1 - (1 - mua ** 2) / (n * n))
        if self.has_flakes:
            t_i = self._t(_lerp1(self.a_tab, _deg(mu_ii), self.step) / mu_ii)
        else:
            t_i = np.ones((_NA, L))
        rho = self.rho
        with np.errstate(divide="ignore", invalid="ignore"):
            base = Ti * t_i * (rho / (1 - rho * self.r_t)) * esc
            base0 = Ti * t_i * (1.0 / (1 - self.r_t)) * esc
        base0 = np.where(np.isfinite(base0), base0, Ti)  # r_t = 1 only for a fully trapping coat
        fl, fl0 = self._flake_albedo(mua)
        self.E1 = Esi + Ti * fl + base
        self.E10 = Esi + Ti * fl0 + base0
        self.E1[-1] = Esi[-1]
        self.E10[-1] = Esi[-1]
        # multiple-scattering compensation (Kulla & Conty 2017)
        self.Dms = np.clip(1.0 - self.E10, 0.0, 1.0)
        E0_bar = 2 * (w_e * mu_e) @ _lerp_table(self.E10, th_e, self.astep)
        sub = 2 * (w_e * mu_e) @ (_lerp_table(self.E1 - self._es_at(tha), th_e, self.astep))
        sub0 = 2 * (w_e * mu_e) @ (_lerp_table(self.E10 - self._es_at(tha), th_e, self.astep))
        with np.errstate(divide="ignore", invalid="ignore"):
            fbar = np.where(sub0 > 1e-12, np.clip(sub / sub0, 0, 1), 0.0)
            Fms = fbar ** 2 * E0_bar / (1 - fbar * (1 - E0_bar))
            self.Fms = np.where(np.isfinite(Fms), Fms, 0.0)
        if self.has_flakes:
            # trapped light in a flake layer escapes far less easily than Kulla–Conty's
            # "escape per cycle = Ē⁰" assumes: use the interreflection model instead
            self.Fms = self._ms_factor(sub, sub0)
        with np.errstate(divide="ignore", invalid="ignore"):
            self.Kms = np.where(1 - E0_bar > 1e-9, self.Fms / (np.pi * (1 - E0_bar)), 0.0)
        self.E0_bar = E0_bar

    def _ms_factor(self, sub, sub0, n_mu: int = 48, n_phi: int = 32, n_doublings: int = 16):
        """F_ms(λ): multiply scattered light that escapes, relative to the lossless paint.

        Azimuthally averaged (0th Fourier mode: exact for hemispherical fluxes) transport
        inside the coat, on Gauss–Legendre polar nodes. The flake layer's reflection and
        transmission matrices come from adding–doubling (van de Hulst 1980) of a thin
        sublayer whose kernel is the oriented-mirror scattering per unit optical depth,
        p(h) R(|u·h|) / (4 μ_in) into upward *and* downward directions (flake–flake paths
        included), with extinction τ_e/τ · a(μ)/μ; the Lambertian base (ρ) is added
        below, and the coat from below transmits T out of the escape cone and mirrors the
        rest back down. For diffuse light entering the coat this gives the total escaping
        fraction e(λ) (1 exactly for the lossless paint); removing the single-scattering
        escape s (``sub``: the terms 2–3 albedo averaged over diffuse incidence, per unit
        light entering) leaves the multiply scattered part, and
        F_ms = (e − s) / (1 − s⁰), so that the diffuse-incidence albedo of the model is the
        transport result and F_ms = 1 for a lossless paint (white furnace untouched).

        This replaced a bounce model keeping only single flake scattering per pass, which
        lost 20–40 % of the lossless light per bounce and overestimated F_ms for absorbing
        paints by ×1.25 (τ = 1) to ×2 (τ = 2); checked against the photon tracer of
        ``tests/appearance/test_brdf_montecarlo.py``.
        """
        n, L = self.n, self.L
        xg, wg = np.polynomial.legendre.leggauss(n_mu)
        th = 0.25 * np.pi * (xg + 1)  # internal polar angle nodes
        mu, sn = np.cos(th), np.sin(th)
        dmu = sn * 0.25 * np.pi * wg  # ∫ dμ weights
        a_mu = _lerp1(self.a_tab, np.degrees(th), self.step) / mu  # flake extinction per unit τ
        ph = (np.arange(n_phi) + 0.5) * np.pi / n_phi  # azimuth differences in [0, π), weights ×2
        uk = np.stack([sn, 0 * sn, -mu], -1)  # incoming travel directions (downward)
        G = np.zeros((2, 2, n_mu, n_mu, L))  # [up/down out][actual/lossless], (j out, k in, L)
        for q in ph:
            for s_out, sz in enumerate((1.0, -1.0)):
                uj = np.stack([sn * np.cos(q), sn * np.sin(q), sz * mu], -1)
                hv = uj[:, None, :] - uk[None, :, :]  # ∥ the mirror's normal
                hn = np.linalg.norm(hv, axis=-1)
                hn = np.where(hn > 1e-12, hn, 1.0)
                c = np.abs(np.sum(hv * uk[None, :, :], axis=-1)) / hn
                wgt = self.tilt.pdf(np.abs(hv[..., 2]) / hn) / (4 * mu[None, :]) * (dmu[:, None] * 2 * np.pi / n_phi)
                dc = _deg(c.ravel())
                G[s_out, 0] += wgt[..., None] * _lerp_table(self.Rf, dc, self.step).reshape(wgt.shape + (L,))
                G[s_out, 1] += wgt[..., None] * _lerp_table(self.Rf0, dc, self.step).reshape(wgt.shape + (L,))
        # the lossless kernel removes exactly τ_e/τ · a/μ per unit τ (corrects the quadrature)
        target = a_mu[:, None] * (self.tau_e / self.tau)[None, :]  # (k, L)
        col0 = (G[0, 1] + G[1, 1]).sum(axis=0)
        scale = np.where(col0 > 0, target / np.where(col0 > 0, col0, 1.0), 0.0)
        eye = np.eye(n_mu)
        delta = self.tau / 2.0 ** n_doublings
        mu_c = np.sqrt(1 - 1 / (n * n))
        mu_ext = np.sqrt(np.clip(1 - n * n * (1 - mu * mu), 0, 1))
        Tint = np.where(mu[:, None] > mu_c, _lerp_table(self.Tc, _deg(mu_ext), self.step), 0.0).T  # (L, K)
        d0 = Tint * (mu * dmu)[None, :]  # diffuse light entering the coat
        d0 = d0 / d0.sum(axis=1, keepdims=True)
        lamb = 2 * mu * dmu
        lamb = lamb / lamb.sum()  # Lambertian redistribution over the nodes
        escaped = []
        for v, rho in ((0, self.rho), (1, np.ones(L))):
            R = np.moveaxis(delta * G[0, v] * scale[None], -1, 0)  # (L, j, k)
            T = np.moveaxis(delta * G[1, v] * scale[None] + eye[..., None] * (1 - delta * target)[None], -1, 0)
            for _ in range(n_doublings):  # symmetric layer: R2 = R + T R (1 − R R)⁻¹ T, T2 = T (1 − R R)⁻¹ T
                M = np.linalg.solve(eye[None] - R @ R, T)
                R, T = R + T @ R @ M, T @ M
            Rb = rho[:, None, None] * np.broadcast_to(lamb[:, None], (n_mu, n_mu))[None]
            Rtot = R + T @ np.linalg.solve(eye[None] - Rb @ R, Rb @ T)  # layer over the base
            u = np.linalg.solve(eye[None] - Rtot * (1 - Tint)[:, None, :],
                                np.einsum("ljk,lk->lj", Rtot, d0)[..., None])[..., 0]
            escaped.append(np.sum(Tint * u, axis=1))
        e, e0 = escaped
        norm = np.maximum(1.0 - self.Es_bar, 1e-12)
        s, s0 = sub / norm, sub0 / norm
        with np.errstate(divide="ignore", invalid="ignore"):
            F = np.where(e0 - s0 > 1e-12, (e - s) / (e0 - s0), 0.0)
        return np.clip(F, 0.0, 1.0)

    def _es_at(self, tha):
        return _lerp_table(self.Es, tha, self.step)

    def _flake_albedo(self, mua, n_theta: int = 24, n_phi: int = 32):
        """External single-scattering flake albedo / T_i, actual and lossless, (NA, L).

        Quadrature over flake normals m (tilt θ_m, azimuth φ_m), restricted for each φ_m
        to the tilts whose mirror ray leaves the coat (θ_m < θ_b(φ_m), found by bisection),
        so that the integrand is smooth (the escape boundary is not cut by the nodes).
        """
        L = self.L
        if not self.has_flakes:
            z = np.zeros((mua.size, L))
            return z, z
        n = self.n
        mu_c = np.sqrt(1 - 1 / (n * n))
        xg, wg = np.polynomial.legendre.leggauss(n_theta)
        ph = (np.arange(n_phi) + 0.5) * np.pi / n_phi  # symmetric in φ: [0, π), weights ×2
        cph, sph = np.cos(ph), np.sin(ph)
        tsup = np.radians(self.tilt.support_deg)
        out = np.zeros((mua.size, L))
        out0 = np.zeros((mua.size, L))

        def opz(theta, ip):  # o'_z for normals at (theta (…, n_phi), ph)
            st, ct = np.sin(theta), np.cos(theta)
            c = st * cph * ip[0] + ct * ip[2]
            return 2 * c * ct - ip[2], c

        for k, mu in enumerate(mua):
            if mu <= 1e-6:
                continue
            wi = np.array([np.sqrt(1 - mu * mu), 0.0, mu])
            ip = refract_in(wi, n)
            # escape boundary per azimuth: first θ where o'_z <= μ_c (or c <= 0)
            tt = np.linspace(0, tsup, 257)[:, None] * np.ones((1, n_phi))
            oz, c = opz(tt, ip)
            bad = (oz <= mu_c) | (c <= 0)
            first = np.where(bad.any(axis=0), bad.argmax(axis=0), tt.shape[0] - 1)
            hi = tt[first, np.arange(n_phi)]
            lo = tt[np.maximum(first - 1, 0), np.arange(n_phi)]
            hasb = bad.any(axis=0)
            for _ in range(30):
                mid = 0.5 * (lo + hi)
                ozm, cm = opz(mid, ip)
                b = (ozm <= mu_c) | (cm <= 0)
                hi = np.where(b & hasb, mid, hi)
                lo = np.where(b & hasb, lo, mid)
            tb = np.where(hasb, 0.5 * (lo + hi), tsup)  # (n_phi,)
            th = 0.5 * (xg[:, None] + 1) * tb[None, :]  # (n_theta, n_phi)
            wth = 0.5 * wg[:, None] * tb[None, :]
            st, ct = np.sin(th), np.cos(th)
            m = np.stack([st * cph, st * sph, ct], axis=-1).reshape(-1, 3)
            wq = (wth * st * np.interp(np.degrees(th), self.tilt.tilt_deg, self.tilt.density)
                  * (2 * np.pi / n_phi)).reshape(-1)
            ck = m @ ip
            op = 2 * ck[:, None] * m - ip
            wok, esc = refract_out(op, n)
            ok = esc & (ck > 0) & (wq > 0)
            if not np.any(ok):
                continue
            ck, opk, wok, wk = ck[ok], op[ok], wok[ok], wq[ok]
            S = (_lerp1(self.a_tab, _deg(ip[2]), self.step) / ip[2]
                 + _lerp1(self.a_tab, _deg(opk[:, 2]), self.step) / opk[:, 2])
            phi = self.tau * _phi_mean(np.outer(S, self.tau_e))  # (K, L)
            To = _lerp_table(self.Tc, _deg(wok[:, 2]), self.step)
            g = (wk * ck / ip[2])[:, None] * phi * To
            out[k] = np.sum(g * _lerp_table(self.Rf, _deg(ck), self.step), axis=0)
            out0[k] = np.sum(g * _lerp_table(self.Rf0, _deg(ck), self.step), axis=0)
        return out, out0

    # ------------------------------------------------------------------------------
    def evaluate_fast(self, wi, wo, comps, out):
        """The fused Numba kernel (same equations as :meth:`evaluate`), writing ``out``."""
        Rf = self.Rf if self.has_flakes else np.zeros((1, 1))
        a_tab = self.a_tab if self.has_flakes else np.zeros(2)
        den = self.tilt.density if self.has_flakes else np.zeros(2)
        dstep = (self.tilt.tilt_deg[1] - self.tilt.tilt_deg[0]) if self.has_flakes else 1.0
        with np.errstate(divide="ignore", invalid="ignore"):
            kb = np.where(self.rho > 0, self.rho / (np.pi * (1 - self.rho * self.r_t)), 0.0)
        do_base = "base" in comps and bool(np.any(self.rho > 0))
        do_ms = "multiple" in comps and bool(np.any(self.Kms > 0))
        _kernel(np.ascontiguousarray(wi), np.ascontiguousarray(wo), out, self.Fs, self.Tc, Rf, a_tab, den,
                self.step, self.astep, dstep, self.n, self.alpha, self.tau if self.has_flakes else 0.0,
                np.ascontiguousarray(self.tau_e, float), kb, self.Dms, np.asarray(self.Kms, float),
                "specular" in comps, "flakes" in comps and self.has_flakes, do_base, do_ms,
                bool(self.tau_e_const))

    def evaluate(self, wi, wo, comps):
        P = wi.shape[0]
        L = self.L
        mi, mo = wi[:, 2], wo[:, 2]
        valid = (mi > 0) & (mo > 0)
        f = np.zeros((P, L))
        if not np.any(valid):
            return f
        if not np.all(valid):
            f[valid] = self.evaluate(wi[valid], wo[valid], comps)
            return f
        thi, tho = _deg(mi), _deg(mo)
        if "specular" in comps and self.alpha > 0:
            h = wi + wo
            h /= np.linalg.norm(h, axis=-1, keepdims=True)
            cd = np.sum(wi * h, axis=-1)
            D = ggx_distribution(h[:, 2], self.alpha)
            G = smith_g1_ggx(mi, self.alpha) * smith_g1_ggx(mo, self.alpha)
            F = _lerp_table(self.Fs, _deg(cd), self.step)
            f += (D * G / (4 * mi * mo))[:, None] * F
        need_sub = bool({"flakes", "base"} & comps) and (self.has_flakes or np.any(self.rho > 0))
        if need_sub:
            TT = _lerp_table(self.Tc, thi, self.step)
            TT *= _lerp_table(self.Tc, tho, self.step)
            TT /= self.n2
            ip = refract_in(wi, self.n)
            op = refract_in(wo, self.n)
            sub = np.zeros((P, L))
            if self.has_flakes:
                ai = _lerp1(self.a_tab, _deg(ip[:, 2]), self.step) / ip[:, 2]
                ao = _lerp1(self.a_tab, _deg(op[:, 2]), self.step) / op[:, 2]
            if self.has_flakes and "flakes" in comps:
                h = ip + op
                h /= np.linalg.norm(h, axis=-1, keepdims=True)
                cd = np.sum(ip * h, axis=-1)
                p = self.tilt.pdf(h[:, 2])
                g = self.tau * p / (4 * ip[:, 2] * op[:, 2])
                S = ai + ao
                if self.tau_e_const:
                    g = g * _phi_mean(S * self.tau_e[0])
                    sub += g[:, None] * _lerp_table(self.Rf, _deg(cd), self.step)
                else:
                    sub += g[:, None] * _phi_mean(np.outer(S, self.tau_e)) * _lerp_table(self.Rf, _deg(cd), self.step)
            if "base" in comps and np.any(self.rho > 0):
                kb = self.rho / (np.pi * (1 - self.rho * self.r_t))
                if self.has_flakes:
                    if self.tau_e_const:
                        sub += np.exp(-(ai + ao) * self.tau_e[0])[:, None] * kb
                    else:
                        sub += np.exp(-np.outer(ai + ao, self.tau_e)) * kb
                else:
                    sub += kb
            f += TT * sub
        if "multiple" in comps and np.any(self.Kms > 0):
            f += _lerp_table(self.Dms, thi, self.astep) * _lerp_table(self.Dms, tho, self.astep) * self.Kms
        return f


# --------------------------------------------------------------------------------------
# fused kernel (Numba): one pass over direction pairs × wavelengths, no temporaries

try:  # pragma: no cover - numba is a dependency, the fallback only guards odd installs
    import numba as _nb

    _njit = _nb.njit(parallel=True, fastmath=True, cache=True)
    _prange = _nb.prange
except ImportError:  # pragma: no cover
    _nb = None


def _table_pos_py(c, step, n_nodes):
    """Node index and fraction of the angle arccos(c) (c clipped to [0, 1]) on a table of
    ``n_nodes`` nodes ``step`` degrees apart (the last interval is closed)."""
    x = min(np.arccos(min(max(c, 0.0), 1.0)) * (180.0 / np.pi) / step, n_nodes - 1.000001)
    i = int(x)
    return i, x - i


if _nb is not None:
    _table_pos = _nb.njit(inline="always", fastmath=True, cache=True)(_table_pos_py)
else:  # pragma: no cover
    _table_pos = _table_pos_py


def _kernel_py(wi, wo, out, Fs, Tc, Rf, a_tab, den, step, astep, dstep, n, alpha, tau, tau_e, kb, Dms, Kms,
               do_spec, do_flakes, do_base, do_ms, tau_e_const):
    P = wi.shape[0]
    L = out.shape[1]
    NT = Fs.shape[0]
    NA = Dms.shape[0]
    ND = den.shape[0]
    inv_n2 = 1.0 / (n * n)
    for p in _prange(P):
        ix, iy, iz = wi[p, 0], wi[p, 1], wi[p, 2]
        ox, oy, oz = wo[p, 0], wo[p, 1], wo[p, 2]
        if iz <= 0.0 or oz <= 0.0:
            for l in range(L):
                out[p, l] = 0.0
            continue
        # external angles -> table positions
        i0, fi = _table_pos(iz, step, NT)
        o0, fo = _table_pos(oz, step, NT)
        ai0, fai = _table_pos(iz, astep, NA)
        ao0, fao = _table_pos(oz, astep, NA)
        # coat specular lobe (GGX)
        spec_w = 0.0
        d0 = 0
        fd = 0.0
        if do_spec and alpha > 0.0:
            hx, hy, hz = ix + ox, iy + oy, iz + oz
            hn = np.sqrt(hx * hx + hy * hy + hz * hz)
            hx /= hn
            hy /= hn
            hz /= hn
            cd = ix * hx + iy * hy + iz * hz
            a2 = alpha * alpha
            dd = hz * hz * (a2 - 1.0) + 1.0
            D = a2 / (np.pi * dd * dd)
            ti2 = (1.0 - iz * iz) / (iz * iz)
            to2 = (1.0 - oz * oz) / (oz * oz)
            G = 4.0 / ((1.0 + np.sqrt(1.0 + a2 * ti2)) * (1.0 + np.sqrt(1.0 + a2 * to2)))
            spec_w = D * G / (4.0 * iz * oz)
            d0, fd = _table_pos(cd, step, NT)
        # internal directions (Snell)
        ipx, ipy = ix / n, iy / n
        ipz = np.sqrt(max(1.0 - ipx * ipx - ipy * ipy, 0.0))
        opx, opy = ox / n, oy / n
        opz = np.sqrt(max(1.0 - opx * opx - opy * opy, 0.0))
        S = 0.0
        g = 0.0
        c0 = 0
        fc = 0.0
        if tau > 0.0:
            k0, fa = _table_pos(ipz, step, NT)
            a_i = a_tab[k0] * (1.0 - fa) + a_tab[k0 + 1] * fa
            k0, fa = _table_pos(opz, step, NT)
            a_o = a_tab[k0] * (1.0 - fa) + a_tab[k0 + 1] * fa
            S = a_i / ipz + a_o / opz
            if do_flakes:
                hx, hy, hz = ipx + opx, ipy + opy, ipz + opz
                hn = np.sqrt(hx * hx + hy * hy + hz * hz)
                hz /= hn
                cdl = (ipx * hx + ipy * hy) / hn + ipz * hz
                t0, ft = _table_pos(hz, dstep, ND)
                pdf = den[t0] * (1.0 - ft) + den[t0 + 1] * ft
                g = tau * pdf / (4.0 * ipz * opz)
                c0, fc = _table_pos(cdl, step, NT)
        # flakes that block no light (tau_e = const over wavelength): one exp per pair
        x0 = tau_e[0] * S
        e0 = np.exp(-x0)
        ph0 = 1.0 - 0.5 * x0 if x0 < 1e-6 else (1.0 - e0) / x0
        for l in range(L):
            val = 0.0
            if spec_w > 0.0:
                val += spec_w * (Fs[d0, l] * (1.0 - fd) + Fs[d0 + 1, l] * fd)
            sub = 0.0
            if do_flakes or do_base:
                if tau_e_const:
                    x = x0
                    e = e0
                else:
                    x = tau_e[l] * S
                    e = np.exp(-x)
                if do_flakes and g > 0.0:
                    if tau_e_const:
                        ph = ph0
                    else:
                        ph = 1.0 - 0.5 * x if x < 1e-6 else (1.0 - e) / x
                    sub += g * ph * (Rf[c0, l] * (1.0 - fc) + Rf[c0 + 1, l] * fc)
                if do_base:
                    sub += e * kb[l]
                if sub != 0.0:
                    Ti = Tc[i0, l] * (1.0 - fi) + Tc[i0 + 1, l] * fi
                    To = Tc[o0, l] * (1.0 - fo) + Tc[o0 + 1, l] * fo
                    val += Ti * To * inv_n2 * sub
            if do_ms:
                val += ((Dms[ai0, l] * (1.0 - fai) + Dms[ai0 + 1, l] * fai)
                        * (Dms[ao0, l] * (1.0 - fao) + Dms[ao0 + 1, l] * fao) * Kms[l])
            out[p, l] = val


if _nb is not None:
    _kernel = _njit(_kernel_py)
    _lerp_nb = _nb.njit(cache=True)(_lerp_table_loop)
else:  # pragma: no cover
    _prange = range
    _kernel = _kernel_py
    _lerp_nb = None


def _hemi_mean(values, mu):
    """2 ∫ v(μ) μ dμ over a table given at the (decreasing) cosines ``mu``."""
    order = np.argsort(mu)
    return 2 * np.trapezoid(values[order] * mu[order][:, None], mu[order], axis=0)


# --------------------------------------------------------------------------------------
# constructors


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
    :func:`nmmm.appearance.examples.grey_metallic_from_deposit`."""
    return metallic_paint(optical_depth=0.5, tilt=6.0, body_reflectance=0.35, name="grey metallic paint")


# --------------------------------------------------------------------------------------
# discrete flakes <-> statistical BRDF


def flake_list_reflection(paint: PaintBRDF, flakes: FlakeList, wavelength_nm, wi):
    """Reflection of light from ``wi`` by each flake of a :class:`FlakeList` under the
    paint's clear coat.

    Returns ``(wo, power, escapes)``: the external mirror directions (N, 3), the fraction
    of the irradiance on the patch that each flake sends out (N, L) — coat transmission
    in and out, flake reflectance at its local angle, projected area, and mean-field
    attenuation exp(−S τ_above) by the flakes above it (τ_above the flake area above the
    flake's depth per unit area, :meth:`FlakeList.optical_depth_above`; scaled by τ_e/τ
    for semi-transparent flakes) — and the mask of flakes whose light leaves the coat.
    Because Σ_k A_k exp(−S τ_above,k) / area → (1 − e^{−Sτ})/S whatever the depth
    distribution, the mean of the discrete flakes is the statistical flake lobe.
    The average of these contributions over many flakes is the ``"flakes"`` term of the
    statistical BRDF built from ``flakes.to_flake_layer()``.
    """
    tab = paint.prepare(wavelength_nm)
    wi = check_directions(np.asarray(wi, float).reshape(3), "wi")
    if abs(tab.n - flakes.n_binder) > 1e-6:
        raise InvalidInputError(
            f"the flake list's binder index ({flakes.n_binder}) differs from the coat's ({tab.n:.6g}); "
            "use the same medium"
        )
    n = tab.n
    ip = refract_in(wi, n)
    c = flakes.normals @ ip
    op = 2 * c[:, None] * flakes.normals - ip
    wo, esc = refract_out(op, n)
    esc = esc & (c > 0)
    Ti = _lerp_table(tab.Tc, np.atleast_1d(_deg(wi[2])), tab.step)[0]
    To = _lerp_table(tab.Tc, _deg(np.clip(wo[:, 2], 0, 1)), tab.step)
    R, _ = flakes.optics.rt(np.clip(c, 1e-6, 1), tab.w, n)
    tau_above = flakes.optical_depth_above()
    tilt = flakes.tilt
    if tilt is None:
        tilt = flakes.to_flake_layer().tilt
    if tab.has_flakes and tilt is tab.tilt:
        a_tab = tab.a_tab
    else:
        a_tab = np.asarray(tilt.projected_mean(np.cos(np.radians(np.linspace(0.0, 90.0, _NT)))), float)
    opz = np.clip(op[:, 2], 1e-6, 1)
    S = _lerp1(a_tab, np.atleast_1d(_deg(ip[2])), tab.step)[0] / ip[2] + _lerp1(a_tab, _deg(opz), tab.step) / opz
    if paint.flakes is not None:
        # τ_e/τ from the paint's tables (semi-transparent flakes)
        ratio = tab.tau_e / tab.tau if tab.tau > 0 else np.ones(tab.L)
    else:
        ratio = np.ones(tab.L)
    att = np.exp(-np.outer(S * tau_above, ratio))
    area = flakes.region_nm[0] * flakes.region_nm[1]
    power = (flakes.areas_nm2 * np.abs(c) / ip[2] / area)[:, None] * R * att * Ti * To
    power[~esc] = 0.0
    return wo, power, esc


def binned_flake_brdf(paint: PaintBRDF, flakes: FlakeList, wavelength_nm, wi, theta_edges_deg, phi_edges_deg):
    """The BRDF estimated from a discrete flake list on angular bins of outgoing
    directions: Σ (flake power in the bin) / ∫_bin cos θ dω -> (nθ, nφ, L). Compare with
    ``paint.bin_average(..., components="flakes")``."""
    wo, power, esc = flake_list_reflection(paint, flakes, wavelength_nm, wi)
    te = np.asarray(theta_edges_deg, float)
    pe = np.asarray(phi_edges_deg, float)
    th = _deg(wo[:, 2])
    ph = np.degrees(np.arctan2(wo[:, 1], wo[:, 0])) % 360.0
    it = np.searchsorted(te, th, side="right") - 1
    ip_ = np.searchsorted(pe, ph, side="right") - 1
    ok = esc & (it >= 0) & (it < te.size - 1) & (ip_ >= 0) & (ip_ < pe.size - 1)
    L = power.shape[1]
    out = np.zeros((te.size - 1, pe.size - 1, L))
    np.add.at(out, (it[ok], ip_[ok]), power[ok])
    tr = np.radians(te)
    proj = 0.5 * (np.sin(tr[1:]) ** 2 - np.sin(tr[:-1]) ** 2)  # ∫ cos θ sin θ dθ
    dphi = np.radians(np.diff(pe))
    return out / (proj[:, None] * dphi[None, :])[..., None]


# --------------------------------------------------------------------------------------
# table export


def rusinkiewicz_to_directions(theta_h_deg, theta_d_deg, phi_d_deg):
    """(θ_h, θ_d, φ_d) -> (wi, wo) unit vectors (..., 3), φ_h = 0 (isotropic BRDFs;
    Rusinkiewicz 1998). Pairs with a direction below the surface have z < 0."""
    th, td, pd = np.broadcast_arrays(*(np.radians(np.asarray(v, float)) for v in (theta_h_deg, theta_d_deg, phi_d_deg)))
    d = np.stack([np.sin(td) * np.cos(pd), np.sin(td) * np.sin(pd), np.cos(td)], axis=-1)
    dm = d * np.array([-1.0, -1.0, 1.0])
    c, s = np.cos(th)[..., None], np.sin(th)[..., None]

    def rot_y(v):  # rotate about the y (binormal) axis by θ_h
        return np.stack([c[..., 0] * v[..., 0] + s[..., 0] * v[..., 2], v[..., 1],
                         -s[..., 0] * v[..., 0] + c[..., 0] * v[..., 2]], axis=-1)

    return rot_y(d), rot_y(dm)


def brdf_table(brdf: PaintBRDF, wavelength_nm, n_theta_h: int = 90, n_theta_d: int = 90, n_phi_d: int = 36,
               reduce: str | None = "mean"):
    """Tabulate a BRDF over Rusinkiewicz coordinates for renderers.

    θ_h is sampled as 90°·(i/(n−1))² (MERL, Matusik et al. 2003) to resolve the specular
    peak, θ_d uniformly in [0, 90°), φ_d uniformly in [0, 180°) (isotropic, reciprocal
    BRDFs are symmetric in φ_d ↔ φ_d + 180°). With ``reduce="mean"`` the table is
    averaged over φ_d (the bivariate (θ_h, θ_d, λ) form), over the pairs above the
    surface; ``reduce=None`` keeps φ_d. Returns an :class:`xarray.Dataset` with
    ``brdf`` (1/sr) and, for a smooth coat, ``specular_reflectance`` (θ_d, λ): the weight
    of the mirror Dirac at θ_h = 0, θ_i = θ_d.
    """
    import xarray as xr

    w = as_wavelength_nm(wavelength_nm).ravel()
    for v, nm in ((n_theta_h, "n_theta_h"), (n_theta_d, "n_theta_d"), (n_phi_d, "n_phi_d")):
        if int(v) < 1:
            raise InvalidInputError(f"{nm} must be >= 1, got {v!r}")
    th = 90.0 * (np.arange(n_theta_h) / max(n_theta_h - 1, 1)) ** 2
    th = np.minimum(th, 89.9)
    td = np.linspace(0.0, 90.0, n_theta_d, endpoint=False)
    pd = np.linspace(0.0, 180.0, n_phi_d, endpoint=False)
    TH, TD, PD = np.meshgrid(th, td, pd, indexing="ij")
    wi, wo = rusinkiewicz_to_directions(TH, TD, PD)
    valid = (wi[..., 2] > 1e-9) & (wo[..., 2] > 1e-9)
    vals = np.full(TH.shape + (w.size,), np.nan)
    vals[valid] = brdf.evaluate(w, wi[valid], wo[valid])
    if reduce == "mean":
        cnt = valid.sum(axis=2)
        with np.errstate(invalid="ignore"):
            table = np.nansum(vals, axis=2) / np.where(cnt > 0, cnt, np.nan)[..., None]
        da = xr.DataArray(table, dims=("theta_h_deg", "theta_d_deg", "wavelength_nm"),
                          coords={"theta_h_deg": th, "theta_d_deg": td, "wavelength_nm": w})
    elif reduce is None:
        da = xr.DataArray(vals, dims=("theta_h_deg", "theta_d_deg", "phi_d_deg", "wavelength_nm"),
                          coords={"theta_h_deg": th, "theta_d_deg": td, "phi_d_deg": pd, "wavelength_nm": w})
    else:
        raise InvalidInputError(f"reduce must be 'mean' or None, got {reduce!r}")
    da.attrs.update(units="1/sr", description="spectral BRDF, Rusinkiewicz coordinates, phi_h = 0")
    ds = xr.Dataset({"brdf": da})
    if brdf.coat.roughness == 0:
        tdc = np.minimum(td, 89.9)
        wi_s = np.stack([np.sin(np.radians(tdc)), 0 * tdc, np.cos(np.radians(tdc))], -1)
        ds["specular_reflectance"] = xr.DataArray(brdf.specular_reflectance(w, wi_s), dims=("theta_d_deg", "wavelength_nm"),
                                                  attrs={"description": "weight of the mirror Dirac (Fresnel) at theta_h = 0"})
    ds.attrs.update(model=repr(brdf), generator="nmmm.appearance.brdf.brdf_table",
                    theta_h_sampling="90*(i/(n-1))**2 deg (MERL)")
    return ds


def write_brdf_table(path, brdf: PaintBRDF, wavelength_nm, **kwargs):
    """Write :func:`brdf_table` to ``path``: netCDF (``.nc``, h5netcdf engine) or CSV
    (``.csv``: columns theta_h_deg, theta_d_deg, wavelength_nm, brdf_per_sr)."""
    from pathlib import Path

    from nmmm.errors import DataFileError

    p = Path(path)
    if p.suffix not in (".nc", ".csv"):
        raise InvalidInputError(f"unknown table format '{p.suffix}'; use .nc or .csv")
    if not p.parent.is_dir():
        raise DataFileError(f"cannot write {p}: the directory {p.parent} does not exist; create it first")
    ds = brdf_table(brdf, wavelength_nm, **kwargs)
    if p.suffix == ".nc":
        ds.to_netcdf(p, engine="h5netcdf")
    else:
        df = ds["brdf"].to_dataframe(name="brdf_per_sr").reset_index()
        df.to_csv(p, index=False, float_format="%.6g")
    return p
