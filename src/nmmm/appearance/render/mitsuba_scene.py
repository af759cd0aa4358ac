"""Scenes for Mitsuba 3: painted spheres, curved panels and plates, mono or stereo, with
spectral film output in the Fichet et al. (2021) EXR layout.

Public functions
----------------
- :func:`scene_dict` — a Mitsuba scene dictionary (lengths in mm) with the paint as
  ``nmmm_paint``, nmmm lights (directional → ``directional`` (its angular size is ignored),
  point → ``point``, or a spherical ``area`` emitter when ``radius_mm`` > 0, uniform
  sky → ``constant`` with a spectral radiance, an (H, W, L) lat-long spectral map →
  ``nmmm_envmap``) and one or two perspective sensors whose
  ``specfilm`` has one box-shaped band per wavelength.
- :func:`render_object` — render a sphere / curved panel / flat plate: a list of
  :class:`~nmmm.appearance.render.plate.SpectralImage` (one per eye), so ``write_exr``
  renames the film's bands to ``S0.<λ>nm`` channels and ``write_png`` gives sRGB.

Stereo uses two parallel-axis cameras separated by the interocular distance with
off-axis principal points converging on the target (as
:func:`nmmm.appearance.render.camera.stereo_pair`).

References
----------
- Mitsuba 3 documentation, plugins ``perspective``, ``specfilm``, ``constant``,
  ``directional``, ``point``, ``path`` (https://mitsuba.readthedocs.io).
- A. Fichet, R. Pacanowski, A. Wilkie, JCGT 10(3) (2021) — spectral EXR layout.
"""

from __future__ import annotations

import numpy as np

from nmmm.appearance.render.lights import DirectionalLight, PointLight, UniformEnvironment, default_wavelengths
from nmmm.appearance.render.mitsuba_paint import paint_bsdf, register_nmmm_plugins, require_mitsuba
from nmmm.errors import InvalidInputError

__all__ = ["scene_dict", "render_object", "SHAPES", "SAMPLERS"]

SHAPES = ("sphere", "panel", "plate")


def _spectrum(spd, scale: float = 1.0):
    w = spd.wavelength_nm
    v = spd.values * scale
    if w.size == 1 or (w[0] <= 1.0 and w[-1] >= 1e4):  # equal energy
        return {"type": "spectrum", "value": float(v[0])}
    return {"type": "spectrum", "value": [(float(a), float(b)) for a, b in zip(w, v)]}


