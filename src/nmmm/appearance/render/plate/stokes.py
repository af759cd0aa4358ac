"""Polarized rendering of a painted plate: spectral Stokes images and the view through a linear polarizer.

:func:`render_plate_stokes` renders S0 with :func:`~nmmm.appearance.render.plate.render_plate`
(the unpolarized radiance, unchanged) and adds the polarization (S1, S2, S3) of the paint's
Fresnel reflections, from the Mueller matrices of :mod:`nmmm.appearance.brdf.mueller` (amplitude
coefficients r_s, r_p of :func:`nmmm.layers.fresnel`). The sources (lamps, sky, environment map)
are unpolarized, so each term's Stokes vector is its radiance times the first column of its Mueller
chain, normalised to that column's S0 (so that S0 stays the unpolarized renderer's):

- the smooth coat's mirror Dirac (the sky or environment map seen in the coat, the finite lamps'
  mirror images): reflection air → coat at θo, polarized along s = n × ωo;
- a rough coat's GGX lobe, per light: each microfacet reflects at θ_d (ωi·h), polarized along
  s = ωi × ωo;
- the statistical flake term, per light: coat transmission air → coat (diattenuator),
  the flake's reflection in the binder at its local angle (a metal's retardance makes the light
  elliptical: S3 ≠ 0), coat transmission coat → air, each Mueller matrix in its own plane of
  incidence and the Stokes frame rotated between them;
- the rough coat's and the flakes' reflection of a sky or map (statistical, as in
  :func:`render_plate`, also on a plate with a flake cell): the same per-direction Stokes vectors
  integrated over 16 × 32 cells of the upper hemisphere on a coarse pixel grid.

The **diffuse body and the multiple-scattering lobe are depolarizing**: they add to S0 only (their
light crossed the coat twice, whose small diattenuation is neglected). The discrete flakes' glints
(a plate with a flake cell) carry the flake chain's Stokes state at their pixel: a flake glints
only when its normal is the binder half vector of (ωi, ωo), so the chain above, evaluated at that
half vector, is the glint's (within the glint spread); the glints of each light are drawn a second
time alone (deterministic: the same flakes) to weight its state.

Stokes frame of each pixel: x = the image's right axis, y = its up axis (both projected
perpendicular to the ray; (x, y, propagation towards the camera) right-handed). A linear polarizer
whose transmission axis is at α from the image's right axis, counter-clockwise as the viewer sees
the image (α = 0: horizontal, 90°: vertical), passes ½ (S0 + S1 cos 2α + S2 sin 2α). The coat's
reflection of a source is polarized along s, horizontal for a camera in the vertical plane of the
source: a vertical polarizer (90°) removes it entirely at Brewster's angle (θ_B = arctan n ≈ 56°
for n = 1.5) — the photographer's polarizing filter.

Public objects
--------------
- :class:`StokesImage` — (4, H, W, L) Stokes radiance; ``s0``, ``through_polarizer(angle_deg)``
  (:class:`SpectralImage`), ``degree_of_polarization()``, ``angle_of_polarization_deg()``,
  ``write_exr`` (Fichet et al. 2021 layout with S0..S3 channels).
- :func:`render_plate_stokes`.

References
----------
- E. Collett, *Polarized Light: Fundamentals and Applications*, Marcel Dekker (1993), ch. 4, 8.
- A. Fichet, R. Pacanowski, A. Wilkie, JCGT 10(3) (2021) — polarised spectral EXR channels S0..S3.
- A. Wilkie, A. Weidlich, "Polarised light in computer graphics", SIGGRAPH Asia courses (2012).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from nmmm.errors import InvalidInputError

__all__ = ["StokesImage", "render_plate_stokes"]


def _unit(v, fallback):
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    fb = np.broadcast_to(np.asarray(fallback, float), v.shape)
    return np.where(n > 1e-9, v / np.where(n > 1e-9, n, 1.0), fb)


def _perp(d):
    """Some unit vector perpendicular to each d (..., 3)."""
    a = np.where(np.abs(d[..., 2:3]) < 0.9, np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]))
    return _unit(np.cross(d, a), (1.0, 0.0, 0.0))


def _axis(a, b, d):
    """normalize(a × b), or a vector perpendicular to d where a ∥ b."""
    return _unit(np.cross(a, b), 0.0) + np.where(np.linalg.norm(np.cross(a, b), axis=-1, keepdims=True) > 1e-9,
                                                  0.0, _perp(d))


def _rotate(S, from_axis, to_axis, d):
    """Stokes (N, L, 4) from frame x = from_axis to x = to_axis about propagation d (N, 3)."""
    from nmmm.appearance.brdf.mueller import stokes_rotation

    R = stokes_rotation(from_axis, to_axis, d)  # (N, 4, 4)
    return np.einsum("nij,nlj->nli", R, S)


def _apply(M, S):
    """(N, L, 4, 4) @ (N, L, 4)."""
    return np.einsum("nlij,nlj->nli", M, S)


def _normalised(S):
    s0 = S[..., :1]
    return np.where(s0 > 0, S / np.where(s0 > 0, s0, 1.0), 0.0)


def _polarized_terms(brdf, w, wi, wo, xcam, flakes: bool = True):
    """Stokes BRDF (N, L, 4) (1/sr; S0 = the unpolarized term) of the coat's GGX lobe plus, with
    ``flakes``, the statistical flake term, for unpolarized light from ``wi`` seen along ``wo``
    (N, 3), in the frame whose x axis is ``xcam`` (N, 3) (perpendicular to ``wo``)."""
    from nmmm.appearance.brdf.mueller import coat_reflection_mueller

    coat = brdf.coat
    N, L = wi.shape[0], w.size
    out = np.zeros((N, L, 4))
    nvec = np.array([0.0, 0.0, 1.0])
    if coat.roughness > 0:
        f = brdf.evaluate(w, wi, wo, components=("specular",), below_surface="zero")
        h = _unit(wi + wo, nvec)
        cd = np.clip(np.einsum("nk,nk->n", wi, h), 0.0, 1.0)
        M = coat_reflection_mueller(coat, w, cd)
        S = _normalised(M[..., :, 0])
        S = _rotate(S, _axis(wi, wo, wo), xcam, wo)
        out += f[..., None] * S
    fl = getattr(brdf, "flakes", None)
    if flakes and fl is not None and fl.optical_depth > 0:
        f = brdf.evaluate(w, wi, wo, components=("flakes",), below_surface="zero")
        out += f[..., None] * _flake_chain(brdf, w, wi, wo, xcam)
    return out


def _flake_chain(brdf, w, wi, wo, xcam):
    """Normalised Stokes (N, L, 4) of unpolarized light from ``wi`` mirrored towards ``wo`` by a
    flake whose normal is the binder half vector: coat transmission in, flake reflection, coat
    transmission out, each in its plane of incidence (the Mueller chain of every glinting flake)."""
    from nmmm.appearance.brdf.mueller import (
        coat_transmission_mueller,
        flake_reflection_mueller,
    )

    coat, fl = brdf.coat, brdf.flakes
    nvec = np.array([0.0, 0.0, 1.0])
    n = float(np.mean(coat.index(w)))  # the BRDF's geometry index (as its tables)

    def inside(v):
        t = v[:, :2] / n
        return np.concatenate([t, np.sqrt(np.clip(1 - np.sum(t * t, axis=1, keepdims=True), 0, 1))], axis=1)

    wi_b, wo_b = inside(wi), inside(wo)
    m = _unit(wi_b + wo_b, nvec)
    cl = np.clip(np.einsum("nk,nk->n", wi_b, m), 0.0, 1.0)
    S = coat_transmission_mueller(coat, w, np.clip(wi[:, 2], 0, 1), into_coat=True)[..., :, 0]
    k1 = -wi_b  # propagation towards the flake
    s1 = _axis(nvec[None, :], wi, k1)
    s2 = _axis(wi_b, wo_b, k1)
    S = _apply(flake_reflection_mueller(fl.optics, w, cl, n), _rotate(S, s1, s2, k1))
    s3 = _axis(nvec[None, :], wo_b, wo_b)
    S = _apply(coat_transmission_mueller(coat, w, np.clip(wo_b[:, 2], 0, 1), into_coat=False),
               _rotate(S, s2, s3, wo_b))
    return _rotate(_normalised(S), s3, xcam, wo)


def _dirac_stokes(brdf, w, wo, xcam):
    """Normalised Stokes (N, L, 4) of the smooth coat's mirror reflection towards wo."""
    from nmmm.appearance.brdf.mueller import coat_reflection_mueller

    M = coat_reflection_mueller(brdf.coat, w, np.clip(wo[:, 2], 0, 1))
    S = _normalised(M[..., :, 0])
    return _rotate(S, _axis(np.array([[0.0, 0.0, 1.0]]), wo, wo), xcam, wo)


