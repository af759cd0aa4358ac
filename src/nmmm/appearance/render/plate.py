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

Public objects
--------------
- :class:`LambertianBRDF` — ideal diffuser f = ρ/π (reference plate).
- :class:`PaintedPlate` — paint, flake unit cell and size; :func:`seed_metallic_plate`
  (Poisson flakes), :func:`deposit_metallic_plate` (the microstructure deposit model).
- :class:`SpectralImage` — radiance (H, W, L), ``to_xyz``, ``to_srgb`` (exposure),
  ``to_display_rgb`` (sRGB / Display P3), ``write_png``, ``write_exr`` (Fichet et al. 2021 layout).
- :func:`render_plate`, :func:`render_stereo_plate`.

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

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from nmmm.appearance.render.camera import PinholeCamera, stereo_pair
from nmmm.appearance.render.lights import (
    DirectionalLight,
    LatLongEnvironment,
    PointLight,
    UniformEnvironment,
    default_wavelengths,
)
from nmmm.errors import InvalidInputError
from nmmm.spectra import as_wavelength_nm, check_finite

try:  # pragma: no cover - numba is a dependency, but keep a NumPy path
    import numba as _nb
except ImportError:  # pragma: no cover
    _nb = None

__all__ = [
    "LambertianBRDF",
    "PaintedPlate",
    "SpectralImage",
    "seed_metallic_plate",
    "deposit_metallic_plate",
    "render_plate",
    "render_stereo_plate",
]


# --------------------------------------------------------------------------------------
# materials


@dataclass(frozen=True)
class LambertianBRDF:
    """Ideal diffuse reflector, f = ρ(λ)/π (ρ a constant or ``(wavelength_nm, values)``)."""

    reflectance: object = 1.0
    name: str = "Lambertian"

    def _rho(self, w):
        r = self.reflectance
        if isinstance(r, tuple) and len(r) == 2:
            rho = np.interp(w, np.asarray(r[0], float), np.asarray(r[1], float))
        else:
            rho = np.broadcast_to(np.asarray(check_finite(r, "reflectance"), float), w.shape)
        if np.any(rho < 0) or np.any(rho > 1):
            raise InvalidInputError("Lambertian reflectance must lie in [0, 1]")
        return rho

    def evaluate(self, wavelength_nm, wi, wo, components=None, dtype=np.float64, **_):
        w = as_wavelength_nm(wavelength_nm).ravel()
        shape = np.broadcast_shapes(np.shape(wi), np.shape(wo))[:-1]
        return np.broadcast_to(self._rho(w) / np.pi, shape + (w.size,)).astype(dtype)

    __call__ = evaluate

    def albedo(self, wavelength_nm, wi):
        w = as_wavelength_nm(wavelength_nm).ravel()
        return np.broadcast_to(self._rho(w), np.shape(wi)[:-1] + (w.size,)).copy()


@dataclass(frozen=True, repr=False)
class PaintedPlate:
    """A flat painted plate ``size_mm`` = (width, height) centred on the origin, normal +z.

    ``brdf`` is a :class:`~nmmm.appearance.brdf.PaintBRDF` (or :class:`LambertianBRDF`);
    ``flakes`` an optional :class:`~nmmm.appearance.flakes.FlakeList` unit cell tiled
    periodically (its ``region_nm`` is the cell). With flakes, the paint's statistical
    flake layer is replaced by the cell's (same optics, τ and tilt) so that the smooth
    terms (base seen through the flakes, multiple scattering) match the discrete flakes.
    """

    brdf: object
    flakes: object = None
    size_mm: tuple = (150.0, 100.0)
    _smooth: object = field(default=None, compare=False, repr=False)

    def __post_init__(self):
        s = np.asarray(check_finite(self.size_mm, "size_mm"), float).ravel()
        if s.shape != (2,) or np.any(s <= 0):
            raise InvalidInputError(f"size_mm must be (width, height) > 0 in mm, got {self.size_mm!r}")
        object.__setattr__(self, "size_mm", (float(s[0]), float(s[1])))
        if not hasattr(self.brdf, "evaluate") or not hasattr(self.brdf, "albedo"):
            raise InvalidInputError("brdf must provide evaluate(wavelength_nm, wi, wo) and albedo(wavelength_nm, wi)")
        smooth = self.brdf
        if self.flakes is not None:
            from nmmm.appearance.brdf import PaintBRDF
            from nmmm.appearance.flakes import FlakeList

            if not isinstance(self.flakes, FlakeList):
                raise InvalidInputError("flakes must be a FlakeList (the unit cell tiled over the plate) or None")
            if not isinstance(self.brdf, PaintBRDF):
                raise InvalidInputError("discrete flakes need a PaintBRDF (its clear coat refracts light to them)")
            smooth = self.brdf.with_(flakes=self.flakes.to_flake_layer())
        object.__setattr__(self, "_smooth", smooth)

    def __repr__(self):
        fl = "no flakes" if self.flakes is None else f"{len(self.flakes)} flakes per cell, {self.cells[0]}x{self.cells[1]} cells"
        return f"<PaintedPlate {self.size_mm[0]:g}x{self.size_mm[1]:g} mm, {getattr(self.brdf, 'name', 'brdf')}, {fl}>"

    @property
    def cell_mm(self) -> tuple[float, float]:
        if self.flakes is None:
            return self.size_mm
        return self.flakes.region_nm[0] * 1e-6, self.flakes.region_nm[1] * 1e-6

    @property
    def cells(self) -> tuple[int, int]:
        """Number of unit cells along x and y (the last ones possibly cut by the edge)."""
        cw, ch = self.cell_mm
        return int(math.ceil(self.size_mm[0] / cw - 1e-9)), int(math.ceil(self.size_mm[1] / ch - 1e-9))

    @property
    def smooth_brdf(self):
        """The BRDF used for the smooth part of the image (flake layer from the cell)."""
        return self._smooth


def seed_metallic_plate(cells=(332, 240), cell_um: float = 450.0, optical_depth: float = 2.0,
                        tilt_deg: float = 12.0, mean_diameter_um: float = 15.0, diameter_cv: float = 0.3,
                        body_reflectance=0.3, rng=0) -> PaintedPlate:
    """The seed paper's grey metallic plate (example 3): Al flakes (Rakić n, k) with a
    Gaussian tilt in a resin binder (n = 1.5) over a light-grey base, smooth clear coat;
    a 450 µm × 450 µm × 20 µm unit cell tiled 332 × 240 times (14.9 cm × 10.8 cm).
    The number of flakes per cell follows from τ = N ⟨π d²/4⟩ / A."""
    from nmmm.appearance.brdf import metallic_paint
    from nmmm.appearance.flakes import FlakeList

    paint = metallic_paint(optical_depth=optical_depth, tilt=tilt_deg, body_reflectance=body_reflectance,
                           name="grey metallic paint")
    cell = float(cell_um) * 1e3
    mean_area = np.pi * (mean_diameter_um * 1e3) ** 2 / 4 * (1 + diameter_cv ** 2)
    n = int(round(optical_depth * cell * cell / mean_area))
    fl = FlakeList.random(paint.flakes.optics, paint.flakes.tilt, n, region_nm=(cell, cell),
                          mean_diameter_nm=mean_diameter_um * 1e3, diameter_cv=diameter_cv,
                          depth_range_nm=(2e3, 18e3), n_binder=1.5, rng=rng)
    cx, cy = (int(c) for c in cells)
    if cx < 1 or cy < 1:
        raise InvalidInputError(f"cells must be positive counts, got {cells!r}")
    return PaintedPlate(paint, fl, (cx * cell * 1e-6, cy * cell * 1e-6))