def _panel_mesh(mi, width_mm=120.0, height_mm=80.0, radius_mm=150.0, n=64):
    """A cylindrical panel (axis along y, bulging towards +z), as a Mitsuba mesh."""
    phi = np.linspace(-width_mm / (2 * radius_mm), width_mm / (2 * radius_mm), n)
    y = np.linspace(-height_mm / 2, height_mm / 2, max(n // 2, 2))
    P, Y = np.meshgrid(phi, y, indexing="ij")
    X = radius_mm * np.sin(P)
    Z = radius_mm * (np.cos(P) - 1)
    V = np.stack([X, Y, Z], axis=-1).reshape(-1, 3)
    N = np.stack([np.sin(P), 0 * P, np.cos(P)], axis=-1).reshape(-1, 3)
    ny = y.size
    faces = []
    for i in range(phi.size - 1):
        for j in range(ny - 1):
            a, b, c, d = i * ny + j, (i + 1) * ny + j, (i + 1) * ny + j + 1, i * ny + j + 1
            faces += [(a, b, c), (a, c, d)]
    F = np.asarray(faces, np.uint32)
    mesh = mi.Mesh("nmmm_panel", V.shape[0], F.shape[0], has_vertex_normals=True)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(V.astype(np.float32).ravel())
    params["vertex_normals"] = mi.Float(N.astype(np.float32).ravel())
    params["faces"] = mi.UInt32(F.ravel())
    params.update()
    return mesh


SAMPLERS = ("independent", "stratified", "multijitter", "ldsampler", "orthogonal")


def _sensors(mi, position_mm, look_at_mm, up, fov_deg, resolution, spp, wavelength_nm, stereo, interocular_mm,
             sampler="independent"):
    w = np.asarray(wavelength_nm, float)
    # box bands around each wavelength, clipped to the grid's ends (lights' SPDs may stop there)
    edges = np.r_[w[0], 0.5 * (w[1:] + w[:-1]), w[-1]] if w.size > 1 else np.r_[w[0] - 2.5, w[0] + 2.5]
    dl = np.diff(edges)
    bands = {}
    for k in range(w.size):
        lo, hi = edges[k], edges[k + 1]
        bands[f"b{k:03d}"] = {"type": "spectrum", "value": [(float(lo), 1.0), (float(hi), 1.0)]}
    p = np.asarray(position_mm, float)
    t = np.asarray(look_at_mm, float)
    f = (t - p) / np.linalg.norm(t - p)
    r = np.cross(f, np.asarray(up, float))
    if np.linalg.norm(r) < 1e-9:
        raise InvalidInputError("camera up vector is parallel to the viewing direction")
    r /= np.linalg.norm(r)
    dist = float(np.linalg.norm(t - p))
    tanx = np.tan(np.radians(fov_deg) / 2)
    eyes = [(p, 0.0)]
    if stereo:
        e = float(interocular_mm)
        s = (e / 2) / (dist * tanx)  # shift in half-widths
        eyes = [(p - e / 2 * r, +s), (p + e / 2 * r, -s)]
    out = []
    for pe, shift in eyes:
        out.append({
            "type": "perspective",
            "fov": float(fov_deg),
            "fov_axis": "x",
            # Mitsuba's principal point offset is in units of the film width (ours: half-widths)
            "principal_point_offset_x": float(shift / 2),
            "to_world": mi.ScalarTransform4f().look_at(origin=[float(v) for v in pe],
                                                       target=[float(v) for v in pe + f * dist],
                                                       up=[float(v) for v in up]),
            "film": {"type": "specfilm", "width": int(resolution[0]), "height": int(resolution[1]),
                     "rfilter": {"type": "box"}, **bands},
            "sampler": {"type": sampler, "sample_count": int(spp)},
        })
    return out, dl


def scene_dict(brdf, shape: str = "sphere", lights=(), environment=None, position_mm=(0.0, -150.0, 400.0),
               look_at_mm=(0.0, 0.0, 0.0), up=(0.0, 0.0, 1.0), fov_deg: float = 30.0, resolution=(256, 256),
               spp: int = 64, wavelength_nm=None, stereo: bool = False, interocular_mm: float = 65.0,
               plate_size_mm=(150.0, 100.0), max_depth: int = 4, variant: str = "llvm_ad_spectral",
               sampler: str = "independent", table=None):
    """Mitsuba scene dictionary of a painted ``shape`` (``"sphere"``: radius 50 mm at the
    origin; ``"panel"``: a 120 × 80 mm cylindrical panel of radius 150 mm facing +z;
    ``"plate"``: a flat ``plate_size_mm`` rectangle in z = 0 facing +z). ``sampler``: one of
    :data:`SAMPLERS` (Mitsuba's sampler plugins; ``"ldsampler"`` converges faster than
    ``"independent"``); ``table``: keyword arguments of
    :func:`~nmmm.appearance.render.mitsuba_paint.paint_table` (table resolution, rank).
    Returns ``(scene_dict, band_widths_nm, n_sensors)``."""
    mi = require_mitsuba(variant)
    register_nmmm_plugins(mi)
    if shape not in SHAPES:
        raise InvalidInputError(f"unknown shape {shape!r}; choose among {SHAPES}")
    if sampler not in SAMPLERS:
        raise InvalidInputError(f"unknown Mitsuba sampler {sampler!r}; choose among {SAMPLERS}")
    if isinstance(lights, (DirectionalLight, PointLight)):
        lights = (lights,)
    w = default_wavelengths() if wavelength_nm is None else np.asarray(wavelength_nm, float).ravel()
    d = {"type": "scene", "integrator": {"type": "path", "max_depth": int(max_depth)}}
    bsdf = paint_bsdf(brdf, wavelength_nm=w, **dict(table or {}))
    if shape == "sphere":
        d["object"] = {"type": "sphere", "center": [0.0, 0.0, 0.0], "radius": 50.0, "bsdf": bsdf}
    elif shape == "panel":
        d["object"] = _mesh_with_bsdf(_panel_mesh(mi), bsdf)
    else:
        sx, sy = (float(v) / 2 for v in plate_size_mm)
        d["object"] = {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale([sx, sy, 1.0]), "bsdf": bsdf}
    for k, lt in enumerate(lights):
        if isinstance(lt, DirectionalLight):
            d[f"light{k}"] = {"type": "directional", "direction": [-float(v) for v in lt.direction],
                              "irradiance": _spectrum(lt.spectrum, lt.irradiance)}
        elif isinstance(lt, PointLight) and lt.radius_mm > 0:
            # a spherical lamp: radiance I / (π ρ²) with ρ in metres (E = I / r², r in m)
            d[f"light{k}"] = {"type": "sphere", "center": [float(v) for v in lt.position_mm],
                              "radius": float(lt.radius_mm),
                              "emitter": {"type": "area", "radiance": _spectrum(
                                  lt.spectrum, lt.intensity / (np.pi * (lt.radius_mm * 1e-3) ** 2))}}
        elif isinstance(lt, PointLight):
            # nmmm: E = I / r² with r in metres; the scene is in mm
            d[f"light{k}"] = {"type": "point", "position": [float(v) for v in lt.position_mm],
                              "intensity": _spectrum(lt.spectrum, lt.intensity * 1e6)}
        else:
            raise InvalidInputError(f"unsupported light {type(lt).__name__}")
    if environment is not None:
        if isinstance(environment, UniformEnvironment):
            d["environment"] = {"type": "constant", "radiance": _spectrum(environment.spectrum, environment.radiance)}
        elif isinstance(environment, np.ndarray) and environment.ndim == 3:
            from nmmm.appearance.render.mitsuba_envmap import envmap_emitter, register_nmmm_envmap

            register_nmmm_envmap(mi)
            d["environment"] = envmap_emitter(environment, w)
        else:
            raise InvalidInputError("environment must be a UniformEnvironment or an (H, W, L) lat-long spectral "
                                    "radiance map on the wavelength grid (see mitsuba_envmap.latlong_environment)")
    if not lights and environment is None:
        raise InvalidInputError("no light: give at least one light or an environment")
    sensors, dl = _sensors(mi, position_mm, look_at_mm, up, fov_deg, resolution, spp, w, stereo, interocular_mm,
                           sampler)
    for k, s in enumerate(sensors):
        d[f"sensor{k}"] = s
    return d, dl, len(sensors)


def _mesh_with_bsdf(mesh, bsdf):
    """A mesh built in Python, written to PLY and loaded back with the BSDF attached."""
    import tempfile
    from pathlib import Path

    tmp = Path(tempfile.mkdtemp(prefix="nmmm_mi_")) / "panel.ply"
    mesh.write_ply(str(tmp))
    return {"type": "ply", "filename": str(tmp), "bsdf": bsdf}


def render_object(brdf, shape: str = "sphere", lights=(), environment=None, distance_mm: float = 400.0,
                  elevation_deg: float = 25.0, fov_deg: float = 30.0, resolution=(256, 256), spp: int = 64,
                  stereo: bool = False, interocular_mm: float = 65.0, wavelength_nm=None, seed: int = 0,
                  position_mm=None, look_at_mm=(0.0, 0.0, 0.0), plate_size_mm=(150.0, 100.0),
                  variant: str = "llvm_ad_spectral", sampler: str = "independent", table=None):
    """Render ``shape`` painted with ``brdf`` through Mitsuba 3 (``llvm_ad_spectral``).

    The camera sits at ``distance_mm`` from ``look_at_mm`` at ``elevation_deg`` above the
    xy-plane on the −y side (or at ``position_mm``); image up is +z (+y when looking along z).
    ``sampler`` and ``table`` as in :func:`scene_dict`. Returns a list of
    :class:`~nmmm.appearance.render.plate.SpectralImage` (left, right for ``stereo``):
    band values divided by the band width are the mean spectral radiance per band.
    """
    from nmmm.appearance.render.plate import SpectralImage, _light_at

    mi = require_mitsuba(variant)
    w = default_wavelengths() if wavelength_nm is None else np.asarray(wavelength_nm, float).ravel()
    if position_mm is None:
        e = np.radians(elevation_deg)
        position_mm = (0.0, -distance_mm * np.cos(e), distance_mm * np.sin(e))
    f = np.asarray(look_at_mm, float) - np.asarray(position_mm, float)
    up = (0.0, 0.0, 1.0) if np.linalg.norm(np.cross(f / np.linalg.norm(f), [0.0, 0.0, 1.0])) > 1e-3 else (0.0, 1.0, 0.0)
    d, dl, ns = scene_dict(brdf, shape, lights, environment, position_mm, look_at_mm, up, fov_deg,
                           resolution, spp, w, stereo, interocular_mm, plate_size_mm, variant=variant,
                           sampler=sampler, table=table)
    scene = mi.load_dict(d)
    if isinstance(lights, (DirectionalLight, PointLight)):
        lights = (lights,)
    white = np.zeros(w.size)
    for lt in lights:
        _, s = _light_at(lt, np.zeros((1, 3)))
        white += s[0] * lt.spectral(w) / np.pi
    if isinstance(environment, UniformEnvironment):
        white += environment.spectral(w)
    elif environment is not None:  # lat-long map: radiance of a white diffuser facing +z
        env = np.asarray(environment, float)
        th = (np.arange(env.shape[0]) + 0.5) / env.shape[0] * np.pi
        wt = np.where(th < np.pi / 2, np.cos(th) * np.sin(th), 0.0) * (np.pi / env.shape[0])
        white += 2 * np.einsum("h,hl->l", wt, env.mean(axis=1))
    out = []
    for k in range(ns):
        img = np.asarray(mi.render(scene, sensor=k, seed=int(seed) + 1000 * k), dtype=np.float32)
        rad = img[..., : w.size] / dl[None, None, :].astype(np.float32)
        out.append(SpectralImage(w, rad, np.ones(rad.shape[:2], bool), white, None,
                                 {"renderer": f"mitsuba {mi.__version__} {variant}", "spp": int(spp), "shape": shape}))
    return out