@dataclass(frozen=True, repr=False)
class StokesImage:
    """Spectral Stokes radiance ``stokes`` (4, H, W, L) (S0 = :class:`SpectralImage` radiance)
    in each pixel's frame (x = image right, y = image up; see the module docstring)."""

    wavelength_nm: np.ndarray
    stokes: np.ndarray
    on_plate: np.ndarray
    white_radiance: np.ndarray
    camera: object = None
    metadata: dict = field(default_factory=dict)

    def __repr__(self):
        _, h, w, L = self.stokes.shape
        return f"<StokesImage {w}x{h}, {L} wavelengths, S0..S3>"

    def _image(self, radiance, white, extra=None):
        from nmmm.appearance.render.plate.spectral_image import SpectralImage

        return SpectralImage(self.wavelength_nm, np.ascontiguousarray(radiance, np.float32), self.on_plate, white,
                             self.camera, {**self.metadata, **(extra or {})})

    @property
    def s0(self):
        """The unpolarized radiance as a :class:`SpectralImage` (what :func:`render_plate` gives)."""
        return self._image(self.stokes[0], self.white_radiance)

    def through_polarizer(self, angle_deg: float):
        """The radiance behind an ideal linear polarizer with its transmission axis at ``angle_deg``
        from the image's right axis (counter-clockwise as seen): ½ (S0 + S1 cos 2α + S2 sin 2α).
        Its white reference is the unpolarized white tile seen through the same filter (½ × white),
        so the display exposure rule is unchanged."""
        from nmmm.appearance.brdf.mueller import polarizer_intensity
        from nmmm.spectra import check_finite

        a = float(check_finite(angle_deg, "polarizer angle_deg"))
        rad = polarizer_intensity(np.moveaxis(self.stokes, 0, -1), a)
        return self._image(np.clip(rad, 0, None), 0.5 * np.asarray(self.white_radiance), {"polarizer_deg": a})

    def _luminance_stokes(self):
        from nmmm.colour import weighting_factors

        ybar = weighting_factors(self.wavelength_nm, illuminant=np.ones(self.wavelength_nm.size))[:, 1]
        return np.einsum("khwl,l->hwk", self.stokes, ybar)

    def degree_of_polarization(self, linear: bool = True) -> np.ndarray:
        """(H, W) degree of (linear, by default) polarization of the luminance-weighted Stokes vector."""
        from nmmm.appearance.brdf.mueller import degree_of_polarization

        return degree_of_polarization(self._luminance_stokes(), linear=linear)

    def angle_of_polarization_deg(self) -> np.ndarray:
        """(H, W) orientation of the linear polarization, ½ atan2(S2, S1), degrees from image right."""
        S = self._luminance_stokes()
        return 0.5 * np.degrees(np.arctan2(S[..., 2], S[..., 1]))

    def write_exr(self, path, half: bool = False):
        """Polarised spectral OpenEXR (Fichet et al. 2021): channels ``S0.<λ>nm`` … ``S3.<λ>nm`` and
        an RGB preview of S0."""
        from pathlib import Path

        import OpenEXR

        from nmmm.appearance.render.exr import EMISSIVE_UNITS, spectral_channel_name
        from nmmm.atomic_io import atomic_path

        dt = np.float16 if half else np.float32
        rgb = self.s0.linear_srgb()
        channels = {c: np.ascontiguousarray(rgb[..., k], dtype=dt) for k, c in enumerate("RGB")}
        for s in range(4):
            for k, wl in enumerate(self.wavelength_nm):
                channels[spectral_channel_name(wl, s)] = np.ascontiguousarray(self.stokes[s, :, :, k], dtype=dt)
        header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
                  "spectralLayoutVersion": "1.0", "emissiveUnits": EMISSIVE_UNITS,
                  "polarisationHandedness": "right", "nmmm": "nmmm.appearance.render.plate.stokes",
                  "nmmm.stokes_frame": "x = image right, y = image up"}
        p = Path(path)
        with atomic_path(p) as tmp, OpenEXR.File(header, channels) as f:
            f.write(str(tmp))
        return p