def deposit_metallic_plate(cells=(332, 240), seed: int = 1, **kwargs) -> PaintedPlate:
    """The grey metallic plate with its unit cell drawn by the deposit model of
    :func:`nmmm.microstructure.flake_deposit` (Couka, Willot & Jeulin 2012; periodic
    450 × 450 × 20 µm cell, exclusion between flakes), through
    :func:`nmmm.appearance.examples.grey_metallic_from_deposit` (``kwargs`` go there)."""
    from nmmm.appearance.examples import grey_metallic_from_deposit

    paint, flakes = grey_metallic_from_deposit(seed=seed, **kwargs)
    cw, ch = flakes.region_nm[0] * 1e-6, flakes.region_nm[1] * 1e-6
    cx, cy = (int(c) for c in cells)
    if cx < 1 or cy < 1:
        raise InvalidInputError(f"cells must be positive counts, got {cells!r}")
    return PaintedPlate(paint, flakes, (cx * cw, cy * ch))


# --------------------------------------------------------------------------------------
# images


@dataclass(frozen=True, repr=False)
class SpectralImage:
    """A rendered spectral radiance image.

    ``radiance`` (H, W, L) float32 in the lights' units × sr⁻¹; ``on_plate`` (H, W) mask;
    ``white_radiance`` (L,) radiance of a perfect white diffuser at the plate centre under
    the same lights (sets the default exposure and the adopted white).
    """

    wavelength_nm: np.ndarray
    radiance: np.ndarray
    on_plate: np.ndarray
    white_radiance: np.ndarray
    camera: PinholeCamera | None = None
    metadata: dict = field(default_factory=dict)

    def __repr__(self):
        h, w, L = self.radiance.shape
        return f"<SpectralImage {w}x{h}, {L} wavelengths {self.wavelength_nm[0]:g}-{self.wavelength_nm[-1]:g} nm>"

    def _weights(self):
        from nmmm.appearance.colorimetry import weighting_factors

        # equal-energy weights: a flat spectrum of value 1 has Y = 100
        return weighting_factors(self.wavelength_nm, illuminant=np.ones(self.wavelength_nm.size))

    def to_xyz(self) -> np.ndarray:
        """CIE 1931 XYZ (H, W, 3) of the radiance, scaled so a flat radiance of 1 has Y = 100."""
        W = self._weights()
        return (self.radiance.reshape(-1, self.radiance.shape[-1]) @ W.astype(np.float32)).reshape(
            self.radiance.shape[:2] + (3,)).astype(float)

    @property
    def white_xyz(self) -> np.ndarray:
        return self.white_radiance @ self._weights()

    def exposure_scale(self, exposure: float = 1.0) -> float:
        """Multiplier putting the white diffuser at Y = 100, times ``exposure``."""
        yw = float(self.white_xyz[1])
        if not yw > 0:
            return float(exposure)
        return 100.0 / yw * float(exposure)

    def to_srgb(self, exposure: float = 1.0, clip: bool = True) -> np.ndarray:
        """Encoded sRGB (H, W, 3) in [0, 1]: ``exposure`` = 1 maps a perfect white diffuser
        under the same lights to display white (1, 1, 1); the lights' white is adapted to
        D65 (CAT02) via :func:`nmmm.appearance.colorimetry.xyz_to_srgb`."""
        from nmmm.appearance.colorimetry import xyz_to_srgb

        e = float(check_finite(exposure, "exposure"))
        if e <= 0:
            raise InvalidInputError(f"exposure must be > 0, got {exposure!r}")
        white = self.white_xyz
        return xyz_to_srgb(self.to_xyz(), white_xyz=white if white[1] > 0 else None, clip=clip,
                           exposure=self.exposure_scale(e))

    def to_display_rgb(self, colourspace: str = "sRGB", exposure: float = 1.0, clip: bool = True) -> np.ndarray:
        """Encoded RGB (H, W, 3) for a calibrated display: ``"sRGB"`` (IEC 61966-2-1) or
        ``"Display P3"`` (P3 primaries, D65, sRGB transfer curve), via colour-science; the
        lights' white is adapted to D65 (CAT02) and ``exposure`` = 1 maps a white diffuser
        to display white."""
        import colour

        if colourspace == "sRGB":
            return self.to_srgb(exposure, clip)
        if colourspace not in ("Display P3",):
            raise InvalidInputError(f"colourspace must be 'sRGB' or 'Display P3', got {colourspace!r}")
        e = float(check_finite(exposure, "exposure"))
        if e <= 0:
            raise InvalidInputError(f"exposure must be > 0, got {exposure!r}")
        white = self.white_xyz
        xyz = self.to_xyz() / 100.0 * self.exposure_scale(e)
        xy_w = colour.XYZ_to_xy(white / white[1]) if white[1] > 0 else colour.CCS_ILLUMINANTS[
            "CIE 1931 2 Degree Standard Observer"]["D65"]
        rgb = colour.XYZ_to_RGB(xyz, colour.RGB_COLOURSPACES[colourspace], illuminant=xy_w,
                                chromatic_adaptation_transform="CAT02", apply_cctf_encoding=True)
        return np.clip(rgb, 0.0, 1.0) if clip else rgb

    def linear_srgb(self) -> np.ndarray:
        """Linear sRGB (H, W, 3) of XYZ/100 (no exposure, no encoding) — the EXR preview."""
        import colour

        return colour.XYZ_to_sRGB(self.to_xyz() / 100.0, apply_cctf_encoding=False)

    def write_png(self, path, exposure: float = 1.0, colourspace: str = "sRGB"):
        """8-bit PNG for a display in ``colourspace`` ("sRGB" or "Display P3"; exposure as
        in :meth:`to_srgb`)."""
        from pathlib import Path

        from PIL import Image

        p = Path(path)
        p.parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(np.round(self.to_display_rgb(colourspace, exposure) * 255).astype(np.uint8)).save(p)
        return p

    def write_exr(self, path, half: bool = False):
        """Spectral OpenEXR (Fichet et al. 2021 layout) with an RGB preview."""
        from nmmm.appearance.render.exr import write_spectral_exr

        attrs = {"nmmm": "nmmm.appearance.render"}
        for k, v in self.metadata.items():
            if isinstance(v, (str, int, float)):
                attrs[f"nmmm.{k}"] = v
        return write_spectral_exr(path, self.wavelength_nm, self.radiance, rgb=self.linear_srgb(),
                                  attributes=attrs, half=half)


# --------------------------------------------------------------------------------------
# numba kernels

_NT = 181  # table nodes over 0..90 deg (0.5 deg), as in nmmm.appearance.brdf
_SUPERSAMPLE = 8  # sub-pixel grid (per axis) of the glint footprint coverage on boundary pixels


def _bilinear_py(coarse, ri, rf, ci, cf, out):
    a = coarse[ri][:, ci]
    b = coarse[ri + 1][:, ci]
    c = coarse[ri][:, ci + 1]
    d = coarse[ri + 1][:, ci + 1]
    fr = rf[:, None, None]
    fc = cf[None, :, None]
    out[:] = (a * (1 - fr) * (1 - fc) + b * fr * (1 - fc) + c * (1 - fr) * fc + d * fr * fc)


