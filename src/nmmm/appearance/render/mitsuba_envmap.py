"""A spectral environment map emitter for Mitsuba 3 (``nmmm_envmap``).

Mitsuba's own ``envmap`` is RGB (spectra are up-sampled from RGB); ``nmmm_envmap`` holds a
latitude–longitude map of **spectral** radiance, L(θ, φ, λ) on nmmm's wavelength grid
(z up = the plate normal; θ from the zenith, φ from +x towards +y), compressed on a few
basis spectra (SVD) so that each of Mitsuba's sampled wavelengths is evaluated exactly
from the tabulated spectra. Directions are sampled uniformly on the sphere (unbiased; a
luminance-driven sampler would reduce noise for peaky maps).

Public functions
----------------
- :func:`latlong_environment` — build the (H, W, L) radiance of a simple sky: a zenith and
  a horizon spectrum blended with elevation, optional ground below the horizon.
- :func:`envmap_emitter` — the scene-dictionary entry ``{"type": "nmmm_envmap", ...}`` of an
  (H, W, L) radiance map.
- :func:`register_nmmm_envmap` — register the plugin with the current variant.

References
----------
- Mitsuba 3 documentation: emitters (``envmap``, ``constant``), Python plugins.
- M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed. (2023) §12.5
  (image infinite lights).
"""

from __future__ import annotations

import uuid

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.spectra import check_finite

__all__ = ["latlong_environment", "envmap_emitter", "register_nmmm_envmap"]

_MAPS: dict = {}
_REGISTERED: set = set()


def latlong_environment(wavelength_nm, zenith, horizon, ground=None, height: int = 32, width: int = 64) -> np.ndarray:
    """(height, width, L) spectral radiance of a sky blending ``zenith`` (at θ = 0) into
    ``horizon`` (at θ = 90°) as cos θ, and ``ground`` (default: horizon × 0.2) below."""
    w = np.asarray(wavelength_nm, float).ravel()
    z = np.broadcast_to(np.asarray(check_finite(zenith, "zenith"), float), w.shape)
    h = np.broadcast_to(np.asarray(check_finite(horizon, "horizon"), float), w.shape)
    g = 0.2 * h if ground is None else np.broadcast_to(np.asarray(check_finite(ground, "ground"), float), w.shape)
    if np.any(z < 0) or np.any(h < 0) or np.any(g < 0):
        raise InvalidInputError("environment radiance must be >= 0")
    th = (np.arange(height) + 0.5) / height * np.pi
    t = np.clip(np.cos(th), 0, 1)[:, None]
    sky = t * z[None, :] + (1 - t) * h[None, :]
    rad = np.where((th < np.pi / 2)[:, None], sky, g[None, :])
    return np.broadcast_to(rad[:, None, :], (height, width, w.size)).copy()


def envmap_emitter(radiance, wavelength_nm, rank: int = 6, scale: float = 1.0) -> dict:
    """Scene entry for an (H, W, L) spectral radiance map on ``wavelength_nm``."""
    r = np.asarray(check_finite(radiance, "environment radiance"), float)
    w = np.asarray(wavelength_nm, float).ravel()
    if r.ndim != 3 or r.shape[2] != w.size:
        raise InvalidInputError(f"radiance must be (height, width, {w.size}), got {r.shape}")
    if np.any(r < 0):
        raise InvalidInputError("environment radiance must be >= 0")
    M = r.reshape(-1, w.size) * float(scale)
    U, S, Vt = np.linalg.svd(M, full_matrices=False)
    k = int(min(rank, w.size, M.shape[0]))
    basis = Vt[:k].T
    coeff = (M @ basis).reshape(r.shape[:2] + (k,))
    key = uuid.uuid4().hex[:12]
    _MAPS[key] = {"coeff": coeff.astype(np.float32), "basis": basis.astype(np.float32), "wavelength_nm": w}
    return {"type": "nmmm_envmap", "map": key}


