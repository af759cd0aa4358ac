"""Rendering a painted plate: :func:`render_plate` (smooth part on a coarse grid, background,
environment, mirror images of finite lamps, glints, white reference) and
:func:`render_stereo_plate` (left and right eyes, same flakes).
"""

from __future__ import annotations

import numpy as np

from nmmm.appearance.render.camera import PinholeCamera, stereo_pair
from nmmm.appearance.render.lights import (
    DirectionalLight,
    LatLongEnvironment,
    PointLight,
    UniformEnvironment,
    default_wavelengths,
)
from nmmm.appearance.render.plate.coarse_grid import _bilinear, accumulate_light, add_environment
from nmmm.appearance.render.plate.environment import _background, _envmap_smooth, _mirror_env
from nmmm.appearance.render.plate.glints import _render_glints
from nmmm.appearance.render.plate.scene import PaintedPlate
from nmmm.appearance.render.plate.spectral_image import SpectralImage
from nmmm.errors import InvalidInputError
from nmmm.spectra import as_wavelength_nm, check_finite

__all__ = ["render_plate", "render_stereo_plate"]


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


def _evaluate_f32(brdf, w, wi, wo, comps):
    """The BRDF (N, L) as a writable float32 array (the paint kernels write float32 directly)."""
    from nmmm.appearance.brdf import PaintBRDF
    from nmmm.appearance.render.plate.scene import LambertianBRDF

    if isinstance(brdf, (PaintBRDF, LambertianBRDF)):
        f = brdf.evaluate(w, wi, wo, components=comps, dtype=np.float32)
    else:  # a user's BRDF object: evaluate(wavelength_nm, wi, wo, components=...) only
        f = brdf.evaluate(w, wi, wo, components=comps)
    f = np.asarray(f, np.float32)
    return f if f.flags.writeable and f.flags.c_contiguous else np.array(f, np.float32)


#: Largest angle (degrees) between the nodes on which a smooth coat's environment integral (its
#: non-Dirac terms: base, flakes, multiple scattering, broad lobes) is evaluated; measured on the
#: booth at 1024 x 683: within 5e-4 of the integral at every coarse node (a rough coat's GGX lobe
#: keeps every 4th node: 1e-3). Review N, booth 1024 x 683, fov 24 / 40 (every 10th / 6th node),
#: largest error over the plate / the plate's largest value: 7e-5 (seed metallic), 2.5e-4 (flake
#: tilt 4 deg), 8e-4 (tilt 2 deg), 1.4e-4 (pearl). The hemisphere quadrature itself is 16 x 32 cells
#: (8 x 16 until review L/N: the booth walls' light on the grey metallic's flake lobe came out 12-15 %
#: low against Mitsuba); largest error over the booth plate / the plate's largest value, against
#: 32 x 64 cells (256 x 171 px, 21 wavelengths): 7.9e-5 (seed metallic), 4.9e-5 (flake tilt 4 deg),
#: 1.2e-4 (tilt 2 deg), 9.5e-4 (GGX 0.05 coat) — at 8 x 16: 4.1e-4, 5.1e-4, 1.5e-3, 1.5e-2. It costs
#: +13-20 % CPU per booth image at 1024 x 683. The lamps' mirror images and direct light are not in
#: this integral.
ENVMAP_NODE_DEG = 1.0


def _envmap_sub(brdf, camera, step):
    """Coarse-grid nodes between the environment integral's nodes: every 4th, or for a smooth
    coat as many as keep the nodes within :data:`ENVMAP_NODE_DEG` of view angle."""
    coat = getattr(brdf, "coat", None)
    if coat is None or coat.roughness > 0:
        return 4
    deg_per_node = camera.fov_deg / camera.resolution[0] * step
    return max(4, int(ENVMAP_NODE_DEG / deg_per_node))


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


#: Bytes per pixel and wavelength a render holds at its peak (radiance, smooth and glint parts,
#: display conversion: float64), plus :data:`RENDER_BYTES_PER_PIXEL` of geometry per pixel.
RENDER_BYTES_PER_VALUE = 32
RENDER_BYTES_PER_PIXEL = 400


def _half_physical_memory_gb() -> float:
    import os

    try:
        return round(0.5 * os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 1e9, 1)
    except (ValueError, OSError, AttributeError):  # pragma: no cover - not POSIX
        return 8.0


#: Default memory limit of one render (GB).
RENDER_MAX_MEMORY_GB = _half_physical_memory_gb()


def _check_render_size(width, height, n_wavelengths, max_memory_gb=None):
    """Refuse a render whose estimated memory exceeds the limit (issue 21: unbounded work)."""
    limit = RENDER_MAX_MEMORY_GB if max_memory_gb is None else float(max_memory_gb)
    pixels = float(width) * float(height)
    gb = pixels * (RENDER_BYTES_PER_VALUE * n_wavelengths + RENDER_BYTES_PER_PIXEL) / 1e9
    if gb > limit:
        raise InvalidInputError(
            f"a {int(width)} x {int(height)} render at {n_wavelengths} wavelengths needs about {gb:.3g} GB "
            f"({pixels:.3g} pixels), above the {limit:g} GB limit: lower the camera resolution or the number of "
            "wavelengths, or raise the limit with render_plate(..., max_memory_gb=)")
    return gb