def _glint_tiles_py(*args):  # pragma: no cover - only without numba
    raise InvalidInputError("discrete flakes (glints) need numba")


if _nb is not None:
    @_nb.njit(parallel=True, cache=True, fastmath=True)
    def _bilinear(coarse, ri, rf, ci, cf, out):
        H = ri.size
        W = ci.size
        L = coarse.shape[2]
        for i in _nb.prange(H):
            r0 = ri[i]
            fr = rf[i]
            for j in range(W):
                c0 = ci[j]
                fc = cf[j]
                w00 = (1 - fr) * (1 - fc)
                w10 = fr * (1 - fc)
                w01 = (1 - fr) * fc
                w11 = fr * fc
                for k in range(L):
                    out[i, j, k] = (w00 * coarse[r0, c0, k] + w10 * coarse[r0 + 1, c0, k]
                                    + w01 * coarse[r0, c0 + 1, k] + w11 * coarse[r0 + 1, c0 + 1, k])

    @_nb.njit(parallel=True, cache=True, fastmath=True)
    def _mirror_env(img, Fc, ri, rf, ci, cf, texel, on, env):
        """img += F(θo, λ) (bilinear from the coarse grid) × L_env(mirror direction)."""
        H = ri.size
        W = ci.size
        L = Fc.shape[2]
        for i in _nb.prange(H):
            r0 = ri[i]
            fr = rf[i]
            for j in range(W):
                if not on[i, j]:
                    continue
                c0 = ci[j]
                fc = cf[j]
                t = texel[i, j]
                for k in range(L):
                    F = ((1 - fr) * (1 - fc) * Fc[r0, c0, k] + fr * (1 - fc) * Fc[r0 + 1, c0, k]
                         + (1 - fr) * fc * Fc[r0, c0 + 1, k] + fr * fc * Fc[r0 + 1, c0 + 1, k])
                    img[i, j, k] += F * env[t, k]

    @_nb.njit(cache=True, fastmath=True)
    def _lerp1_nb(tab, th, step):
        x = th / step
        if x < 0:
            x = 0.0
        i0 = int(x)
        if i0 >= tab.shape[0] - 1:
            return tab[tab.shape[0] - 1]
        f = x - i0
        return tab[i0] * (1 - f) + tab[i0 + 1] * f

    @_nb.njit(cache=True)
    def _tile_hash(i, j, seed):
        """Deterministic pseudo-random numbers in [0, 1) for tile (i, j) (splitmix64)."""
        z = (np.uint64(i) * np.uint64(0x9E3779B97F4A7C15)) ^ (np.uint64(j) * np.uint64(0xC2B2AE3D27D4EB4F)) \
            ^ np.uint64(seed)
        out = np.empty(4)
        for k in range(4):
            z = z + np.uint64(0x9E3779B97F4A7C15)
            x = z
            x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
            x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
            x = x ^ (x >> np.uint64(31))
            out[k] = float(x >> np.uint64(11)) / 9007199254740992.0
        return out

    @_nb.njit(cache=True, fastmath=True)
    def _ellipse_coverage(x0, y0, a1x, a1y, a2x, a2y, idet):
        """Fraction of the unit pixel [x0, x0 + 1] × [y0, y0 + 1] (relative to the ellipse
        centre) inside the ellipse {s A1 + t A2 : s² + t² <= 1}: 1 when its four corners are
        inside (the ellipse is convex), else the fraction of an 8 × 8 grid of sub-pixel
        centres inside (error <= 1/64 of a pixel per boundary pixel, unbiased on average)."""
        inside = 0
        for cy in range(2):
            for cx in range(2):
                x = x0 + cx
                y = y0 + cy
                s = (a2y * x - a2x * y) * idet
                t = (-a1y * x + a1x * y) * idet
                if s * s + t * t <= 1.0:
                    inside += 1
        if inside == 4:
            return 1.0
        ns = _SUPERSAMPLE
        cnt = 0
        for iy in range(ns):
            y = y0 + (iy + 0.5) / ns
            for ix in range(ns):
                x = x0 + (ix + 0.5) / ns
                s = (a2y * x - a2x * y) * idet
                t = (-a1y * x + a1x * y) * idet
                if s * s + t * t <= 1.0:
                    cnt += 1
        return cnt / (ns * ns)

    @_nb.njit(parallel=True, cache=True, fastmath=True)
    def _glint_tiles(fill, offsets, rec_pix, rec_w, rec_th, rec_li, counts,
                     cam, cam_r, cam_u, cam_f, tx, ty, sx, sy, W, H,
                     hx, hy, cw, ch, i0, i1, j0, j1,
                     fpos, fnrm, farea, fdiam, fzeta, G, gstart_all, gorder_all,
                     lkind, lvec, lscale, n, sigma, cut, a_tab, astep, randomize, seed, splat):
        """One pass over the visible tiles (rows j in parallel): count (fill=False) or
        write (fill=True) the glint records (pixel, weight, angles, light)."""
        pix_sa = (2 * tx / W) * (2 * ty / H)
        nl = lkind.size
        inv2s2 = 1.0 / (2 * sigma * sigma)
        gnorm = 1.0 / (2 * math.pi * sigma * sigma * (1 - math.exp(-0.5 * cut * cut)))
        maxang = cut * sigma
        cosmax = math.cos(maxang)
        half_diag = 0.5 * math.sqrt(cw * cw + ch * ch)
        # a flake normal m off the half vector h' by δ sends the external mirror ray at
        # least 2 n cos θd' δ >= 2 sqrt(n² - 1) δ away (reflection + Snell, θd' below the
        # critical angle): search normals within maxang / (2 sqrt(n² - 1)), +10 %
        mfac = min(2.0, 1.1 / (2 * math.sqrt(max(n * n - 1, 1e-6))))
        for jj in _nb.prange(j1 - j0):
            j = j0 + jj
            cnt = 0
            base = offsets[jj]
            for i in range(i0, i1):
                ox = -hx + i * cw
                oy = -hy + j * ch
                if randomize:
                    rnd = _tile_hash(i, j, seed)
                    cph = math.cos(2 * math.pi * rnd[0])
                    sph = math.sin(2 * math.pi * rnd[0])
                    offx = rnd[1] * cw
                    offy = rnd[2] * ch
                    var = min(int(rnd[3] * fnrm.shape[0]), fnrm.shape[0] - 1)
                else:
                    cph, sph, offx, offy = 1.0, 0.0, 0.0, 0.0
                    var = 0
                gstart = gstart_all[var]
                gorder = gorder_all[var]
                pcx = ox + 0.5 * cw
                pcy = oy + 0.5 * ch
                # camera direction at the tile centre
                vx = cam[0] - pcx
                vy = cam[1] - pcy
                vz = cam[2]
                dc = math.sqrt(vx * vx + vy * vy + vz * vz)
                vx /= dc
                vy /= dc
                vz /= dc
                # internal outgoing direction
                ox_ = vx / n
                oy_ = vy / n
                oz_ = math.sqrt(max(0.0, 1 - ox_ * ox_ - oy_ * oy_))
                for li in range(nl):
                    if lkind[li] == 0:
                        wx, wy, wz = lvec[li, 0], lvec[li, 1], lvec[li, 2]
                        dl = 1e30
                    else:
                        wx = lvec[li, 0] - pcx
                        wy = lvec[li, 1] - pcy
                        wz = lvec[li, 2]
                        dl = math.sqrt(wx * wx + wy * wy + wz * wz)
                        wx /= dl
                        wy /= dl
                        wz /= dl
                    if wz <= 0:
                        continue
                    ix = wx / n
                    iy = wy / n
                    iz = math.sqrt(max(0.0, 1 - ix * ix - iy * iy))
                    hxv = ix + ox_
                    hyv = iy + oy_
                    hzv = iz + oz_
                    hn = math.sqrt(hxv * hxv + hyv * hyv + hzv * hzv)
                    hxv /= hn
                    hyv /= hn
                    # to the unit cell's frame (normals rotated by phi in this tile)
                    hxc = cph * hxv + sph * hyv
                    hyc = -sph * hxv + cph * hyv
                    hxv = hxc
                    hyv = hyc
                    # search radius in the flake-normal (m_x, m_y) plane
                    r = mfac * maxang + half_diag / dc + half_diag / dl
                    bx0 = int(math.floor((hxv - r + 1) * 0.5 * G))
                    bx1 = int(math.floor((hxv + r + 1) * 0.5 * G))
                    by0 = int(math.floor((hyv - r + 1) * 0.5 * G))
                    by1 = int(math.floor((hyv + r + 1) * 0.5 * G))
                    bx0 = max(bx0, 0)
                    by0 = max(by0, 0)
                    bx1 = min(bx1, G - 1)
                    by1 = min(by1, G - 1)
                    for by in range(by0, by1 + 1):
                        for bx in range(bx0, bx1 + 1):
                            b = by * G + bx
                            for q in range(gstart[b], gstart[b + 1]):
                                k = gorder[q]
                                px = ox + (fpos[k, 0] + offx) % cw
                                py = oy + (fpos[k, 1] + offy) % ch
                                if px < -hx or px > hx or py < -hy or py > hy:
                                    continue
                                dx = px - cam[0]
                                dy = py - cam[1]
                                dz = -cam[2]
                                d = math.sqrt(dx * dx + dy * dy + dz * dz)
                                wox = -dx / d
                                woy = -dy / d
                                woz = -dz / d
                                # light direction and plane irradiance factor at the flake
                                if lkind[li] == 0:
                                    lx, ly, lz = wx, wy, wz
                                    e = lscale[li] * lz
                                else:
                                    lx = lvec[li, 0] - px
                                    ly = lvec[li, 1] - py
                                    lz = lvec[li, 2]
                                    r2 = lx * lx + ly * ly + lz * lz
                                    rl = math.sqrt(r2)
                                    lx /= rl
                                    ly /= rl
                                    lz /= rl
                                    if lz <= 0:
                                        continue
                                    e = lscale[li] / (r2 * 1e-6) * lz
                                jx = lx / n
                                jy = ly / n
                                jz = math.sqrt(max(0.0, 1 - jx * jx - jy * jy))
                                mx = cph * fnrm[var, k, 0] - sph * fnrm[var, k, 1]
                                my = sph * fnrm[var, k, 0] + cph * fnrm[var, k, 1]
                                mz = fnrm[var, k, 2]
                                c = mx * jx + my * jy + mz * jz
                                if c <= 0:
                                    continue
                                qx = 2 * c * mx - jx
                                qy = 2 * c * my - jy
                                qz = 2 * c * mz - jz
                                s2 = n * n * (qx * qx + qy * qy)
                                if qz <= 0 or s2 >= 1:
                                    continue
                                fx = n * qx
                                fy = n * qy
                                fz = math.sqrt(1 - s2)
                                ca = fx * wox + fy * woy + fz * woz
                                if ca < cosmax:
                                    continue
                                zc = dx * cam_f[0] + dy * cam_f[1] + dz * cam_f[2]
                                if zc <= 0:
                                    continue
                                uc = (dx * cam_r[0] + dy * cam_r[1] + dz * cam_r[2]) / zc
                                vc = (dx * cam_u[0] + dy * cam_u[1] + dz * cam_u[2]) / zc
                                u = uc / tx - sx
                                v = vc / ty - sy
                                colf = (u + 1) * 0.5 * W
                                rowf = (1 - v) * 0.5 * H
                                # projected footprint of the flake disc (radius rho, normal m):
                                # affine (Jacobian) image of the disc at its centre, an ellipse
                                # c + s A1 + t A2 (s² + t² <= 1) in pixel units
                                rho = 0.5 * fdiam[k]
                                if abs(mx) <= abs(my):
                                    e1x, e1y, e1z = 0.0, -mz, my  # x̂ × m (unnormalised, |.| >= 1/√2)
                                else:
                                    e1x, e1y, e1z = mz, 0.0, -mx  # ŷ × m
                                en = math.sqrt(e1x * e1x + e1y * e1y + e1z * e1z)
                                e1x /= en
                                e1y /= en
                                e1z /= en
                                e2x = my * e1z - mz * e1y
                                e2y = mz * e1x - mx * e1z
                                e2z = mx * e1y - my * e1x
                                # d(col)/dX = W/2 (r - uc f) / (zc tx); d(row)/dX = -H/2 (up - vc f) / (zc ty)
                                kc = rho * 0.5 * W / (zc * tx)
                                kr = -rho * 0.5 * H / (zc * ty)
                                a1x = kc * ((cam_r[0] - uc * cam_f[0]) * e1x + (cam_r[1] - uc * cam_f[1]) * e1y
                                            + (cam_r[2] - uc * cam_f[2]) * e1z)
                                a2x = kc * ((cam_r[0] - uc * cam_f[0]) * e2x + (cam_r[1] - uc * cam_f[1]) * e2y
                                            + (cam_r[2] - uc * cam_f[2]) * e2z)
                                a1y = kr * ((cam_u[0] - vc * cam_f[0]) * e1x + (cam_u[1] - vc * cam_f[1]) * e1y
                                            + (cam_u[2] - vc * cam_f[2]) * e1z)
                                a2y = kr * ((cam_u[0] - vc * cam_f[0]) * e2x + (cam_u[1] - vc * cam_f[1]) * e2y
                                            + (cam_u[2] - vc * cam_f[2]) * e2z)
                                ex = math.sqrt(a1x * a1x + a2x * a2x)  # bounding-box half sizes
                                ey = math.sqrt(a1y * a1y + a2y * a2y)
                                det = a1x * a2y - a2x * a1y
                                area = splat and max(ex, ey) > 0.5 and abs(det) > 1e-12
                                col = int(math.floor(colf))
                                row = int(math.floor(rowf))
                                if area:
                                    c0 = max(int(math.floor(colf - ex)), 0)
                                    c1 = min(int(math.floor(colf + ex)), W - 1)
                                    r0 = max(int(math.floor(rowf - ey)), 0)
                                    r1 = min(int(math.floor(rowf + ey)), H - 1)
                                    if c0 > c1 or r0 > r1:
                                        continue
                                elif col < 0 or col >= W or row < 0 or row >= H:
                                    continue
                                ang = math.acos(min(1.0, ca))
                                g = gnorm * math.exp(-ang * ang * inv2s2)
                                cosa = zc / d
                                omega = pix_sa * cosa * cosa * cosa
                                wgt = e * farea[k] * c / jz * g / (omega * d * d)
                                th0 = 0.0
                                th1 = 0.0
                                th2 = 0.0
                                th3 = 0.0
                                if fill:
                                    th0 = math.degrees(math.acos(min(1.0, lz)))
                                    th1 = math.degrees(math.acos(min(1.0, fz)))
                                    th2 = math.degrees(math.acos(min(1.0, c)))
                                    S = (_lerp1_nb(a_tab, math.degrees(math.acos(min(1.0, jz))), astep) / jz
                                         + _lerp1_nb(a_tab, math.degrees(math.acos(min(1.0, qz))), astep) / qz)
                                    th3 = S * fzeta[k]
                                if not area:
                                    if fill:
                                        o = base + cnt
                                        rec_pix[o] = row * W + col
                                        rec_w[o] = wgt
                                        rec_th[o, 0] = th0
                                        rec_th[o, 1] = th1
                                        rec_th[o, 2] = th2
                                        rec_th[o, 3] = th3
                                        rec_li[o] = li
                                    cnt += 1
                                    continue
                                # area splat: the flake's power wgt·Ω(flake) shared over the pixels
                                # in proportion to their covered area (the whole ellipse, frame
                                # included or not), each divided by its own solid angle Ω_p
                                idet = 1.0 / det
                                tot = 0.0
                                first = base + cnt
                                for rr in range(int(math.floor(rowf - ey)), int(math.floor(rowf + ey)) + 1):
                                    for cc in range(int(math.floor(colf - ex)), int(math.floor(colf + ex)) + 1):
                                        cov = _ellipse_coverage(cc - colf, rr - rowf, a1x, a1y, a2x, a2y, idet)
                                        if cov <= 0.0:
                                            continue
                                        tot += cov
                                        if cc < c0 or cc > c1 or rr < r0 or rr > r1:
                                            continue
                                        if fill:
                                            o = base + cnt
                                            up_ = (2 * (cc + 0.5) / W - 1 + sx) * tx
                                            vp_ = (1 - 2 * (rr + 0.5) / H + sy) * ty
                                            cp = 1.0 / math.sqrt(1 + up_ * up_ + vp_ * vp_)
                                            rec_pix[o] = rr * W + cc
                                            rec_w[o] = wgt * cov * omega / (pix_sa * cp * cp * cp)
                                            rec_th[o, 0] = th0
                                            rec_th[o, 1] = th1
                                            rec_th[o, 2] = th2
                                            rec_th[o, 3] = th3
                                            rec_li[o] = li
                                        cnt += 1
                                if fill and tot > 0.0:
                                    for o in range(first, base + cnt):
                                        rec_w[o] /= tot
            counts[jj] = cnt

    @_nb.njit(parallel=True, cache=True, fastmath=True)
    def _glint_splat(img, gstart, rec_pix, rec_w, rec_th, rec_li, Tc, Rf, step, tau_e, const_tau, espec):
        """Add the glint spectra to the image; records sorted by pixel, one pixel group
        per task (no write conflicts, deterministic order)."""
        L = img.shape[1]
        nt = Tc.shape[0]
        ng = gstart.size - 1
        for gi in _nb.prange(ng):
            for r in range(gstart[gi], gstart[gi + 1]):
                p = rec_pix[r]
                x0 = rec_th[r, 0] / step
                x1 = rec_th[r, 1] / step
                x2 = rec_th[r, 2] / step
                a0 = min(int(x0), nt - 2)
                a1 = min(int(x1), nt - 2)
                a2 = min(int(x2), nt - 2)
                f0 = min(x0 - a0, 1.0)
                f1 = min(x1 - a1, 1.0)
                f2 = min(x2 - a2, 1.0)
                wgt = rec_w[r]
                sz = rec_th[r, 3]
                li = rec_li[r]
                if const_tau:
                    wgt *= math.exp(-tau_e[0] * sz)
                    for l in range(L):
                        ti = Tc[a0, l] * (1 - f0) + Tc[a0 + 1, l] * f0
                        to = Tc[a1, l] * (1 - f1) + Tc[a1 + 1, l] * f1
                        rf = Rf[a2, l] * (1 - f2) + Rf[a2 + 1, l] * f2
                        img[p, l] += wgt * ti * to * rf * espec[li, l]
                else:
                    for l in range(L):
                        ti = Tc[a0, l] * (1 - f0) + Tc[a0 + 1, l] * f0
                        to = Tc[a1, l] * (1 - f1) + Tc[a1 + 1, l] * f1
                        rf = Rf[a2, l] * (1 - f2) + Rf[a2 + 1, l] * f2
                        img[p, l] += wgt * ti * to * rf * math.exp(-tau_e[l] * sz) * espec[li, l]