def register_nmmm_envmap(mi):
    """Register ``nmmm_envmap`` with the current Mitsuba variant (idempotent)."""
    variant = mi.variant()
    if variant in _REGISTERED:
        return
    import drjit as dr

    class NmmmEnvmap(mi.Emitter):
        def __init__(self, props):
            mi.Emitter.__init__(self, props)
            key = props["map"]
            if key not in _MAPS:
                raise InvalidInputError(f"nmmm_envmap: unknown map key {key!r}; build it with envmap_emitter()")
            m = _MAPS[key]
            w = m["wavelength_nm"]
            self.l0, self.l1, self.nl = float(w[0]), float(w[-1]), int(w.size)
            self.k = int(m["coeff"].shape[-1])
            self.coeff = mi.Texture2f(mi.TensorXf(np.ascontiguousarray(m["coeff"])),
                                      wrap_mode=dr.WrapMode.Repeat)
            self.basis = mi.Texture1f(mi.TensorXf(np.ascontiguousarray(m["basis"])))
            self.m_flags = mi.EmitterFlags.Infinite | mi.EmitterFlags.SpatiallyVarying
            self.radius = 1e6

        def set_scene(self, scene):
            bs = scene.bbox().bounding_sphere()
            self.radius = float(max(bs.radius, 1.0)) * 2.0

        def _radiance(self, d, wavelengths):
            th = dr.safe_acos(d.z)
            ph = dr.atan2(d.y, d.x)
            # column j holds φ in [2πj/W, 2π(j+1)/W) from +x towards +y, as LatLongEnvironment.texel
            # (the u = φ/2π + 0.5 of Mitsuba's own envmap turned the map by 180°); φ wraps (Repeat)
            u = mi.Point2f(ph * (0.5 / dr.pi), th / dr.pi)
            c = self.coeff.eval(u)
            vals = []
            for j in range(4):
                x = dr.clip((wavelengths[j] - self.l0) / (self.l1 - self.l0), 0.0, 1.0)
                b = self.basis.eval(mi.Point1f((x * (self.nl - 1) + 0.5) / self.nl))
                acc = mi.Float(0.0)
                for q in range(self.k):
                    acc += c[q] * b[q]
                vals.append(dr.maximum(acc, 0.0))
            value = mi.UnpolarizedSpectrum(vals[0], vals[1], vals[2], vals[3])
            return mi.depolarizer(value) if mi.is_polarized else value  # unpolarized emission

        def eval(self, si, active=True):
            return self._radiance(-si.wi, si.wavelengths)

        def sample_direction(self, it, sample, active=True):
            d = mi.warp.square_to_uniform_sphere(sample)
            ds = mi.DirectionSample3f()
            ds.p = it.p + d * self.radius
            ds.n = -d
            ds.uv = sample
            ds.time = it.time
            ds.pdf = mi.Float(1.0 / (4 * dr.pi))
            ds.delta = mi.Bool(False)
            ds.d = d
            ds.dist = mi.Float(dr.inf)
            ds.emitter = mi.EmitterPtr(self)
            return ds, self._radiance(d, it.wavelengths) * (4 * dr.pi)

        def pdf_direction(self, it, ds, active=True):
            return mi.Float(1.0 / (4 * dr.pi))

        def eval_direction(self, it, ds, active=True):
            return self._radiance(ds.d, it.wavelengths)

        def sample_ray(self, time, sample1, sample2, sample3, active=True):
            raise NotImplementedError("nmmm_envmap supports camera paths (path/direct integrators), not light tracing")

        def bbox(self):
            return mi.ScalarBoundingBox3f()

        def traverse(self, callback):
            pass

        def parameters_changed(self, keys):
            pass

        def to_string(self):
            return f"NmmmEnvmap[rank {self.k}]"

    mi.register_emitter("nmmm_envmap", lambda props: NmmmEnvmap(props))
    _REGISTERED.add(variant)