def render_plate(plate: PaintedPlate, camera: PinholeCamera, lights=(), environment=None, wavelength_nm=None,
                 glint_spread_deg: float = 1.0, coarse_step: int = 4, background=None,
                 randomize_tiles: bool = True, tile_seed: int = 0, area_splat: bool = True,
                 max_memory_gb: float | None = None) -> SpectralImage:
    """Render the spectral radiance image of ``plate`` seen by ``camera``.

    The memory of the render (``RENDER_BYTES_PER_VALUE`` bytes per pixel and wavelength, the
    per-pixel geometry included) is estimated first; beyond ``max_memory_gb`` (default
    :data:`RENDER_MAX_MEMORY_GB`, half the physical memory) the call is refused with the
    estimate instead of exhausting the machine.

    Parameters
    ----------
    plate : PaintedPlate
    camera : PinholeCamera
        Must be in front of the plate (z > 0) and look towards it.
    lights : DirectionalLight / PointLight or a sequence of them
    environment : UniformEnvironment or LatLongEnvironment, optional
        Uniform spectral sky (reflected through the paint's albedo) or a spectral lat-long
        map (non-Dirac terms integrated over 16 × 32 cells of the upper hemisphere on a
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
    _check_render_size(Wd, Hd, L, max_memory_gb)
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
    if rows.size == Hd and cols.size == Wd:  # every pixel is a node: reuse the full-resolution geometry
        cd, chit, cP = dirs.reshape(-1, 3), hit.reshape(-1), P.reshape(-1, 3)
    else:
        cd = camera.pixel_directions(rows, cols).reshape(-1, 3)
        chit, cP = _plate_hits(camera, cd)
    wo = -cd
    wo[~chit] = (0.0, 0.0, 1.0)
    wo[:, 2] = np.maximum(wo[:, 2], 0.0)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    coarse = None
    comps = ("specular", "base", "multiple") if plate.flakes is not None else ("specular", "flakes", "base", "multiple")
    for lt, sp in zip(lights, spectra):
        wi, s = _light_at(lt, cP)
        f = _evaluate_f32(brdf, w, wi, wo, comps)
        if coarse is None:  # the first light scales its BRDF values in place: no (pixels x L) copy
            coarse = np.ascontiguousarray(f)
            accumulate_light(coarse, coarse, s, sp, True)
        else:
            accumulate_light(coarse, f, s, sp, False)
        del f
    if env is not None:
        if coarse is None:
            coarse = np.empty((cd.shape[0], L), np.float32)
            add_environment(coarse, brdf, w, wo, env, True)
        else:
            add_environment(coarse, brdf, w, wo, env, False)
    if coarse is None:
        coarse = np.zeros((cd.shape[0], L), np.float32)
    coarse[~chit] = 0.0
    coarse = coarse.reshape(rows.size, cols.size, L)
    if envmap is not None:
        quad = envmap.upper_quadrature(w)  # once: the smooth part and the white reference
        coarse += _envmap_smooth(brdf, w, envmap, wo.reshape(rows.size, cols.size, 3), chit.reshape(rows.size, cols.size),
                                 sub=_envmap_sub(brdf, camera, step), quad=quad)
        r = envmap._on(w)
        env32 = np.ascontiguousarray(r.reshape(-1, L), np.float32)  # the map once in float32 (background, mirror)
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
    if step == 1 and coarse.shape[:2] == (Hd, Wd) and coarse.dtype == np.float32:
        img = coarse  # every pixel is a node: the coarse grid is the image (no interpolation copy)
    else:
        img = np.empty((Hd, Wd, L), np.float32)
        _bilinear(coarse, ri.astype(np.int64), rf, ci.astype(np.int64), cf, img)
    coarse_shape = (rows.size, cols.size, L)

    # --- off-plate pixels
    bg = background if background is not None else env
    off = ~on
    if bg is None and envmap is not None:  # the map seen past the plate, bilinear between texels
        _background(img, np.ascontiguousarray(dirs, float), off, r.shape[0], r.shape[1], env32)
    elif bg is None:
        img[off] = 0.0
    else:
        img[off] = np.asarray(bg, np.float32)[None, :]

    # --- mirror reflection of an environment map in a smooth coat (the coat's Dirac)
    if envmap is not None and hasattr(brdf, "specular_reflectance"):
        Fc = brdf.specular_reflectance(w, wo).reshape(coarse_shape)
        if np.any(Fc > 0):  # the view ray mirrored at the plate; the map bilinear between texels
            _mirror_env(img, np.ascontiguousarray(Fc, np.float32), ri.astype(np.int64), rf, ci.astype(np.int64), cf,
                        np.ascontiguousarray(dirs, float), on, r.shape[0], r.shape[1], env32)

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
        qd, qs, qr = quad
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


def render_stereo_plate(plate: PaintedPlate, position_mm=(0.0, 0.0, 400.0), look_at_mm=(0.0, 0.0, 0.0),
                        interocular_mm: float = 65.0, fov_deg: float = 20.0, resolution=(512, 341),
                        up=(0.0, 1.0, 0.0), **kwargs) -> tuple[SpectralImage, SpectralImage]:
    """Left- and right-eye images of the same plate (same flakes), cameras from
    :func:`~nmmm.appearance.render.camera.stereo_pair`; ``kwargs`` go to :func:`render_plate`."""
    left, right = stereo_pair(position_mm, look_at_mm, interocular_mm, up, fov_deg, resolution)
    return render_plate(plate, left, **kwargs), render_plate(plate, right, **kwargs)
