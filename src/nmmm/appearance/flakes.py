"""Effect-pigment flakes: orientation (tilt) distributions, flake optics, flake lists.

A metallic or interference paint holds platelets ("flakes") lying roughly parallel to the
surface, embedded in a transparent binder of index ``n_binder``. This module describes
them at the two scales the appearance needs:

- the **statistics** used by the smooth BRDF seen from afar
  (:class:`nmmm.appearance.brdf.PaintBRDF`): a :class:`TiltDistribution` of flake normals,
  the flake optics and the flake optical depth τ (projected flake area per unit area);
- the **discrete flake list** seen up close (sparkle): :class:`FlakeList`, one row per
  flake with its position, depth, normal and diameter, and a per-flake spectral
  reflectance.

Public objects
--------------
- :class:`TiltDistribution` — isotropic distribution of flake normals, a density per
  steradian, normalised over the upper hemisphere: ``gaussian_tilt(sigma_deg)``,
  ``TiltDistribution.tabulated(tilt_deg, density)``, ``TiltDistribution.from_function(f)``,
  ``TiltDistribution.from_normals(normals)`` (kernel density estimate).
- :func:`gaussian_tilt` — the usual model of flake misorientation.
- :class:`MetalFlakeOptics` — opaque metal flake (Fresnel binder → metal, e.g. aluminium).
- :class:`ThinFilmFlakeOptics` — a thin-film stack embedded in the binder (interference /
  pearlescent pigments such as TiO2-coated mica); reflectance *and* transmittance.
- :func:`mica_pigment` — TiO2 / mica / TiO2 interference flake.
- :func:`aluminium_flakes` — Al flakes (refractiveindex.info ``main/Al/Rakic``).
- :class:`FlakeLayer` — the statistical description: tilt, optics, optical depth τ;
  built from a volume fraction or an areal density.
- :class:`FlakeList` — discrete flakes; ``FlakeList.random(...)``,
  ``FlakeList.from_deposit(...)``, ``.reflectance(wavelength_nm, wi)``,
  ``.reflected_directions(wi)``, ``.to_flake_layer()``.
- :func:`fresnel_unpolarized` — unpolarised Fresnel reflectance at a planar interface
  (complex second medium allowed).
- :func:`thin_film_rt` — unpolarised R, T of a stack between two identical media
  (:class:`nmmm.layers.Stack`, transfer matrices, Born & Wolf §1.6).

Conventions
-----------
Directions are unit vectors in the surface frame (z = macroscopic normal). Flake normals
have z > 0. Depths are in nm below the top of the clear coat, lengths in nm, angles in
degrees at public interfaces.

References
----------
- M. Born, E. Wolf, *Principles of Optics*, 7th ed., Cambridge University Press (1999),
  §1.5 (Fresnel formulae) and §1.6 (characteristic matrix of a stratified medium).
- Couka, Willot, Jeulin, "A mixed Boolean and deposit model for the modeling of metal
  pigments in paint layers", Image Anal. Stereol. 32(2) (2012) — flake deposits.
- S. Ershov, K. Kolchin, K. Myszkowski, "Rendering pearlescent appearance based on
  paint-composition modelling", Computer Graphics Forum 20(3) (2001) 227 — flakes as
  oriented mirrors in a layer, statistical BRDF.
- F. J. Maile, G. Pfaff, P. Reynders, "Effect pigments — past, present and future",
  Prog. Org. Coat. 54 (2005) 150 — TiO2-on-mica pigments (mica n ≈ 1.58).
- A. Jolivet et al., Appl. Surf. Sci. 608 (2023) 155214 — anatase TiO2 optical constants
  (``main/TiO2/Jolivet-anatase``); A. D. Rakić, Appl. Opt. 34 (1995) 4755 — aluminium
  (``main/Al/Rakic``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.spectra import as_wavelength_nm, check_finite

__all__ = [
    "TiltDistribution",
    "gaussian_tilt",
    "MetalFlakeOptics",
    "ThinFilmFlakeOptics",
    "mica_pigment",
    "aluminium_flakes",
    "FlakeLayer",
    "edge_scatter_fraction",
    "FlakeList",
    "fresnel_unpolarized",
    "thin_film_rt",
    "refract_in",
    "refract_out",
    "check_directions",
]

_N_TILT_NODES = 8193
_MAX_ANGLE_DEG = 89.999  # nmmm.layers takes angles in [0, 90)


# --------------------------------------------------------------------------------------
# directions


def check_directions(v, name: str = "direction", allow_grazing: bool = True) -> np.ndarray:
    """Validate unit direction vectors ``(..., 3)`` in the surface frame (z = normal).

    Raises :class:`InvalidInputError` for a wrong shape, non-finite entries, vectors that
    are not unit length (tolerance 1e-6; they are renormalised within it) or directions
    below the surface (z < 0): a BRDF is defined for directions in the upper hemisphere.
    """
    a = check_finite(v, name)
    if np.iscomplexobj(a):
        raise InvalidInputError(f"{name} must be real unit vectors")
    a = a.astype(float, copy=False)
    if a.ndim < 1 or a.shape[-1] != 3:
        raise InvalidInputError(f"{name} must have shape (..., 3), got {a.shape}")
    norm = np.sqrt(np.sum(a * a, axis=-1))
    if np.any(np.abs(norm - 1.0) > 1e-6):
        raise InvalidInputError(
            f"{name} must be unit vectors (|v| = 1); got norms in [{norm.min():.6g}, {norm.max():.6g}]; "
            "normalise them first"
        )
    a = a / norm[..., None]
    below = a[..., 2] < 0 if allow_grazing else a[..., 2] <= 0
    if np.any(below):
        k = int(np.flatnonzero(below.ravel())[0])
        raise InvalidInputError(
            f"{name} has {int(below.sum())} direction(s) below the surface (z < 0), first at flat index {k} "
            f"(z = {a.reshape(-1, 3)[k, 2]:.6g}); directions must point away from the surface, z >= 0, "
            "in the frame where z is the surface normal"
        )
    return a


def refract_in(v: np.ndarray, n: float) -> np.ndarray:
    """External direction (air side, pointing away) -> internal direction in a medium of
    index ``n`` (pointing away, upward): Snell's law, ω'_xy = ω_xy / n."""
    xy = v[..., :2] / n
    z = np.sqrt(np.clip(1.0 - np.sum(xy * xy, axis=-1), 0.0, 1.0))
    return np.concatenate([xy, z[..., None]], axis=-1)


def refract_out(v: np.ndarray, n: float) -> tuple[np.ndarray, np.ndarray]:
    """Internal upward direction -> external direction; returns ``(direction, escapes)``
    where ``escapes`` is False beyond the critical angle (total internal reflection)."""
    xy = v[..., :2] * n
    s2 = np.sum(xy * xy, axis=-1)
    escapes = (s2 < 1.0) & (v[..., 2] > 0)
    z = np.sqrt(np.clip(1.0 - s2, 0.0, 1.0))
    return np.concatenate([xy, z[..., None]], axis=-1), escapes


# --------------------------------------------------------------------------------------
# Fresnel and thin films


def fresnel_unpolarized(cos_i, n1, n2):
    """Unpolarised reflectance (R_s + R_p)/2 at a plane interface (Born & Wolf §1.5.2),
    from :func:`nmmm.layers.fresnel_equations`; ``cos_i`` the cosine of the angle of incidence in
    medium 1. ``n2`` may be complex (k >= 0) or smaller than ``n1`` (total internal
    reflection, R = 1). Broadcasts over all arguments.

    >>> round(float(fresnel_unpolarized(1.0, 1.0, 1.5)), 6)  # ((1.5-1)/(1.5+1))**2
    0.04
    """
    from nmmm.layers.fresnel_equations import fresnel

    angle = np.degrees(np.arccos(np.clip(np.asarray(cos_i, dtype=float), 0.0, 1.0)))
    return np.asarray(fresnel(n1, n2, np.minimum(angle, _MAX_ANGLE_DEG)).R, dtype=float)


def thin_film_rt(cos_i, wavelength_nm, n_ambient, layers):
    """Unpolarised reflectance and transmittance of a thin-film stack between two
    half-spaces of the same real index ``n_ambient`` (a flake embedded in its binder),
    from :class:`nmmm.layers.Stack` (transfer matrices, Born & Wolf §1.6).

    ``cos_i`` (...) local incidence cosines, ``wavelength_nm`` (L,), ``layers`` a
    sequence of ``(material, thickness_nm)`` top to bottom. Returns ``(R, T)`` of shape
    ``cos_i.shape + (L,)``.
    """
    from nmmm.layers import Stack

    c = np.asarray(cos_i, dtype=float)
    angle = np.minimum(np.degrees(np.arccos(np.clip(c, 0.0, 1.0))), _MAX_ANGLE_DEG)
    res = Stack(list(layers), ambient=n_ambient, substrate=n_ambient).rt(
        np.asarray(wavelength_nm, float), angle.ravel())
    R = np.moveaxis(np.asarray(res.R, float), -1, 0).reshape(c.shape + (-1,))
    T = np.moveaxis(np.asarray(res.T, float), -1, 0).reshape(c.shape + (-1,))
    return R, np.clip(T, 0.0, 1.0)


def _material_nk(material, wavelength_nm):
    from nmmm.materials import as_material

    return np.asarray(as_material(material).nk(wavelength_nm), dtype=complex)


@dataclass(frozen=True)
class MetalFlakeOptics:
    """An opaque metal flake: unpolarised Fresnel reflectance binder → metal, T = 0.

    ``material`` is any :class:`nmmm.materials.Material` (or a constant complex n + ik).
    """

    material: object
    name: str = "metal flake"

    def rt(self, cos_local, wavelength_nm, n_binder: float):
        """(R, T) at local incidence cosines ``cos_local`` (...) and wavelengths (L,),
        each of shape ``cos_local.shape + (L,)``."""
        w = as_wavelength_nm(wavelength_nm)
        nk = _material_nk(self.material, w)
        R = fresnel_unpolarized(np.asarray(cos_local, float)[..., None], n_binder, nk)
        return R, np.zeros_like(R)


@dataclass(frozen=True)
class ThinFilmFlakeOptics:
    """A flake made of thin films (top to bottom), embedded in the binder on both sides.

    ``layers`` is a sequence of ``(material, thickness_nm)`` or ``(material,
    thickness_nm, coherent)``; reflectance and transmittance come from
    :func:`thin_film_rt` (:class:`nmmm.layers.Stack`).
    Light transmitted through the flake continues in its direction (a parallel slab).
    """

    layers: tuple
    name: str = "thin-film flake"

    def __post_init__(self):
        if not self.layers:
            raise InvalidInputError("ThinFilmFlakeOptics needs at least one (material, thickness_nm) layer")
        for layer in self.layers:
            d = layer[1]
            if not (np.isfinite(d) and d > 0):
                raise InvalidInputError(f"layer thickness_nm must be finite and > 0, got {d!r}")

    def rt(self, cos_local, wavelength_nm, n_binder: float):
        w = as_wavelength_nm(wavelength_nm)
        return thin_film_rt(cos_local, w, float(n_binder), self.layers)


def aluminium_flakes(key: str = "main/Al/Rakic") -> MetalFlakeOptics:
    """Aluminium flakes with n, k from the refractiveindex.info database (Rakić 1995)."""
    from nmmm.materials import get

    return MetalFlakeOptics(get(key), name=f"Al flake ({key})")


def mica_pigment(tio2_thickness_nm: float = 120.0, mica_thickness_nm: float = 350.0,
                 tio2=None, mica=None, mica_coherent: bool = False) -> ThinFilmFlakeOptics:
    """TiO2-coated mica interference flake: TiO2 / mica / TiO2 (Maile et al. 2005).

    Materials default to those of :mod:`nmmm.layers.interference`: anatase TiO2
    (``main/TiO2/Jolivet-anatase``) and its muscovite model (n_D = 1.58). The mica is
    incoherent by default (its thickness varies between platelets by more than λ/2n,
    averaging its own fringes out); the TiO2 coatings are coherent and set the colour
    (about 120 nm: blue–violet travelling to green; 60 nm: silver-white pearl).
    """
    from nmmm.layers.interference import DEFAULT_TIO2, muscovite

    if tio2 is None or isinstance(tio2, str):
        from nmmm.materials import get

        tio2 = get(tio2 or DEFAULT_TIO2)
    mica = muscovite() if mica is None else mica
    for v, nm in ((tio2_thickness_nm, "tio2_thickness_nm"), (mica_thickness_nm, "mica_thickness_nm")):
        if not (np.isfinite(v) and v > 0):
            raise InvalidInputError(f"{nm} must be > 0 nm, got {v!r}")
    return ThinFilmFlakeOptics(
        layers=((tio2, float(tio2_thickness_nm)), (mica, float(mica_thickness_nm), bool(mica_coherent)),
                (tio2, float(tio2_thickness_nm))),
        name=f"TiO2({tio2_thickness_nm:g} nm)/mica({mica_thickness_nm:g} nm)/TiO2",
    )


# --------------------------------------------------------------------------------------
# tilt distributions


@dataclass(frozen=True, repr=False)
class TiltDistribution:
    """Isotropic (azimuth-uniform) distribution of flake normals.

    ``density`` is the probability density **per steradian** p(θ) of a flake normal at
    tilt θ from the surface normal, tabulated at ``tilt_deg`` (0 → 90°) and normalised so
    that ∫ p dω = 2π ∫ p(θ) sin θ dθ = 1 over the upper hemisphere. The flake BRDF reads it
    as the AREA distribution of normals (glint power and τ ∝ flake area): estimates from
    flakes weight each normal by its face area (:meth:`from_normals`).

    Build it with :func:`gaussian_tilt`, :meth:`tabulated` or :meth:`from_function`; a
    density that is negative, not finite or has zero integral raises
    :class:`InvalidInputError` (it cannot be normalised).
    """

    tilt_deg: np.ndarray
    density: np.ndarray
    name: str = "tabulated"

    def __post_init__(self):
        t = check_finite(self.tilt_deg, "tilt_deg").astype(float)
        try:
            d = np.asarray(self.density, dtype=float)
        except (TypeError, ValueError):
            raise InvalidInputError("tilt density must be numeric") from None
        if t.ndim != 1 or t.shape != d.shape or t.size < 2:
            raise InvalidInputError("tilt_deg and density must be 1-D arrays of equal length >= 2")
        if np.any(np.diff(t) <= 0) or t[0] < 0 or t[-1] > 90:
            raise InvalidInputError("tilt_deg must increase strictly within [0, 90] degrees")
        if not np.all(np.isfinite(d)):
            raise InvalidInputError(
                "the tilt density is not finite somewhere (NaN/inf): it cannot be normalised; "
                "give a finite density per steradian"
            )
        if np.any(d < 0):
            raise InvalidInputError(
                f"the tilt density is negative (min {d.min():.3g}); a probability density must be >= 0"
            )
        # resample on a fine uniform grid over [0, 90] (zero outside the given nodes)
        grid = np.linspace(0.0, 90.0, _N_TILT_NODES)
        dg = np.interp(grid, t, d, left=0.0, right=0.0)
        th = np.radians(grid)
        norm = np.trapezoid(dg * 2 * np.pi * np.sin(th), th)
        if not (np.isfinite(norm) and norm > 0):
            raise InvalidInputError(
                f"the tilt density integrates to {norm!r} over the hemisphere; it is not normalisable "
                "(it must be >= 0 with a positive finite integral of p(θ)·2π·sinθ dθ)"
            )
        dg = dg / norm
        cdf = np.concatenate([[0.0], np.cumsum(0.5 * (dg[1:] * np.sin(th[1:]) + dg[:-1] * np.sin(th[:-1]))
                                               * np.diff(th) * 2 * np.pi)])
        cdf /= cdf[-1]
        object.__setattr__(self, "tilt_deg", grid)
        object.__setattr__(self, "density", dg)
        object.__setattr__(self, "_cdf", cdf)
        hi = np.searchsorted(cdf, 1.0 - 1e-9)
        object.__setattr__(self, "support_deg", float(min(90.0, grid[min(hi + 1, grid.size - 1)])))

    # constructors ------------------------------------------------------------------
    @classmethod
    def tabulated(cls, tilt_deg, density_per_sr, name: str = "tabulated") -> "TiltDistribution":
        """From a density per steradian at tilt nodes (deg); normalised here."""
        return cls(np.asarray(tilt_deg, float), np.asarray(density_per_sr, float), name)

    @classmethod
    def from_function(cls, density_per_sr: Callable[[np.ndarray], np.ndarray], name: str = "function") -> "TiltDistribution":
        """From a function of the tilt (deg) returning an unnormalised density per sr."""
        t = np.linspace(0.0, 90.0, _N_TILT_NODES)
        return cls(t, np.asarray(density_per_sr(t), float) * np.ones_like(t), name)

    @classmethod
    def from_normals(cls, normals, bandwidth_deg: float | None = None, name: str = "from normals",
                     weights=None, kernel: str = "auto") -> "TiltDistribution":
        """Smooth isotropic density estimated from flake normals (N, 3), each weighted by
        ``weights`` (N,) — give the flake face areas: glint power and τ are ∝ area, so the
        flake BRDF needs the area-weighted law (default equal weights). ``kernel``: "2d" (a
        Gaussian in the plane of tilt vectors, for laws smooth per sr), "theta" (a Gaussian in
        θ reflected at 0, for laws with a finite density per unit θ at 0 — a 1/sin θ peak per
        sr, like the deposit's half-normal tilts) or "auto" (the one with the larger
        leave-one-out likelihood). Silverman bandwidth with N = (Σw)²/Σw² unless
        ``bandwidth_deg``. See :mod:`nmmm.appearance.tilt_kde`."""
        from nmmm.appearance.tilt_kde import tilt_density

        nrm = check_finite(normals, "normals").astype(float).reshape(-1, 3)
        if nrm.shape[0] < 2:
            raise InvalidInputError("need at least two flake normals to estimate a tilt distribution")
        length = np.linalg.norm(nrm, axis=1)
        if np.any(length == 0):
            raise InvalidInputError(
                f"normals has {int(np.sum(length == 0))} zero vector(s) (first at row {int(np.argmin(length))}); "
                "a flake normal needs a direction")
        w = np.ones(nrm.shape[0]) if weights is None else check_finite(weights, "weights").astype(float).ravel()
        if w.shape != (nrm.shape[0],) or np.any(w < 0) or not w.sum() > 0:
            raise InvalidInputError(f"weights must be {nrm.shape[0]} values >= 0 (one per normal, e.g. the flake "
                                    f"face areas) with a positive sum; got shape {w.shape}")
        if kernel not in ("auto", "2d", "theta"):
            raise InvalidInputError(f"kernel must be 'auto', '2d' or 'theta', got {kernel!r}")
        h = None
        if bandwidth_deg is not None:
            h = np.radians(float(bandwidth_deg))
            if not h > 0:
                raise InvalidInputError("bandwidth_deg must be > 0")
        th_k = np.arccos(np.clip(np.abs(nrm[:, 2]) / length, -1, 1))
        t, dens, mode, h = tilt_density(th_k, w, h, kernel)
        return cls(t, dens, name=f"{name} (KDE {mode}, h={np.degrees(h):.2f} deg)")

    # evaluation ----------------------------------------------------------------------
    def pdf(self, cos_tilt) -> np.ndarray:
        """Density per steradian of normals with cos(tilt) = ``cos_tilt``."""
        th = np.degrees(np.arccos(np.clip(cos_tilt, -1.0, 1.0)))
        return np.interp(th, self.tilt_deg, self.density, right=0.0)

    def sample(self, n: int, rng=None) -> np.ndarray:
        """``n`` unit normals (n, 3) drawn from the distribution (azimuth uniform)."""
        rng = np.random.default_rng(rng)
        u = rng.random(n)
        th = np.radians(np.interp(u, self._cdf, self.tilt_deg))
        ph = rng.random(n) * 2 * np.pi
        s = np.sin(th)
        return np.stack([s * np.cos(ph), s * np.sin(ph), np.cos(th)], axis=-1)

    def quadrature(self, n_theta: int = 48, n_phi: int = 48, half: bool = False):
        """Quadrature over flake normals: ``(normals (K, 3), weights (K,))`` with
        Σ w g(m) ≈ ∫ p(m) g(m) dω_m (Gauss–Legendre in tilt over the support, uniform in
        azimuth). ``half=True``: azimuths in [0, π) only, weights doubled (for integrands
        even in the azimuth)."""
        x, wx = np.polynomial.legendre.leggauss(n_theta)
        tmax = np.radians(self.support_deg)
        th = 0.5 * (x + 1) * tmax
        wth = 0.5 * tmax * wx
        span = np.pi if half else 2 * np.pi
        ph = (np.arange(n_phi) + 0.5) * span / n_phi
        T, P = np.meshgrid(th, ph, indexing="ij")
        W = (wth * np.sin(th) * np.interp(np.degrees(th), self.tilt_deg, self.density))[:, None] * (2 * np.pi / n_phi)
        W = np.broadcast_to(W, T.shape)
        m = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1)
        return m.reshape(-1, 3), W.reshape(-1).copy()

    def projected_mean(self, cos_theta) -> np.ndarray:
        """a(μ) = ∫ p(m) |u·m| dω_m: mean projected area (relative to the flake area) of a
        flake seen along a direction u with u_z = ``cos_theta``."""
        mu = np.asarray(cos_theta, float)
        m, w = self.quadrature(64, 64)
        s = np.sqrt(np.clip(1 - mu * mu, 0, 1))
        u = np.stack([s, np.zeros_like(s), mu], axis=-1)
        return np.abs(u.reshape(-1, 3) @ m.T) @ w if mu.ndim else float(np.abs(u @ m.T) @ w)

    def roughened(self, alpha: float, name: str | None = None) -> "TiltDistribution":
        """The distribution of **facet** normals of flakes whose faces are rough: each flake
        face a GGX microfacet surface of roughness α (Walter et al. 2007), facets weighted by
        their area projected on the flake (D(h) cos θ_h, the GGX normalisation). The flake
        tilt and the facet offset compose as tilt vectors (small-angle: θ(cos φ, sin φ) add),
        so the density per unit tilt-vector area is the 2-D convolution of the two. α = 0:
        the distribution itself. The long GGX tail is what keeps far-from-specular light
        falling smoothly with the aspecular angle."""
        a = float(check_finite(alpha, "surface_roughness"))
        if not 0 <= a <= 1:
            raise InvalidInputError(f"surface_roughness (GGX alpha of the flake faces) must lie in [0, 1], got {a!r}")
        if a == 0:
            return self
        from nmmm.appearance.flake_facets import facet_normal_density

        grid, dens = facet_normal_density(self.tilt_deg, self.density, a)
        return TiltDistribution(grid, dens, name=name or f"{self.name} + GGX faces alpha={a:g}")

    def mean_tilt_deg(self) -> float:
        th = np.radians(self.tilt_deg)
        return float(np.degrees(np.trapezoid(th * self.density * 2 * np.pi * np.sin(th), th)))

    def __repr__(self):
        return f"<TiltDistribution '{self.name}', mean tilt {self.mean_tilt_deg():.2f} deg>"


def gaussian_tilt(sigma_deg: float) -> TiltDistribution:
    """Gaussian distribution of flake tilt, density per steradian
    p(θ) ∝ exp(−θ² / 2σ²), truncated at 90° and normalised over the hemisphere.

    The usual description of flake misorientation in metallic paints (Ershov et al. 2001;
    σ of a few degrees for well-aligned flakes, 10–20° for poorly aligned ones).
    """
    s = float(check_finite(sigma_deg, "sigma_deg"))
    if not s > 0:
        raise InvalidInputError(
            f"sigma_deg must be > 0 (a zero-width tilt distribution is a Dirac, not a normalisable "
            f"density); got {sigma_deg!r}"
        )
    t = np.linspace(0.0, 90.0, _N_TILT_NODES)
    return TiltDistribution(t, np.exp(-0.5 * (t / s) ** 2), name=f"gaussian sigma={s:g} deg")


# --------------------------------------------------------------------------------------
# statistical layer


@dataclass(frozen=True)
class FlakeLayer:
    """Statistical description of a flake layer for the smooth BRDF.

    Parameters
    ----------
    optics : MetalFlakeOptics or ThinFilmFlakeOptics
        Reflectance (and transmittance) of one flake in the binder.
    tilt : TiltDistribution
        Distribution of flake normals.
    optical_depth : float
        τ = total flake area per unit area of paint (number per area × mean flake face
        area), ≥ 0. Flakes are spread uniformly in depth through the layer; a ray crossing
        the whole layer along u meets a flake with probability 1 − exp(−τ a(u)/u_z).
        Depth and diameter only matter for the discrete list (sparkle), not for this
        mean-field BRDF — except through a pigmented coat medium.
    depth_range : (z0, z1), default (0, 1)
        The flakes lie uniformly between these fractions of the basecoat thickness (0: its
        top, 1: its bottom). Only matters when the paint has a pigmented ``medium``
        (:class:`nmmm.appearance.brdf.CoatMedium`): pigment above the band hides the flakes.
    surface_roughness : float, default 0
        GGX α of the flake faces (a microfacet lobe per flake; :meth:`TiltDistribution.roughened`).
    edge_fraction : float, default 0
        Fraction of the light meeting a flake that its rims scatter diffusely instead of mirroring,
        with the flake's mean (hemispherical) reflectance. Rims take light in proportion to the
        flakes' projected area a(ui) = E_m|ui·m| along the incoming direction (as every flake
        interaction does) and send it over the whole sphere, up and down, with intensity ∝ a(uo),
        the projected area along the outgoing direction: the kernel a(ui) a(uo) is reciprocal
        (Helmholtz), with no memory of the incoming azimuth (not isotropic emission, which is not
        reciprocal). :func:`edge_scatter_fraction` (perimeter/area × edge width) gives it from the
        diameter.
    """

    optics: object
    tilt: TiltDistribution
    optical_depth: float
    depth_range: tuple = (0.0, 1.0)
    surface_roughness: float = 0.0
    edge_fraction: float = 0.0

    def __post_init__(self):
        tau = float(check_finite(self.optical_depth, "optical_depth"))
        if tau < 0:
            raise InvalidInputError(
                f"flake optical depth (projected flake area per unit area) must be >= 0, got {tau!r}; "
                "a density cannot be negative"
            )
        if not isinstance(self.tilt, TiltDistribution):
            raise InvalidInputError("tilt must be a TiltDistribution (e.g. gaussian_tilt(10))")
        object.__setattr__(self, "optical_depth", tau)
        try:
            z0, z1 = (float(v) for v in self.depth_range)
        except (TypeError, ValueError):
            raise InvalidInputError(f"depth_range must be two fractions (z0, z1) of the coat thickness, got "
                                    f"{self.depth_range!r}") from None
        if not (0.0 <= z0 < z1 <= 1.0):
            raise InvalidInputError(f"depth_range must satisfy 0 <= z0 < z1 <= 1 (fractions of the coat thickness, "
                                    f"0 = top), got ({z0!r}, {z1!r})")
        object.__setattr__(self, "depth_range", (z0, z1))
        a = float(check_finite(self.surface_roughness, "surface_roughness"))
        if not 0 <= a <= 1:
            raise InvalidInputError(f"surface_roughness (GGX alpha of the flake faces) must lie in [0, 1], got {a!r}")
        fe = float(check_finite(self.edge_fraction, "edge_fraction"))
        if not 0 <= fe < 1:
            raise InvalidInputError(f"edge_fraction (light scattered by flake edges) must lie in [0, 1), got {fe!r}")
        object.__setattr__(self, "surface_roughness", a)
        object.__setattr__(self, "edge_fraction", fe)

    @classmethod
    def from_volume_fraction(cls, optics, tilt, volume_fraction: float, flake_thickness_nm: float,
                             layer_thickness_nm: float) -> "FlakeLayer":
        """τ = φ H / t for flakes of thickness t filling a volume fraction φ of a layer of
        thickness H (number per volume φ/(A t), times area A, times H)."""
        from nmmm.spectra import check_fraction, check_positive

        phi = float(check_fraction(volume_fraction, "volume_fraction"))
        t = float(check_positive(flake_thickness_nm, "flake_thickness_nm"))
        H = float(check_positive(layer_thickness_nm, "layer_thickness_nm"))
        return cls(optics, tilt, phi * H / t)

    @classmethod
    def from_areal_density(cls, optics, tilt, flakes_per_mm2: float, mean_diameter_nm: float,
                           diameter_cv: float = 0.0) -> "FlakeLayer":
        """τ = N_A · π⟨d²⟩/4 from the number of flakes per mm² of paint and their diameter
        (mean and coefficient of variation)."""
        na = float(check_finite(flakes_per_mm2, "flakes_per_mm2"))
        if na < 0:
            raise InvalidInputError(f"flakes_per_mm2 must be >= 0 (a density), got {na!r}")
        d = float(check_finite(mean_diameter_nm, "mean_diameter_nm"))
        if d <= 0:
            raise InvalidInputError(f"mean_diameter_nm must be > 0, got {d!r}")
        d2 = d * d * (1 + float(diameter_cv) ** 2)
        return cls(optics, tilt, na * 1e-12 * np.pi * d2 / 4)


def edge_scatter_fraction(mean_diameter_nm: float, edge_width_nm: float = 500.0) -> float:
    """Fraction of the light meeting a flake that its rim scatters diffusely: the rim is a
    band of width w round a disc of diameter d, perimeter/area = 4/d, so f = 4 w / d (capped
    at 0.5). The default w = 500 nm is an assumed wavelength-scale width, not a measured one:
    give a smaller w for smooth "silver-dollar" rims and a larger one for ragged "cornflake"
    rims (which scatter more; Maile, Pfaff & Reynders 2005, and Pfaff, *Special Effect
    Pigments*, 2008, describe the difference qualitatively)."""
    d = float(check_finite(mean_diameter_nm, "mean_diameter_nm"))
    w = float(check_finite(edge_width_nm, "edge_width_nm"))
    if not d > 0 or w < 0:
        raise InvalidInputError(f"mean_diameter_nm must be > 0 and edge_width_nm >= 0, got {d!r}, {w!r}")
    return float(min(0.5, 4.0 * w / d))


# --------------------------------------------------------------------------------------
# discrete flakes


@dataclass(frozen=True, repr=False)
class FlakeList:
    """A discrete list of flakes in a rectangular patch of paint (for sparkle, rendering).

    Attributes (N flakes)
    ---------------------
    positions_nm : (N, 2) lateral centre positions (x, y) in the patch, nm.
    depth_nm : (N,) depth of the flake centre below the top of the clear coat, nm (> 0).
    normals : (N, 3) unit flake normals, z > 0.
    diameters_nm : (N,) flake diameters (discs), nm.
    optics : the flake optics (:class:`MetalFlakeOptics` / :class:`ThinFilmFlakeOptics`).
    n_binder : real refractive index of the binder/clear coat around the flakes.
    region_nm : (width, height) of the patch, nm.
    layer_depth_nm : (top, bottom) depths bounding the flake layer (informative; defaults
        to the depth range of the flakes).
    tilt : the TiltDistribution they were drawn from, if known.

    ``centers_nm`` gives (N, 3) centres with z = −depth (z = 0 at the coat surface).
    """

    positions_nm: np.ndarray
    depth_nm: np.ndarray
    normals: np.ndarray
    diameters_nm: np.ndarray
    optics: object
    n_binder: float
    region_nm: tuple
    layer_depth_nm: tuple | None = None
    tilt: TiltDistribution | None = None
    thickness_nm: float = 300.0
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        p = check_finite(self.positions_nm, "positions_nm").astype(float)
        z = check_finite(self.depth_nm, "depth_nm").astype(float)
        nrm = check_finite(self.normals, "normals").astype(float)
        d = check_finite(self.diameters_nm, "diameters_nm").astype(float)
        n = z.shape[0] if z.ndim == 1 else -1
        if p.shape != (n, 2) or nrm.shape != (n, 3) or d.shape != (n,):
            raise InvalidInputError(
                "FlakeList needs positions_nm (N, 2), depth_nm (N,), normals (N, 3), diameters_nm (N,); "
                f"got {p.shape}, {z.shape}, {nrm.shape}, {d.shape}"
            )
        if np.any(d <= 0):
            raise InvalidInputError("flake diameters_nm must be > 0")
        if np.any(z < 0):
            raise InvalidInputError("flake depth_nm must be >= 0 (below the coat surface)")
        nrm = check_directions(nrm, "flake normals")
        w, h = (float(v) for v in self.region_nm)
        if not (w > 0 and h > 0):
            raise InvalidInputError(f"region_nm must be two positive lengths, got {self.region_nm!r}")
        nb = float(self.n_binder)
        if not nb >= 1.0:
            raise InvalidInputError(f"n_binder must be a real index >= 1, got {self.n_binder!r}")
        for name, val in (("positions_nm", p), ("depth_nm", z), ("normals", nrm), ("diameters_nm", d)):
            object.__setattr__(self, name, val)
        object.__setattr__(self, "region_nm", (w, h))
        object.__setattr__(self, "n_binder", nb)
        if self.layer_depth_nm is None:
            lo, hi = (float(z.min()), float(z.max())) if n > 0 else (0.0, 1.0)
            object.__setattr__(self, "layer_depth_nm", (lo, max(hi, lo + 1e-9)))

    # basic statistics ------------------------------------------------------------------
    def __len__(self):
        return int(self.depth_nm.shape[0])

    @property
    def centers_nm(self) -> np.ndarray:
        return np.column_stack([self.positions_nm, -self.depth_nm])

    @property
    def areas_nm2(self) -> np.ndarray:
        return np.pi * self.diameters_nm ** 2 / 4

    @property
    def optical_depth(self) -> float:
        """τ = Σ flake area / patch area."""
        return float(self.areas_nm2.sum() / (self.region_nm[0] * self.region_nm[1]))

    def optical_depth_above(self) -> np.ndarray:
        """τ_above (N,): area of the flakes lying above each flake (smaller depth), plus
        half its own, per unit area of the patch — the mean-field optical depth that light
        crosses to reach it (statistical shadowing by the flakes above)."""
        order = np.argsort(self.depth_nm, kind="stable")
        a = self.areas_nm2[order]
        cum = np.cumsum(a) - 0.5 * a
        out = np.empty_like(cum)
        out[order] = cum
        return out / (self.region_nm[0] * self.region_nm[1])

    def to_flake_layer(self, tilt: TiltDistribution | None = None) -> FlakeLayer:
        """The statistical :class:`FlakeLayer` with the same optics and τ; the tilt
        distribution is ``tilt``, the one the list was drawn from, or a kernel density
        estimate from the normals weighted by the face areas (:meth:`TiltDistribution.from_normals`)."""
        if tilt is None:
            tilt = self.tilt
        if tilt is None:
            tilt = TiltDistribution.from_normals(self.normals, weights=self.areas_nm2)
        return FlakeLayer(self.optics, tilt, self.optical_depth)

    # optics ---------------------------------------------------------------------------
    def local_cosines(self, wi) -> np.ndarray:
        """cos of the local angle of incidence on each flake for the refracted external
        direction ``wi`` (3,) -> (N,)."""
        wi = check_directions(np.asarray(wi, float).reshape(3), "wi")
        ip = refract_in(wi, self.n_binder)
        return np.abs(self.normals @ ip)

    def reflectance(self, wavelength_nm, wi) -> np.ndarray:
        """Spectral reflectance of each flake (N, L) for light arriving from the external
        direction ``wi`` (refracted into the binder, local angle on each flake)."""
        w = as_wavelength_nm(wavelength_nm)
        R, _ = self.optics.rt(self.local_cosines(wi), w, self.n_binder)
        return R

    def reflected_directions(self, wi):
        """Mirror reflection of the refracted ``wi`` on each flake.

        Returns ``(wo, escapes)``: external outgoing directions (N, 3) and a mask of the
        flakes whose reflected ray leaves the coat (not totally internally reflected and
        going upward).
        """
        wi = check_directions(np.asarray(wi, float).reshape(3), "wi")
        ip = refract_in(wi, self.n_binder)
        c = self.normals @ ip
        op = 2 * c[:, None] * self.normals - ip
        wo, esc = refract_out(op, self.n_binder)
        return wo, esc

    # construction ---------------------------------------------------------------------
    @classmethod
    def random(cls, optics, tilt: TiltDistribution, n_flakes: int, region_nm=(450e3, 450e3),
               mean_diameter_nm: float = 15e3, diameter_cv: float = 0.3,
               depth_range_nm=(5e3, 20e3), n_binder: float = 1.5, rng=None) -> "FlakeList":
        """Flakes placed uniformly at random (Poisson) in a patch, normals from ``tilt``,
        log-normal diameters (mean, coefficient of variation), depths uniform in
        ``depth_range_nm``. Overlaps are not excluded (use
        :func:`nmmm.microstructure` deposits for exclusion and aggregates)."""
        if int(n_flakes) < 0:
            raise InvalidInputError(f"n_flakes must be >= 0, got {n_flakes!r}")
        rng = np.random.default_rng(rng)
        n = int(n_flakes)
        w, h = (float(v) for v in region_nm)
        pos = rng.random((n, 2)) * [w, h]
        lo, hi = (float(v) for v in depth_range_nm)
        if not (0 <= lo < hi):
            raise InvalidInputError(f"depth_range_nm must be (top, bottom) with 0 <= top < bottom, got {depth_range_nm!r}")
        depth = lo + rng.random(n) * (hi - lo)
        d_mean = float(check_finite(mean_diameter_nm, "mean_diameter_nm"))
        if not d_mean > 0:
            raise InvalidInputError(f"mean_diameter_nm must be > 0 (a flake diameter), got {mean_diameter_nm!r}")
        diameter_cv = float(check_finite(diameter_cv, "diameter_cv"))
        if diameter_cv < 0:
            raise InvalidInputError(
                f"diameter_cv must be >= 0 (coefficient of variation: std/mean; 0 for equal flakes), got {diameter_cv!r}")
        if diameter_cv > 0:
            s2 = np.log(1 + diameter_cv ** 2)
            dia = rng.lognormal(np.log(mean_diameter_nm) - s2 / 2, np.sqrt(s2), n)
        else:
            dia = np.full(n, float(mean_diameter_nm))
        return cls(pos, depth, tilt.sample(n, rng), dia, optics, n_binder, (w, h), (lo, hi), tilt)

    @classmethod
    def from_deposit(cls, deposit, optics, n_binder: float = 1.5, tilt=None,
                     coat_thickness_nm: float = 0.0) -> "FlakeList":
        """Adapt a flake deposit from :func:`nmmm.microstructure.flake_deposit`
        (:class:`~nmmm.microstructure.flakes.FlakeDeposit`: ``centres_nm`` with z the
        height above the substrate, ``normals``, ``diameters_nm``, ``box_nm``) — or any
        object/dict with centres/positions, normals, diameters and optionally depth and
        region. Depths are measured from the top of the coat: the flake layer's top lies
        ``coat_thickness_nm`` below it. Duck-typed so that the two packages stay
        independent.
        """
        def get(*names, default=None):
            for nm in names:
                if isinstance(deposit, dict) and nm in deposit:
                    return deposit[nm]
                if not isinstance(deposit, dict) and hasattr(deposit, nm):
                    return getattr(deposit, nm)
            return default

        centers = get("centres_nm", "centers_nm", "positions_nm", "centres", "centers", "positions")
        normals = get("normals", "normal")
        dia = get("diameters_nm", "diameters", "diameter_nm")
        if centers is None or normals is None or dia is None:
            raise InvalidInputError("deposit needs centres/positions, normals and diameters")
        centers = np.asarray(centers, float)
        box = get("box_nm")
        depth = get("depth_nm", "depths_nm", "depth")
        if depth is None:
            if centers.shape[-1] != 3:
                raise InvalidInputError("deposit has no depth and 2-D positions; give depth_nm")
            zc = centers[:, 2]
            if box is not None:
                depth = float(box[2]) - zc
            else:
                depth = np.abs(zc) if np.all(zc <= 0) else zc.max() - zc
        depth = np.asarray(depth, float) + float(coat_thickness_nm)
        region = get("region_nm", "size_nm", "region")
        if region is None and box is not None:
            region = box[:2]
        if region is None:
            region = (np.ptp(centers[:, 0]) or 1.0, np.ptp(centers[:, 1]) or 1.0)
        region = tuple(np.asarray(region, float).ravel()[:2])
        layer = None
        if box is not None:
            layer = (float(coat_thickness_nm), float(coat_thickness_nm) + float(box[2]))
        dia = np.broadcast_to(np.asarray(dia, float), (centers.shape[0],)).copy()
        thick = get("thicknesses_nm", "thickness_nm")
        thick = float(np.mean(thick)) if thick is not None and np.size(thick) else 300.0
        return cls(centers[:, :2].copy(), depth, np.asarray(normals, float), dia,
                   optics, n_binder, region, layer, tilt, thick)

    def __repr__(self):
        return (f"<FlakeList {len(self)} flakes, tau={self.optical_depth:.3g}, "
                f"region {self.region_nm[0]/1e3:g}x{self.region_nm[1]/1e3:g} um>")
