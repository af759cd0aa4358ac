"""Lat-long environment maps on a plate: the non-Dirac BRDF terms integrated over cells of
the upper hemisphere (``_envmap_smooth``, a quadrature on a coarser grid of pixels,
interpolated back by ``_interp_axis``) and the smooth coat's mirror image of the map at
full resolution (``_mirror_env``, Numba); and :class:`ViewingBooth`, the seed's viewing
scene as a source plus a spectral environment map of the booth's grey walls.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nmmm.appearance.render.latlong_lookup import _env_taps, envmap_lookup_bilinear  # noqa: F401 (re-exported)
from nmmm.errors import InvalidInputError
from nmmm.spectra import check_finite

__all__ = ["ViewingBooth"]

try:  # pragma: no cover - numba is a dependency, but keep a NumPy path
    import numba as _nb
except ImportError:  # pragma: no cover
    _nb = None


def _background_py(img, dirs, off, h, wd, env):
    """img[i, j] = the map seen along ``dirs[i, j]`` (bilinear) where ``off[i, j]``."""
    H, W, L = img.shape
    for i in _prange(H):
        for j in range(W):
            if not off[i, j]:
                continue
            t0, t1, t2, t3, a0, a1, a2, a3 = _env_taps(dirs[i, j, 0], dirs[i, j, 1], dirs[i, j, 2], h, wd)
            for k in range(L):
                img[i, j, k] = a0 * env[t0, k] + a1 * env[t1, k] + a2 * env[t2, k] + a3 * env[t3, k]


def _mirror_env_py(img, Fc, ri, rf, ci, cf, dirs, on, h, wd, env):
    """img += F(θo, λ) (bilinear from the coarse grid) × L_env(mirror of the view ray), the map
    bilinearly interpolated (``dirs`` are the view rays; the mirror flips their z)."""
    H = ri.size
    W = ci.size
    L = Fc.shape[2]
    for i in _prange(H):
        r0 = ri[i]
        fr = rf[i]
        for j in range(W):
            if not on[i, j]:
                continue
            c0 = ci[j]
            fc = cf[j]
            t0, t1, t2, t3, a0, a1, a2, a3 = _env_taps(dirs[i, j, 0], dirs[i, j, 1], -dirs[i, j, 2], h, wd)
            for k in range(L):
                F = ((1 - fr) * (1 - fc) * Fc[r0, c0, k] + fr * (1 - fc) * Fc[r0 + 1, c0, k]
                     + (1 - fr) * fc * Fc[r0, c0 + 1, k] + fr * fc * Fc[r0 + 1, c0 + 1, k])
                img[i, j, k] += F * (a0 * env[t0, k] + a1 * env[t1, k] + a2 * env[t2, k] + a3 * env[t3, k])


if _nb is not None:
    _prange = _nb.prange
    _background = _nb.njit(parallel=True, cache=True)(_background_py)
    _mirror_env = _nb.njit(parallel=True, cache=True)(_mirror_env_py)
else:  # pragma: no cover
    _prange = range
    _background = _background_py
    _mirror_env = _mirror_env_py


def _envmap_smooth(brdf, w, envmap, wo_grid, hit_grid, sub: int = 4, n_theta: int = 16, n_phi: int = 32, quad=None):
    """Radiance reflected from a lat-long environment by the non-Dirac BRDF terms,
    ∑_k f(ω_k, ωo) cos θ_k ΔΩ_k L_k over n_theta × n_phi cells of the upper hemisphere,
    on every ``sub``-th node of the coarse grid, interpolated back onto it (``quad``: the map's
    ``upper_quadrature(w, n_theta, n_phi)`` if already computed)."""
    nr, nc = wo_grid.shape[:2]
    rs = np.unique(np.r_[np.arange(0, nr, sub), nr - 1])
    cs = np.unique(np.r_[np.arange(0, nc, sub), nc - 1])
    wo = wo_grid[np.ix_(rs, cs)].reshape(-1, 3)
    qd, qs, qr = envmap.upper_quadrature(w, n_theta, n_phi) if quad is None else quad
    N, K = wo.shape[0], qd.shape[0]
    out = np.zeros((N, w.size))
    comps = ("specular", "flakes", "base", "multiple")
    wt = (qd[:, 2] * qs)[:, None] * qr  # (K, L): cos θ_k ΔΩ_k L_k
    # all (cell, node) pairs in a few large BRDF calls (one call per cell paid a per-call floor
    # of ~10 ms on a loaded machine: 128 calls of 2752 pairs ran at 20 M evaluations/s)
    kb = max(1, min(K, (1 << 17) // max(N, 1)))
    for k0 in range(0, K, kb):
        k1 = min(K, k0 + kb)
        wi = np.repeat(qd[k0:k1], N, axis=0)
        f = brdf.evaluate(w, wi, np.tile(wo, (k1 - k0, 1)), components=comps).reshape(k1 - k0, N, w.size)
        out += np.einsum("knl,kl->nl", f, wt[k0:k1])
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


#: luminous efficacy of radiation at 555 nm, lm/W (CIE)
_KM = 683.002


def _luminance_weight(w):
    """Photopic ȳ(λ) (CIE 1931 2°) on ``w`` (nm) times the grid step (∫ ȳ S dλ ≈ weights · S)."""
    import colour

    cmf = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    y = np.interp(w, cmf.wavelengths, cmf.values[:, 1], left=0.0, right=0.0)
    return y * np.gradient(w) if w.size > 1 else y


@dataclass(frozen=True)
class ViewingBooth:
    """A viewing booth around the plate (the seed's viewing scene), in the plate frame (mm).

    The plate lies on the booth's floor (z = 0) at its centre; the booth is a box
    ``size_mm`` = (width along x, depth along y, height along z), open towards the viewer
    (−y). Walls, ceiling and floor are matt (Lambertian) greys of reflectance
    ``wall_reflectance`` and ``floor_reflectance`` (ISO 3664 asks for N5–N7, ρ ≈ 0.2–0.4).
    The source is a small sphere of radius ``source_radius_mm`` with the spectrum
    ``illuminant`` (a D65 simulator by default): ``source = "overhead"`` at the ceiling
    above the plate, ``"45"`` at 45° from the plate normal behind it (−y viewer, +y source,
    ``source_distance_mm`` from the plate centre). Its intensity is set so that the plate
    centre receives ``illuminance_lux`` (ISO 3664 P1: 2000 lx).

    :meth:`lights` gives the source as a :class:`~nmmm.appearance.render.PointLight` (it
    lights the plate with the cos θ / r² fall-off across it and its mirror image appears in
    a smooth clear coat where the geometry puts it); :meth:`environment` the booth as a
    :class:`~nmmm.appearance.render.LatLongEnvironment` seen from the plate centre: each
    surface's radiance is ρ/π (E_direct + E_inter), E_direct = I cos θ / r² from the source
    and E_inter the integrating-sphere inter-reflection ρ̄ Φ / (A (1 − ρ̄)) (Φ = 4π I, A the
    box's area); directions below the horizon see the floor around the plate (from a point
    half the booth's height above it). The coat mirrors this map with its Fresnel factor,
    the paint's diffuse and flake terms integrate it, and pixels off the plate show it — a
    plain grey background instead of a black void.
    """

    size_mm: tuple = (800.0, 800.0, 600.0)
    wall_reflectance: float = 0.2
    floor_reflectance: float = 0.2
    source: str = "45"
    source_distance_mm: float = 500.0
    source_radius_mm: float = 25.0
    illuminant: object = "D65"
    illuminance_lux: float = 2000.0

    def __post_init__(self):
        s = np.asarray(check_finite(self.size_mm, "booth size_mm"), float).ravel()
        if s.shape != (3,) or np.any(s <= 0):
            raise InvalidInputError(f"booth size_mm must be (width, depth, height) > 0 in mm, got {self.size_mm!r}")
        object.__setattr__(self, "size_mm", tuple(float(x) for x in s))
        for key in ("wall_reflectance", "floor_reflectance"):
            v = float(check_finite(getattr(self, key), key))
            if not 0 <= v < 1:
                raise InvalidInputError(f"booth {key} must lie in [0, 1) (a matt grey), got {v!r}")
            object.__setattr__(self, key, v)
        if self.source not in ("overhead", "45"):
            raise InvalidInputError(f"booth source must be 'overhead' or '45', got {self.source!r}")
        for key in ("source_distance_mm", "source_radius_mm", "illuminance_lux"):
            v = float(check_finite(getattr(self, key), key))
            if v <= 0:
                raise InvalidInputError(f"booth {key} must be > 0, got {v!r}")
            object.__setattr__(self, key, v)
        p = self.source_position_mm
        W, D, H = self.size_mm
        if abs(p[0]) > W / 2 or abs(p[1]) > D / 2 or p[2] + self.source_radius_mm > H:
            raise InvalidInputError(f"booth source_distance_mm = {self.source_distance_mm:g} puts the source at "
                                    f"{np.round(p, 1).tolist()} mm, outside the {W:g} x {D:g} x {H:g} mm booth; "
                                    "shorten it or enlarge size_mm")

    @property
    def source_position_mm(self) -> np.ndarray:
        H = self.size_mm[2]
        if self.source == "overhead":
            return np.array([0.0, 0.0, H - 2.0 * self.source_radius_mm])
        d = self.source_distance_mm / math.sqrt(2.0)
        return np.array([0.0, d, d])

    def check_plate(self, plate) -> None:
        """Refuse a plate that does not fit on the booth's floor."""
        W, D, _ = self.size_mm
        pw, ph = plate.size_mm
        if pw > W or ph > D:
            raise InvalidInputError(f"the plate ({pw:g} x {ph:g} mm, size_mm) is larger than the booth's floor "
                                    f"({W:g} x {D:g} mm, booth size_mm); enlarge the booth or use a smaller plate")

    def lights(self):
        """[the source as a PointLight], its intensity giving ``illuminance_lux`` at the plate centre."""
        from nmmm.appearance.render.lights import PointLight, spd

        w = np.arange(380.0, 781.0, 5.0)  # ȳ is < 1e-4 outside
        lum = _KM * float(_luminance_weight(w) @ spd(self.illuminant).on(w))  # lm/m² per unit irradiance SPD
        p = self.source_position_mm
        r_m = float(np.linalg.norm(p)) * 1e-3
        cos = p[2] * 1e-3 / r_m
        intensity = self.illuminance_lux * r_m ** 2 / (cos * lum)
        return [PointLight(tuple(p), self.illuminant, intensity, self.source_radius_mm)]

    def scene(self, plate, wavelength_nm, height: int = 256, width: int = 512) -> dict:
        """``lights=`` and ``environment=`` for :func:`~nmmm.appearance.render.render_plate`
        (the plate checked to fit on the floor): ``render_plate(plate, camera, **booth.scene(plate, w),
        wavelength_nm=w)``."""
        self.check_plate(plate)
        return dict(lights=self.lights(), environment=self.environment(wavelength_nm, height, width))

    def environment(self, wavelength_nm, height: int = 128, width: int = 256, supersample: int = 4):
        """The booth's grey surfaces as a spectral lat-long map (see the class docstring). Each
        texel is the mean over ``supersample`` × ``supersample`` directions spread over it, so
        the edges where walls, floor and ceiling meet (where the direct irradiance jumps) are
        anti-aliased instead of printed as a staircase of whole texels."""
        from nmmm.appearance.render.lights import LatLongEnvironment

        w = np.asarray(wavelength_nm, float).ravel()
        light = self.lights()[0]
        I = light.spectral(w)  # (L,) W/sr/nm per unit
        W, D, H = self.size_mm
        ss = int(supersample)
        if ss < 1:
            raise InvalidInputError(f"booth environment supersample must be >= 1, got {supersample!r}")
        sub = (np.arange(ss) + 0.5) / ss
        ph = ((np.arange(width)[:, None] + sub[None, :]).ravel()) / width * 2 * np.pi
        factor = np.empty((height, width))
        rows_per = max(1, 65536 // (width * ss * ss))
        for i0 in range(0, height, rows_per):
            i1 = min(height, i0 + rows_per)
            th = ((np.arange(i0, i1)[:, None] + sub[None, :]).ravel()) / height * np.pi
            T, P = np.meshgrid(th, ph, indexing="ij")
            d = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
            f = self._radiance_factor(d)
            factor[i0:i1] = f.reshape(i1 - i0, ss, width, ss).mean(axis=(1, 3))
        L = factor[..., None] * I[None, None, :]
        return LatLongEnvironment(w, L, name=f"viewing booth ({W:g} x {D:g} x {H:g} mm, walls {self.wall_reflectance:g})")

    def _radiance_factor(self, d):
        """ρ/π (E_direct + E_inter) per unit source intensity along unit directions d (..., 3)."""
        W, D, H = self.size_mm
        origin = np.where(d[..., 2:3] < 0, np.array([0.0, 0.0, H / 2]), 0.0)
        lo, hi = np.array([-W / 2, -D / 2, 0.0]), np.array([W / 2, D / 2, H])
        with np.errstate(divide="ignore", invalid="ignore"):
            t_hi = np.where(d > 0, (hi - origin) / d, np.inf)
            t_lo = np.where(d < 0, (lo - origin) / d, np.inf)
        t_ax = np.minimum(t_hi, t_lo)
        axis = np.argmin(t_ax, axis=-1)
        t = np.take_along_axis(t_ax, axis[..., None], -1)
        X = origin + t * d
        n = np.zeros_like(d)
        sign = -np.sign(np.take_along_axis(d, axis[..., None], -1))[..., 0]
        np.put_along_axis(n, axis[..., None], sign[..., None], -1)
        floor = (axis == 2) & (sign > 0)
        rho = np.where(floor, self.floor_reflectance, self.wall_reflectance)
        to_src = self.source_position_mm - X
        r = np.linalg.norm(to_src, axis=-1)
        cos = np.clip(np.sum(to_src * n, -1) / r, 0.0, None)
        e_direct = cos / (r * 1e-3) ** 2  # per unit I
        area = 2 * (W * D + W * H + D * H) * 1e-6  # m²
        rho_mean = (W * D * self.floor_reflectance + (W * D + 2 * W * H + 2 * D * H) * self.wall_reflectance) \
            / (2 * (W * D + W * H + D * H))
        e_inter = rho_mean * 4 * np.pi / (area * (1 - rho_mean))
        return rho / np.pi * (e_direct + e_inter)