else:  # pragma: no cover
    _bilinear = _bilinear_py
    _glint_tiles = _glint_tiles_py
    _mirror_env = _glint_tiles_py


# --------------------------------------------------------------------------------------
# rendering


def _check_lights(lights, environment):
    if isinstance(lights, (DirectionalLight, PointLight)):
        lights = (lights,)
    lights = tuple(lights or ())
    for lt in lights:
        if not isinstance(lt, (DirectionalLight, PointLight)):
            raise InvalidInputError(f"lights must be DirectionalLight / PointLight objects, got {type(lt).__name__}")
    if environment is not None and not isinstance(environment, (UniformEnvironment, LatLongEnvironment)):
        raise InvalidInputError("environment must be a UniformEnvironment, a LatLongEnvironment or None")
    if not lights and environment is None:
        raise InvalidInputError("no light: give at least one light or an environment")
    return lights, environment


def _envmap_smooth(brdf, w, envmap, wo_grid, hit_grid, sub: int = 4, n_theta: int = 8, n_phi: int = 16):
    """Radiance reflected from a lat-long environment by the non-Dirac BRDF terms,
    ∑_k f(ω_k, ωo) cos θ_k ΔΩ_k L_k over n_theta × n_phi cells of the upper hemisphere,
    on every ``sub``-th node of the coarse grid, interpolated back onto it."""
    nr, nc = wo_grid.shape[:2]
    rs = np.unique(np.r_[np.arange(0, nr, sub), nr - 1])
    cs = np.unique(np.r_[np.arange(0, nc, sub), nc - 1])
    wo = wo_grid[np.ix_(rs, cs)].reshape(-1, 3)
    qd, qs, qr = envmap.upper_quadrature(w, n_theta, n_phi)
    out = np.zeros((wo.shape[0], w.size))
    comps = ("specular", "flakes", "base", "multiple")
    for k in range(qd.shape[0]):
        f = brdf.evaluate(w, np.broadcast_to(qd[k], wo.shape), wo, components=comps)
        out += f * (qd[k, 2] * qs[k] * qr[k])[None, :]
    out = out.reshape(rs.size, cs.size, w.size)
    # bilinear back onto the coarse grid (separable linear interpolation)
    res = _interp_axis(cs, _interp_axis(rs, out, nr, 0), nc, 1)
    return np.where(hit_grid[..., None], res, 0.0)


