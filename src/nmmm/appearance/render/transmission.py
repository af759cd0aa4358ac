"""Plates that are not paints: a glass plate seen in transmission and reflection, and a
thin-film stack seen in reflection (issue 19 item 1).

- :class:`GlassPlate` — a thick homogeneous plate of complex index N(λ) and thickness d in
  air: per polarization, the Fresnel reflectance R(θ) of one face, the internal transmission
  a = exp(−α d / cos θt) (α = 4πk/λ, θt from Snell's law) and the incoherent sum of the
  multiple reflections between the two faces,

      T = (1 − R)² a / (1 − R² a²),   R_plate = R + (1 − R)² R a² / (1 − R² a²),

  averaged over s and p (unpolarized). At normal incidence T is exactly
  :func:`nmmm.layers.thick_plate.plate_transmittance`, the spectrum a ``[plate]`` recipe reports.
- :class:`ThinFilmPlate` — a :class:`nmmm.layers.Stack` on a black backing: its unpolarized
  specular reflectance R(θ, λ) by transfer matrices (coherent layers interfere), tabulated on
  a grid of angles and interpolated per pixel, so the colour shifts across the plate as the
  angle of view does. It transmits nothing to the viewer.
- :func:`render_specular_plate` — the spectral image of such a plate (lying in z = 0, as
  :func:`nmmm.appearance.render.render_plate`'s): each pixel on the plate is

      L(λ) = R(θ, λ) L_env(mirror of the view ray) + T(θ, λ) L_behind(λ)

  with L_behind the ``back_radiance`` (a light table under the plate) or the environment
  straight along the view ray (the plate's faces are parallel: the ray leaves it parallel to
  itself, displaced by less than d); the mirror images of finite lamps are added with R(θ)
  (the renderer's own ``_add_light_images``). Pixels off the plate see the light table (rays
  going down) or the environment.

References
----------
- M. Born, E. Wolf, *Principles of Optics*, 7th ed., Cambridge University Press (1999), §1.5.2
  (Fresnel's formulae), §13 / §14.1 (absorbing media); the incoherent plate sum e.g.
  G. Stokes (1862), Proc. R. Soc. Lond. 11, 545.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.spectra import as_wavelength_nm, check_finite

__all__ = ["GlassPlate", "ThinFilmPlate", "render_specular_plate"]


def _cos_of(wo):
    wo = np.asarray(wo, float)
    return np.clip(wo[..., 2] / np.linalg.norm(wo, axis=-1), 0.0, 1.0)


@dataclass(frozen=True)
class GlassPlate:
    """A glass plate of index ``nk`` (L,) complex on ``wavelength_nm`` and ``thickness_nm`` in air."""

    wavelength_nm: np.ndarray
    nk: np.ndarray
    thickness_nm: float
    name: str = "glass plate"

    def __post_init__(self):
        w = as_wavelength_nm(self.wavelength_nm).ravel()
        N = np.asarray(self.nk, complex).ravel()
        if N.shape != w.shape or not np.all(np.isfinite(N)):
            raise InvalidInputError(f"glass plate nk must be finite, one value per wavelength ({w.size}), got {N.shape}")
        if np.any(N.imag < 0) or np.any(N.real <= 0):
            raise InvalidInputError("glass plate nk must have n > 0 and k >= 0 (absorbing)")
        d = float(check_finite(self.thickness_nm, "thickness_nm"))
        if d <= 0:
            raise InvalidInputError(f"glass plate thickness_nm must be > 0, got {d!r}")
        object.__setattr__(self, "wavelength_nm", w)
        object.__setattr__(self, "nk", N)
        object.__setattr__(self, "thickness_nm", d)

    def _N(self, w):
        w = as_wavelength_nm(w).ravel()
        if w.shape == self.wavelength_nm.shape and np.allclose(w, self.wavelength_nm):
            return w, self.nk
        raise InvalidInputError(f"{self.name} was built on {self.wavelength_nm.size} wavelengths "
                                f"{self.wavelength_nm[0]:g}-{self.wavelength_nm[-1]:g} nm; render on that grid")

    def reflectance_transmittance(self, wavelength_nm, cos_theta):
        """Unpolarized (R, T) of the plate, each (..., L), at the angles of incidence whose cosines
        are ``cos_theta`` (...)."""
        w, N = self._N(wavelength_nm)
        ci = np.clip(np.asarray(cos_theta, float), 1e-6, 1.0)[..., None]
        si2 = 1.0 - ci**2
        ct = np.sqrt(1.0 - si2 / N**2)  # complex cos θt (Snell, N sin θt = sin θ)
        rs = (ci - N * ct) / (ci + N * ct)
        rp = (N * ci - ct) / (N * ci + ct)
        ctr = np.maximum(np.real(ct), 1e-6)
        a = np.exp(-4 * np.pi * N.imag / w * self.thickness_nm / ctr)
        R_out = np.zeros(np.broadcast(ci, N).shape)
        T_out = np.zeros_like(R_out)
        for r in (rs, rp):
            R = np.abs(r) ** 2
            den = 1.0 - R**2 * a**2
            T_out += 0.5 * (1 - R) ** 2 * a / den
            R_out += 0.5 * (R + (1 - R) ** 2 * R * a**2 / den)
        return R_out, T_out

    def specular_reflectance(self, wavelength_nm, wo):
        """R(θo, λ) (N, L) for outgoing directions ``wo`` (N, 3) (the lamps' mirror images)."""
        return self.reflectance_transmittance(wavelength_nm, _cos_of(wo))[0]


@dataclass(frozen=True)
class ThinFilmPlate:
    """A thin-film :class:`nmmm.layers.Stack` on a black backing seen in reflection: R(θ, λ)
    tabulated at ``n_angles`` angles from 0 to 89° (:meth:`from_stack`)."""

    wavelength_nm: np.ndarray
    angles_deg: np.ndarray
    reflectance: np.ndarray  # (A, L)
    name: str = "thin-film plate"
    stack: object = field(default=None, repr=False, compare=False)

    @classmethod
    def from_stack(cls, stack, wavelength_nm, n_angles: int = 90, name: str = "thin-film plate"):
        w = as_wavelength_nm(wavelength_nm).ravel()
        if int(n_angles) < 2:
            raise InvalidInputError(f"n_angles must be >= 2, got {n_angles!r}")
        a = np.linspace(0.0, 89.0, int(n_angles))
        R = np.asarray(stack.rt(w, a).R, float).reshape(w.size, a.size).T
        return cls(w, a, R, name, stack)

    def reflectance_transmittance(self, wavelength_nm, cos_theta):
        w = as_wavelength_nm(wavelength_nm).ravel()
        if w.shape != self.wavelength_nm.shape or not np.allclose(w, self.wavelength_nm):
            raise InvalidInputError(f"{self.name} was tabulated on {self.wavelength_nm.size} wavelengths; render on that grid")
        th = np.degrees(np.arccos(np.clip(np.asarray(cos_theta, float), 0.0, 1.0)))
        x = np.clip(th, self.angles_deg[0], self.angles_deg[-1])
        i = np.clip(np.searchsorted(self.angles_deg, x, side="right") - 1, 0, self.angles_deg.size - 2)
        t = ((x - self.angles_deg[i]) / (self.angles_deg[i + 1] - self.angles_deg[i]))[..., None]
        R = self.reflectance[i] * (1 - t) + self.reflectance[i + 1] * t
        return R, np.zeros_like(R)

    def specular_reflectance(self, wavelength_nm, wo):
        return self.reflectance_transmittance(wavelength_nm, _cos_of(wo))[0]


def _env_along(environment, w, d):
    from nmmm.appearance.render.lights import LatLongEnvironment, UniformEnvironment

    if isinstance(environment, LatLongEnvironment):
        return environment.lookup(w, d)
    if isinstance(environment, UniformEnvironment):
        return np.broadcast_to(environment.spectral(w), d.shape[:-1] + (w.size,))
    return np.zeros(d.shape[:-1] + (w.size,))


def render_specular_plate(optics, camera, size_mm=(150.0, 100.0), lights=(), environment=None, back_radiance=None,
                          wavelength_nm=None, max_memory_gb: float | None = None):
    """Spectral image of a :class:`GlassPlate` or :class:`ThinFilmPlate` of ``size_mm`` lying in
    z = 0, seen by ``camera`` (a :class:`~nmmm.appearance.render.PinholeCamera` in front of it)
    under ``lights`` (their mirror images only: a clear plate has no diffuse term) and
    ``environment`` (uniform or lat-long), in front of ``back_radiance`` (L,) — a light table
    under the plate — or, without one, the environment behind it (see the module docstring).

    The image's white reference is the light table when there is one (the bare table is display
    white), else a white diffuser at the plate centre under the same lights and environment."""
    from nmmm.appearance.render.lights import LatLongEnvironment, UniformEnvironment, default_wavelengths
    from nmmm.appearance.render.plate.renderer import (
        _add_light_images,
        _check_camera,
        _check_lights,
        _check_render_size,
        _light_at,
        _plate_hits,
    )
    from nmmm.appearance.render.plate.spectral_image import SpectralImage

    if not hasattr(optics, "reflectance_transmittance"):
        raise InvalidInputError("optics must be a GlassPlate or a ThinFilmPlate")
    w = optics.wavelength_nm if wavelength_nm is None else as_wavelength_nm(wavelength_nm).ravel()
    if w is None:
        w = default_wavelengths()
    _check_camera(None, camera)
    lights, environment = _check_lights(lights, environment)
    s = np.asarray(check_finite(size_mm, "plate size_mm"), float).ravel()
    if s.shape != (2,) or np.any(s <= 0):
        raise InvalidInputError(f"plate size_mm must be (width, height) > 0 mm, got {size_mm!r}")
    L = w.size
    if back_radiance is not None:
        back = np.asarray(check_finite(back_radiance, "back_radiance"), float).ravel()
        if back.shape != (L,) or np.any(back < 0):
            raise InvalidInputError(f"back_radiance must be {L} radiances >= 0 (one per wavelength), got shape {back.shape}")
    else:
        back = None
    Wd, Hd = camera.resolution
    _check_render_size(Wd, Hd, L, max_memory_gb)
    dirs = camera.pixel_directions()
    hit, P = _plate_hits(camera, dirs)
    on = hit & (np.abs(P[..., 0]) <= s[0] / 2) & (np.abs(P[..., 1]) <= s[1] / 2)
    if not on.any():
        raise InvalidInputError("no pixel centre of the camera falls on the plate: aim the camera at the plate "
                                f"({s[0]:g} x {s[1]:g} mm centred on the origin) or widen fov_deg")
    img = np.zeros((Hd, Wd, L), np.float32)
    off = ~on
    d_off = dirs[off]
    rad = _env_along(environment, w, d_off)
    if back is not None:  # the light table lies under everything: rays going down see it
        rad = np.where((d_off[:, 2] < 0)[:, None], back[None, :], rad)
    img[off] = rad
    d_on = dirs[on]
    R, T = optics.reflectance_transmittance(w, _cos_of(-d_on))
    m = d_on.copy()
    m[:, 2] *= -1.0
    behind = back[None, :] if back is not None else _env_along(environment, w, d_on)
    img[on] = (R * _env_along(environment, w, m) + T * behind).astype(np.float32)
    spectra = [lt.spectral(w) for lt in lights]
    _add_light_images(optics, camera, lights, spectra, w, dirs, P, on, img)
    if back is not None:
        white = back.copy()
    else:
        white = np.zeros(L)
        for lt, sp in zip(lights, spectra):
            _, sc = _light_at(lt, np.zeros((1, 3)))
            white += sc[0] * sp / np.pi
        if isinstance(environment, UniformEnvironment):
            white += environment.spectral(w)
        if isinstance(environment, LatLongEnvironment):
            qd, qs, qr = environment.upper_quadrature(w)
            white += (qs * qd[:, 2]) @ qr / np.pi
    meta = {"plate": f"{optics.name} {s[0]:g} x {s[1]:g} mm", "light_table": back is not None, "n_glints": 0}
    return SpectralImage(w, img, on, white, camera, meta)
