"""A plate tilted in its scene (issue 19 item 2: "a plate of stated size at stated distance and tilt").

The plate renderers keep the plate in z = 0 of its own frame; a plate tilted by ``tilt_deg``
about its horizontal (x) axis is rendered by expressing the scene — camera, lights and
environment map, all given in the world (booth) frame — in the plate's frame. The world frame
has the plate centre at the origin, z up and the viewer towards −y; a positive tilt raises the
plate's far edge (+y), turning its normal towards the viewer, n = (0, −sin t, cos t) (the plate
pivots about the line through its centre). World → plate is the rotation R_x(−t).

- :func:`tilt_rotation` — the 3 × 3 matrix plate → world (R_x(t)).
- :func:`to_plate_frame` — points or directions (..., 3) from the world frame into the plate's.
- :func:`tilted_scene` — camera, lights and environment in the plate frame.
"""

from __future__ import annotations

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.spectra import check_finite

__all__ = ["tilt_rotation", "to_plate_frame", "tilted_scene"]


def tilt_rotation(tilt_deg: float) -> np.ndarray:
    """Rotation plate → world for a plate tilted by ``tilt_deg`` (in (−90, 90)) about x."""
    t = float(check_finite(tilt_deg, "tilt_deg"))
    if not -90 < t < 90:
        raise InvalidInputError(f"tilt_deg must lie in (-90, 90) degrees (0: the plate lies flat), got {t!r}")
    c, s = np.cos(np.radians(t)), np.sin(np.radians(t))
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def to_plate_frame(tilt_deg: float, v) -> np.ndarray:
    """World-frame points or directions ``v`` (..., 3) in the frame of the tilted plate."""
    return np.asarray(v, float) @ tilt_rotation(tilt_deg)  # R^T v for row vectors


def tilted_scene(tilt_deg: float, camera, lights=(), environment=None):
    """``(camera, lights, environment)`` of a world-frame scene in the frame of a plate tilted by
    ``tilt_deg``: the camera's position, target and up vector, point lights' positions,
    directional lights' directions rotated; a lat-long map resampled (bilinear) along the rotated
    directions of its texel centres; a uniform environment unchanged."""
    from dataclasses import replace

    from nmmm.appearance.render.lights import DirectionalLight, LatLongEnvironment, PointLight

    R = tilt_rotation(tilt_deg)
    if float(tilt_deg) == 0.0:
        return camera, tuple(lights), environment
    cam = replace(camera, position_mm=tuple(to_plate_frame(tilt_deg, camera.position_mm)),
                  look_at_mm=tuple(to_plate_frame(tilt_deg, camera.look_at_mm)),
                  up=tuple(to_plate_frame(tilt_deg, camera.up)))
    out = []
    for lt in lights:
        if isinstance(lt, PointLight):
            out.append(replace(lt, position_mm=tuple(to_plate_frame(tilt_deg, lt.position_mm))))
        elif isinstance(lt, DirectionalLight):
            out.append(replace(lt, direction=tuple(to_plate_frame(tilt_deg, lt.direction))))
        else:
            raise InvalidInputError(f"lights must be DirectionalLight / PointLight objects, got {type(lt).__name__}")
    env = environment
    if isinstance(environment, LatLongEnvironment):
        h, wd, _ = environment.radiance.shape
        th = (np.arange(h) + 0.5) / h * np.pi
        ph = (np.arange(wd) + 0.5) / wd * 2 * np.pi
        T, P = np.meshgrid(th, ph, indexing="ij")
        d = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
        world = d @ R.T  # plate-frame texel directions in the world
        env = LatLongEnvironment(environment.wavelength_nm, environment.lookup(environment.wavelength_nm, world),
                                 name=f"{environment.name}, plate tilted {float(tilt_deg):g} deg")
    return cam, tuple(out), env