def _interp_axis(nodes, values, n, axis):
    """Linear interpolation of ``values`` given at integer ``nodes`` along ``axis`` onto 0..n-1."""
    if nodes.size == 1:
        return np.repeat(values, n, axis=axis)
    x = np.arange(n, dtype=float)
    i = np.clip(np.searchsorted(nodes, x, side="right") - 1, 0, nodes.size - 2)
    t = (x - nodes[i]) / (nodes[i + 1] - nodes[i])
    shape = [1] * values.ndim
    shape[axis] = n
    t = t.reshape(shape)
    return np.take(values, i, axis=axis) * (1 - t) + np.take(values, i + 1, axis=axis) * t


def _light_at(lt, P):
    """Directions to the light (n, 3) and the geometric factor (n,) of the plane irradiance
    (cos θi, over r² in m² for a point light); the spectrum carries the power."""
    if isinstance(lt, DirectionalLight):
        d = np.broadcast_to(np.asarray(lt.direction), P.shape).copy()
        s = d[:, 2].copy()
    else:
        v = np.asarray(lt.position_mm)[None, :] - P
        r2 = np.sum(v * v, axis=1)
        d = v / np.sqrt(r2)[:, None]
        s = d[:, 2] / (r2 * 1e-6)
    ok = d[:, 2] > 0
    d[~ok] = (0.0, 0.0, 1.0)
    s = np.where(ok, s, 0.0)
    return d, s