def _hemisphere(environment, w, n_theta=16, n_phi=32):
    """(directions (K, 3), solid angles (K,), radiance (K, L)) of the sky / map above the plate."""
    from nmmm.appearance.render.lights import LatLongEnvironment, UniformEnvironment

    if isinstance(environment, LatLongEnvironment):
        return environment.upper_quadrature(w, n_theta, n_phi)
    if isinstance(environment, UniformEnvironment):
        te = np.linspace(0, np.pi / 2, n_theta + 1)
        pe = np.linspace(0, 2 * np.pi, n_phi + 1)
        tc, pc = 0.5 * (te[1:] + te[:-1]), 0.5 * (pe[1:] + pe[:-1])
        T, P = np.meshgrid(tc, pc, indexing="ij")
        d = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1).reshape(-1, 3)
        om = ((np.cos(te[:-1]) - np.cos(te[1:]))[:, None] * np.diff(pe)[None, :]).ravel()
        return d, om, np.broadcast_to(environment.spectral(w), (d.shape[0], w.size))
    return None


def render_plate_stokes(plate, camera, lights=(), environment=None, wavelength_nm=None, env_step: int = 8,
                        **render_kwargs) -> StokesImage:
    """Spectral Stokes image (S0..S3) of ``plate`` seen by ``camera`` (arguments as
    :func:`~nmmm.appearance.render.plate.render_plate`, whose image is S0). ``env_step``: pixel
    step of the coarse grid on which the rough coat's and the flakes' polarized reflection of a
    sky or map is integrated (16 × 32 hemisphere cells) and then interpolated bilinearly."""
    from scipy.interpolate import RegularGridInterpolator

    from nmmm.appearance.render.lights import LatLongEnvironment, UniformEnvironment
    from nmmm.appearance.render.plate.renderer import (
        _add_light_images,
        _check_lights,
        _light_at,
        _plate_hits,
        render_plate,
    )

    img = render_plate(plate, camera, lights, environment, wavelength_nm=wavelength_nm, **render_kwargs)
    w = img.wavelength_nm
    L = w.size
    lights, environment = _check_lights(lights, environment)
    step = int(env_step)
    if step < 1:
        raise InvalidInputError(f"env_step must be >= 1, got {env_step!r}")
    brdf = plate.smooth_brdf
    Hd, Wd = img.on_plate.shape
    stokes = np.zeros((4, Hd, Wd, L), np.float32)
    stokes[0] = img.radiance
    if not hasattr(brdf, "coat"):  # a Lambertian reference plate: depolarizing
        return StokesImage(w, stokes, img.on_plate, img.white_radiance, camera, {**img.metadata, "stokes": True})
    r, _, _ = camera.basis()
    dirs = camera.pixel_directions()
    _, P = _plate_hits(camera, dirs)
    on = img.on_plate
    wo = -dirs[on]
    wo[:, 2] = np.maximum(wo[:, 2], 1e-6)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)

    def xref(v):
        return _unit(r[None, :] - (v @ r)[:, None] * v, (1.0, 0.0, 0.0))

    xc = xref(wo)
    pol = np.zeros((wo.shape[0], L, 3))
    stat_flakes = plate.flakes is None
    spectra = [lt.spectral(w) for lt in lights]
    for lt, sp in zip(lights, spectra):
        wi, s = _light_at(lt, P[on])
        pol += _polarized_terms(brdf, w, wi, wo, xc, stat_flakes)[..., 1:] * (s[:, None] * sp[None, :])[..., None]
        if not stat_flakes and getattr(brdf, "flakes", None) is not None:
            # the glints of this light (drawn again alone, deterministic) carry the flake chain's state:
            # a flake glints only when its normal is the binder half vector of (wi, wo)
            from nmmm.appearance.render.plate.glints import _render_glints

            glints = np.zeros((Hd, Wd, L), np.float32)
            sig = np.radians(float(render_kwargs.get("glint_spread_deg", 1.0)))
            _render_glints(plate, camera, [lt], [sp], w, sig, P[on], glints,
                           render_kwargs.get("randomize_tiles", True), render_kwargs.get("tile_seed", 0),
                           render_kwargs.get("area_splat", True))
            pol += _flake_chain(brdf, w, wi, wo, xc)[..., 1:] * glints[on][..., None]
    # the smooth coat's mirror Dirac: sky / map / finite lamps seen in the coat
    if brdf.coat.roughness == 0:
        F = brdf.specular_reflectance(w, wo)
        lin = np.zeros((wo.shape[0], L))
        if isinstance(environment, UniformEnvironment):
            lin += environment.spectral(w)[None, :]
        elif isinstance(environment, LatLongEnvironment):
            lin += environment.lookup(w, dirs[on] * np.array([1.0, 1.0, -1.0]))
        lamp = np.zeros((Hd, Wd, L), np.float32)
        _add_light_images(brdf, camera, lights, spectra, w, dirs, P, on, lamp)
        dirac = F * lin + lamp[on]
        pol += _dirac_stokes(brdf, w, wo, xc)[..., 1:] * dirac[..., None]
    # rough coat / flakes reflecting the sky or map: coarse grid, hemisphere cells
    quad = _hemisphere(environment, w) if environment is not None else None
    # (render_plate lights the flakes by a sky or map through the statistical term even with a flake cell)
    needs = brdf.coat.roughness > 0 or getattr(brdf, "flakes", None) is not None
    if quad is not None and needs:
        qd, qs, qr = quad
        rows = np.unique(np.r_[np.arange(0, Hd, step), Hd - 1])
        cols = np.unique(np.r_[np.arange(0, Wd, step), Wd - 1])
        cd = camera.pixel_directions(rows.astype(float), cols.astype(float)).reshape(-1, 3)
        cwo = -cd
        cwo[:, 2] = np.maximum(cwo[:, 2], 1e-6)
        cwo /= np.linalg.norm(cwo, axis=1, keepdims=True)
        cx = xref(cwo)
        acc = np.zeros((cwo.shape[0], L, 3))
        for k in range(qd.shape[0]):
            wi = np.broadcast_to(qd[k], cwo.shape).copy()
            acc += _polarized_terms(brdf, w, wi, cwo, cx, True)[..., 1:] * (qr[k] * qs[k] * qd[k, 2])[None, :, None]
        acc = acc.reshape(rows.size, cols.size, L * 3)
        if rows.size == 1 or cols.size == 1:
            pol += acc.reshape(-1, L, 3).mean(axis=0)[None]
        else:
            rr, cc = np.nonzero(on)
            pol += RegularGridInterpolator((rows, cols), acc)(np.stack([rr, cc], -1)).reshape(-1, L, 3)
    for k in range(3):
        stokes[k + 1][on] = pol[..., k].astype(np.float32)
    meta = {**img.metadata, "stokes": True, "stokes_frame": "x = image right, y = image up",
            "glints_polarized": plate.flakes is not None}
    return StokesImage(w, stokes, on, img.white_radiance, camera, meta)