def _plate_hits(camera: PinholeCamera, dirs):
    cz = camera.position_mm[2]
    dz = dirs[..., 2]
    hit = dz < -1e-12
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(hit, -cz / np.where(hit, dz, -1.0), 0.0)
    P = np.asarray(camera.position_mm) + t[..., None] * dirs
    return hit, P


def _check_camera(plate: PaintedPlate, camera: PinholeCamera):
    if not isinstance(camera, PinholeCamera):
        raise InvalidInputError("camera must be a PinholeCamera")
    if camera.position_mm[2] <= 0:
        raise InvalidInputError(
            f"the camera is at z = {camera.position_mm[2]:g} mm, on or behind the plate (z = 0); "
            "place it in front of the painted side (z > 0)"
        )
    _, _, f = camera.basis()
    to_plate = -np.asarray(camera.position_mm)
    if f[2] >= 0 or f @ to_plate <= 0:
        raise InvalidInputError(
            f"the camera looks away from the plate (viewing direction {np.round(f, 3).tolist()}); "
            "point it at the plate, e.g. look_at_mm=(0, 0, 0)"
        )


def render_plate(plate: PaintedPlate, camera: PinholeCamera, lights=(), environment=None, wavelength_nm=None,
                 glint_spread_deg: float = 1.0, coarse_step: int = 4, background=None,
                 randomize_tiles: bool = True, tile_seed: int = 0, area_splat: bool = True) -> SpectralImage:
    """Render the spectral radiance image of ``plate`` seen by ``camera``.

    Parameters
    ----------
    plate : PaintedPlate
    camera : PinholeCamera
        Must be in front of the plate (z > 0) and look towards it.
    lights : DirectionalLight / PointLight or a sequence of them
    environment : UniformEnvironment or LatLongEnvironment, optional
        Uniform spectral sky (reflected through the paint's albedo) or a spectral lat-long
        map (non-Dirac terms integrated over 8 × 16 cells of the upper hemisphere on a
        4×-coarser grid; the smooth coat's mirror image of the map at full resolution);
        seen behind the plate.
    wavelength_nm : (L,) grid, default 380–780 nm every 5 nm (81 wavelengths).
    glint_spread_deg : float
        Standard deviation of the flakes' mirror lobe (light source angular size, flake
        roughness), degrees.
    coarse_step : int
        Pixel step of the grid on which the smooth BRDF part is evaluated (1: every pixel).
    background : (L,) radiance for pixels off the plate (default: the environment, or 0).
    randomize_tiles : bool
        Give each copy of the unit cell a pseudo-random cyclic shift and a rotation of its
        flake normals about the plate normal, and one of up to 64 tilt variants of the
        cell (its tilts moved by a rotation of their cumulative probability, see
        ``_tilt_variants``) (hash of the tile index and ``tile_seed``: deterministic).
        This keeps the flake statistics (isotropic tilt distribution, periodic positions)
        but hides the moiré of a strictly periodic tiling and the cell's finite sample of
        tilts: without the variants every tile repeats the same few flakes of small tilt,
        and the glints around a light's highlight print that histogram (a dark or bright
        centre or ring) instead of the smooth p(θh) of the statistical BRDF; False tiles
        the cell as is.
    area_splat : bool
        Spread the glint of a flake whose projected disc is wider than a pixel over the
        pixels its footprint covers (default), instead of the pixel of its centre. The
        footprint is the affine image of the flake disc (diameter, normal) at its centre —
        the pinhole projection to first order; the coat's refraction and the flake's depth
        are neglected — an ellipse; each pixel of its bounding box gets the fraction of
        the ellipse's area it covers (exactly 1 for pixels whose four corners are inside,
        else an 8 × 8 sub-pixel count), normalised over the whole ellipse, divided by the
        pixel's own solid angle: Σ_p L_p Ω_p equals the point splat's L Ω exactly (the
        part of a footprint outside the frame is lost). Flakes whose projected diameter
        is at most one pixel keep the point splat (identical results).
        ``metadata['n_glints']`` counts the glint records (one per lit pixel of a flake).

    Returns
    -------
    SpectralImage
    """
    w = default_wavelengths() if wavelength_nm is None else as_wavelength_nm(wavelength_nm).ravel()
    if not isinstance(plate, PaintedPlate):
        raise InvalidInputError("plate must be a PaintedPlate")
    _check_camera(plate, camera)
    lights, environment = _check_lights(lights, environment)
    sig = float(check_finite(glint_spread_deg, "glint_spread_deg"))
    if not 0 < sig <= 20:
        raise InvalidInputError(f"glint_spread_deg must lie in (0, 20] degrees, got {sig!r}")
    step = int(coarse_step)
    if step < 1:
        raise InvalidInputError(f"coarse_step must be >= 1, got {coarse_step!r}")
    Wd, Hd = camera.resolution
    L = w.size
    hx, hy = plate.size_mm[0] / 2, plate.size_mm[1] / 2

    # --- full-resolution geometry: which pixels see the plate
    dirs = camera.pixel_directions()
    hit, P = _plate_hits(camera, dirs)
    on = hit & (np.abs(P[..., 0]) <= hx) & (np.abs(P[..., 1]) <= hy)
    if not on.any():
        raise InvalidInputError(
            "no pixel centre of the camera falls on the plate: it looks past it (or the plate covers less than "
            "a pixel); aim the camera at the plate "
            f"(plate {plate.size_mm[0]:g} x {plate.size_mm[1]:g} mm centred on the origin) or widen fov_deg"
        )
    spectra = [lt.spectral(w) for lt in lights]
    env = environment.spectral(w) if isinstance(environment, UniformEnvironment) else None
    envmap = environment if isinstance(environment, LatLongEnvironment) else None

    # --- smooth part on a coarse grid of pixels
    brdf = plate.smooth_brdf
    rows = np.unique(np.r_[np.arange(0, Hd, step), Hd - 1]).astype(float)
    cols = np.unique(np.r_[np.arange(0, Wd, step), Wd - 1]).astype(float)
    cd = camera.pixel_directions(rows, cols).reshape(-1, 3)
    chit, cP = _plate_hits(camera, cd)
    wo = -cd
    wo[~chit] = (0.0, 0.0, 1.0)
    wo[:, 2] = np.maximum(wo[:, 2], 0.0)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    coarse = np.zeros((cd.shape[0], L))
    comps = ("specular", "base", "multiple") if plate.flakes is not None else ("specular", "flakes", "base", "multiple")
    for lt, sp in zip(lights, spectra):
        wi, s = _light_at(lt, cP)
        f = brdf.evaluate(w, wi, wo, components=comps)
        coarse += f * s[:, None] * sp[None, :]
    if env is not None:
        coarse += brdf.albedo(w, wo) * env[None, :]
    coarse[~chit] = 0.0
    coarse = coarse.reshape(rows.size, cols.size, L)
    if envmap is not None:
        coarse += _envmap_smooth(brdf, w, envmap, wo.reshape(rows.size, cols.size, 3), chit.reshape(rows.size, cols.size))
    coarse = coarse.astype(np.float32)
    if rows.size == 1:
        coarse = np.concatenate([coarse, coarse], axis=0)
        rows = np.r_[rows, rows + 1]
    if cols.size == 1:
        coarse = np.concatenate([coarse, coarse], axis=1)
        cols = np.r_[cols, cols + 1]
    pr = np.arange(Hd, dtype=float)
    pc = np.arange(Wd, dtype=float)
    ri = np.clip(np.searchsorted(rows, pr, side="right") - 1, 0, rows.size - 2)
    ci = np.clip(np.searchsorted(cols, pc, side="right") - 1, 0, cols.size - 2)
    rf = ((pr - rows[ri]) / (rows[ri + 1] - rows[ri])).astype(np.float32)
    cf = ((pc - cols[ci]) / (cols[ci + 1] - cols[ci])).astype(np.float32)
    img = np.empty((Hd, Wd, L), np.float32)
    _bilinear(coarse, ri.astype(np.int64), rf, ci.astype(np.int64), cf, img)

    # --- off-plate pixels
    bg = background if background is not None else env
    off = ~on
    if bg is None and envmap is not None:
        img[off] = envmap.lookup(w, dirs[off]).astype(np.float32)
    elif bg is None:
        img[off] = 0.0
    else:
        img[off] = np.asarray(bg, np.float32)[None, :]

    # --- mirror reflection of an environment map in a smooth coat (the coat's Dirac)
    if envmap is not None and hasattr(brdf, "specular_reflectance"):
        Fc = brdf.specular_reflectance(w, wo).reshape(coarse.shape)
        if np.any(Fc > 0):
            mirror = dirs * np.array([1.0, 1.0, -1.0])  # view ray mirrored at the plate
            env_flat = envmap._on(w).reshape(-1, L)
            _mirror_env(img, np.ascontiguousarray(Fc, np.float32), ri.astype(np.int64), rf, ci.astype(np.int64), cf,
                        envmap.texel(mirror), on, np.ascontiguousarray(env_flat, np.float32))

    # --- mirror images of finite-size lights in a smooth clear coat (the coat's Dirac)
    if hasattr(plate.smooth_brdf, "specular_reflectance"):
        _add_light_images(plate.smooth_brdf, camera, lights, spectra, w, dirs, P, on, img)

    # --- glints of the discrete flakes
    n_glints = 0
    if plate.flakes is not None and lights:
        n_glints = _render_glints(plate, camera, lights, spectra, w, np.radians(sig), P[on], img,
                                  randomize_tiles, tile_seed, area_splat)

    # white diffuser at the plate centre (exposure / adopted white)
    centre = np.zeros((1, 3))
    white = np.zeros(L)
    for lt, sp in zip(lights, spectra):
        _, s = _light_at(lt, centre)
        white += s[0] * sp / np.pi
    if env is not None:
        white += env
    if envmap is not None:
        qd, qs, qr = envmap.upper_quadrature(w)
        white += (qs * qd[:, 2]) @ qr / np.pi
    meta = {"plate": repr(plate), "glint_spread_deg": sig, "n_glints": int(n_glints), "coarse_step": step}
    return SpectralImage(w, img, on, white, camera, meta)


def _add_light_images(brdf, camera, lights, spectra, w, dirs, P, on, img):
    """Add F(θ, λ) L_light(λ) where the mirror of the view ray meets a lamp of finite size
    (a directional light's disc, a point light's sphere)."""
    m = -dirs.copy()
    m[..., :2] *= -1.0  # mirror direction of the view ray (towards where the light must be)
    for lt, sp in zip(lights, spectra):
        if isinstance(lt, DirectionalLight):
            if lt.angular_diameter_deg <= 0:
                continue
            a = np.radians(lt.angular_diameter_deg) / 2
            hit = on & (m @ np.asarray(lt.direction) >= np.cos(a))
            lum = sp / (2 * np.pi * (1 - np.cos(a)))  # E⊥ / Ω
        else:
            if lt.radius_mm <= 0:
                continue
            c = np.asarray(lt.position_mm)
            oc = c - P
            tca = np.einsum("...k,...k->...", oc, m)
            d2 = np.einsum("...k,...k->...", oc, oc) - tca * tca
            hit = on & (tca > 0) & (d2 <= lt.radius_mm ** 2)
            lum = sp / (np.pi * (lt.radius_mm * 1e-3) ** 2)  # I / (π ρ²), ρ in m
        if not hit.any():
            continue
        wo = -dirs[hit]
        wo[:, 2] = np.maximum(wo[:, 2], 0.0)
        wo /= np.linalg.norm(wo, axis=1, keepdims=True)
        F = brdf.specular_reflectance(w, wo)
        img[hit] += (F * lum[None, :]).astype(np.float32)


#: tilt variants of the unit cell (see :func:`_tilt_variants`): enough copies for
#: ~2·10⁵ distinct flake tilts, at most 64, and at most 8·10⁶ entries of normal grids
_TILT_SAMPLE_TARGET = 200_000
_MAX_TILT_VARIANTS = 64
_MAX_GRID_ENTRIES = 8_000_000


def _tilt_variants(fl, n_var: int) -> np.ndarray:
    """``n_var`` copies (n_var, N, 3) of the cell's flake normals with the tilts θ_k moved
    by a Cranley–Patterson rotation of their cumulative probability,
    θ_k^(v) = F⁻¹((F(θ_k) + v / n_var) mod 1), azimuths kept (variant 0 = the cell).

    Why: tiling repeats the cell's N flakes, and the per-tile rotation about the plate
    normal changes only their azimuths, so without variants every tile has the *same* N
    tilt magnitudes. The glint density around a light's highlight (half vector h' at
    angle θh from the normal) is then the cell's empirical tilt histogram, which at small
    θ holds a handful of flakes (grey metallic seed cell, N = 2103, σ = 12°: 1.9 expected
    below 0.5°, 7.4 below 1°) — a deterministic dark (or bright) spot or ring at the
    mirror point that no amount of averaging over pixels removes. Each variant's tilts
    still follow F exactly (the shift maps a uniform variable to a uniform one), and the
    union over variants is stratified in F, so the tile-averaged density of normals is
    the model p(θ) down to θ = 0. F is the cell's tilt distribution (``fl.tilt``), or a
    kernel estimate of its normals when unknown (deposit cells)."""
    from nmmm.appearance.flakes import TiltDistribution

    nrm = np.asarray(fl.normals, float)
    if n_var <= 1:
        return np.ascontiguousarray(nrm[None])
    tilt = getattr(fl, "tilt", None)
    if tilt is None:
        tilt = TiltDistribution.from_normals(nrm)
    th = np.degrees(np.arccos(np.clip(nrm[:, 2], -1.0, 1.0)))
    ph = np.arctan2(nrm[:, 1], nrm[:, 0])
    cdf = np.asarray(tilt._cdf, float)
    u = np.interp(th, tilt.tilt_deg, cdf)
    shifts = np.arange(n_var, dtype=float)[:, None] / n_var
    th_v = np.radians(np.interp((u[None, :] + shifts) % 1.0, cdf, tilt.tilt_deg))
    th_v[0] = np.radians(th)  # variant 0: the cell itself
    s = np.sin(th_v)
    out = np.stack([s * np.cos(ph), s * np.sin(ph), np.cos(th_v)], axis=-1)
    return np.ascontiguousarray(out)


def _render_glints(plate, camera, lights, spectra, w, sigma, P_on, img, randomize_tiles=True, tile_seed=0,
                   area_splat=True):
    fl = plate.flakes
    tab = plate.smooth_brdf.prepare(w)
    n = float(tab.n)
    cw, ch = plate.cell_mm
    nx, ny = plate.cells
    hx, hy = plate.size_mm[0] / 2, plate.size_mm[1] / 2
    # visible tiles
    xmin, ymin = P_on[:, 0].min(), P_on[:, 1].min()
    xmax, ymax = P_on[:, 0].max(), P_on[:, 1].max()
    i0 = max(int(math.floor((xmin + hx) / cw)) - 1, 0)
    i1 = min(int(math.floor((xmax + hx) / cw)) + 2, nx)
    j0 = max(int(math.floor((ymin + hy) / ch)) - 1, 0)
    j1 = min(int(math.floor((ymax + hy) / ch)) + 2, ny)
    # flakes of the unit cell (mm) and a grid on their normals
    fpos = np.ascontiguousarray(fl.positions_nm * 1e-6)
    fnrm = np.ascontiguousarray(fl.normals)
    farea = fl.areas_nm2 * 1e-12
    fdiam = np.ascontiguousarray(np.asarray(fl.diameters_nm, float) * 1e-6)
    # attenuation by the flakes above each flake: exp(-τ_e S ζ) with ζ = τ_above / τ, the
    # same mean-field factor as nmmm.appearance.brdf.flake_list_reflection
    if hasattr(fl, "optical_depth_above") and fl.optical_depth > 0:
        fzeta = np.asarray(fl.optical_depth_above(), float) / fl.optical_depth
    else:
        top, bottom = fl.layer_depth_nm
        fzeta = np.clip((fl.depth_nm - top) / max(bottom - top, 1e-9), 0.0, 1.0)
    cut = 3.0
    mfac = min(2.0, 1.1 / (2 * math.sqrt(max(n * n - 1, 1e-6))))
    G = int(np.clip(4.0 / (mfac * cut * sigma), 4, 512))
    if randomize_tiles:
        n_var = max(1, min(_MAX_TILT_VARIANTS, int(math.ceil(_TILT_SAMPLE_TARGET / max(len(fl), 1))),
                           int(_MAX_GRID_ENTRIES // (G * G + 1))))
        fnrm = _tilt_variants(fl, n_var)
    else:
        fnrm = fnrm[None]
    bx = np.clip(((fnrm[..., 0] + 1) * 0.5 * G).astype(np.int64), 0, G - 1)
    by = np.clip(((fnrm[..., 1] + 1) * 0.5 * G).astype(np.int64), 0, G - 1)
    key = by * G + bx
    order = np.ascontiguousarray(np.argsort(key, axis=1, kind="stable").astype(np.int64))
    gstart = np.ascontiguousarray(np.stack([np.searchsorted(kv[o], np.arange(G * G + 1))
                                            for kv, o in zip(key, order)]).astype(np.int64))
    nl = len(lights)
    lkind = np.array([0 if isinstance(lt, DirectionalLight) else 1 for lt in lights], np.int64)
    lvec = np.array([lt.direction if isinstance(lt, DirectionalLight) else lt.position_mm for lt in lights], float)
    lscale = np.ones(nl)  # the light spectra (espec) carry the irradiance / intensity
    cam = np.asarray(camera.position_mm, float)
    r, u, f = camera.basis()
    tx, ty = camera.tan_half
    sx, sy = camera.shift
    Wd, Hd = camera.resolution
    a_tab = np.ascontiguousarray(tab.a_tab, float)
    nrow = max(j1 - j0, 0)
    counts = np.zeros(nrow, np.int64)
    offsets = np.zeros(nrow, np.int64)
    e0 = np.zeros(0, np.int64)
    args = (cam, r, u, f, tx, ty, sx, sy, Wd, Hd, hx, hy, cw, ch, i0, i1, j0, j1,
            fpos, fnrm, farea, fdiam, fzeta, G, gstart, order, lkind, lvec, lscale, n, sigma, cut, a_tab, tab.step,
            bool(randomize_tiles), int(tile_seed), bool(area_splat))
    _glint_tiles(False, offsets, e0, np.zeros(0), np.zeros((0, 4)), e0, counts, *args)
    total = int(counts.sum())
    if total == 0:
        return 0
    offsets[1:] = np.cumsum(counts)[:-1]
    rec_pix = np.empty(total, np.int64)
    rec_w = np.empty(total)
    rec_th = np.empty((total, 4))
    rec_li = np.empty(total, np.int64)
    _glint_tiles(True, offsets, rec_pix, rec_w, rec_th, rec_li, counts, *args)
    espec = np.ascontiguousarray(np.stack(spectra), float)
    tau_e = np.ascontiguousarray(np.broadcast_to(tab.tau_e, (w.size,)), float)
    flat = img.reshape(-1, w.size)
    order = np.argsort(rec_pix, kind="stable")
    rec_pix, rec_w, rec_th, rec_li = rec_pix[order], rec_w[order], rec_th[order], rec_li[order]
    starts = np.flatnonzero(np.r_[True, rec_pix[1:] != rec_pix[:-1], True]).astype(np.int64)
    _glint_splat(flat, starts, rec_pix, rec_w, rec_th, rec_li, np.ascontiguousarray(tab.Tc), np.ascontiguousarray(tab.Rf),
                 tab.step, tau_e, bool(np.ptp(tau_e) <= 1e-12 * max(1.0, float(tau_e.max()))), espec)
    return total


def render_stereo_plate(plate: PaintedPlate, position_mm=(0.0, 0.0, 400.0), look_at_mm=(0.0, 0.0, 0.0),
                        interocular_mm: float = 65.0, fov_deg: float = 20.0, resolution=(512, 341),
                        up=(0.0, 1.0, 0.0), **kwargs) -> tuple[SpectralImage, SpectralImage]:
    """Left- and right-eye images of the same plate (same flakes), cameras from
    :func:`~nmmm.appearance.render.camera.stereo_pair`; ``kwargs`` go to :func:`render_plate`."""
    left, right = stereo_pair(position_mm, look_at_mm, interocular_mm, up, fov_deg, resolution)
    return render_plate(plate, left, **kwargs), render_plate(plate, right, **kwargs)
