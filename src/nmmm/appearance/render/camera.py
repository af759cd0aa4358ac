"""Pinhole cameras and stereo pairs for the plate renderer (plate frame, lengths in mm).

Public objects
--------------
- :class:`PinholeCamera` — position, target, up vector, horizontal field of view, resolution
  and an off-axis sensor shift; ``.basis()``, ``.pixel_directions()``,
  ``.pixel_solid_angle()``, ``.project(points)``.
- :func:`stereo_pair` — left and right eye cameras separated by the interocular distance,
  parallel axes with off-axis frusta converging on the target (no keystone distortion).

The image's pixel (row i, column j) has its centre at normalised coordinates
u = (2 (j + ½) / W − 1), v = 1 − 2 (i + ½) / H; its ray is
``forward + (u + shift_x) tan(fov_x/2) right + (v + shift_y) tan(fov_y/2) up``.

References
----------
- M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed. (2023), §5.1–5.2
  (projective and pinhole cameras).
- P. Bourke, "Calculating stereo pairs" (1999) — parallel-axis asymmetric frustum stereo.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.spectra import check_finite

__all__ = ["PinholeCamera", "stereo_pair"]


def _vec3(v, name):
    a = np.asarray(check_finite(v, name), float).ravel()
    if a.shape != (3,):
        raise InvalidInputError(f"{name} must be a 3-vector (mm), got shape {a.shape}")
    return a


@dataclass(frozen=True)
class PinholeCamera:
    """A pinhole camera. ``fov_deg`` is the horizontal field of view; ``resolution`` is
    (width, height) in pixels; ``shift`` moves the frustum off-axis (in units of the
    half-width / half-height of the image at unit distance)."""

    position_mm: tuple = (0.0, 0.0, 500.0)
    look_at_mm: tuple = (0.0, 0.0, 0.0)
    up: tuple = (0.0, 1.0, 0.0)
    fov_deg: float = 20.0
    resolution: tuple = (512, 341)
    shift: tuple = (0.0, 0.0)

    def __post_init__(self):
        p = _vec3(self.position_mm, "camera position_mm")
        t = _vec3(self.look_at_mm, "camera look_at_mm")
        u = _vec3(self.up, "camera up")
        if np.linalg.norm(t - p) == 0:
            raise InvalidInputError("camera look_at_mm must differ from position_mm")
        f = (t - p) / np.linalg.norm(t - p)
        if np.linalg.norm(np.cross(f, u)) < 1e-9:
            raise InvalidInputError("camera up vector is parallel to the viewing direction; choose another up")
        fov = float(check_finite(self.fov_deg, "fov_deg"))
        if not 0 < fov < 179:
            raise InvalidInputError(f"fov_deg must lie in (0, 179) degrees, got {fov!r}")
        try:
            w, h = (int(x) for x in self.resolution)
        except (TypeError, ValueError):
            raise InvalidInputError(f"resolution must be (width, height) integers, got {self.resolution!r}") from None
        if w < 1 or h < 1:
            raise InvalidInputError(f"resolution must be positive, got {self.resolution!r}")
        s = np.asarray(check_finite(self.shift, "shift"), float).ravel()
        if s.shape != (2,):
            raise InvalidInputError("shift must be (shift_x, shift_y)")
        object.__setattr__(self, "position_mm", tuple(p))
        object.__setattr__(self, "look_at_mm", tuple(t))
        object.__setattr__(self, "up", tuple(u))
        object.__setattr__(self, "fov_deg", fov)
        object.__setattr__(self, "resolution", (w, h))
        object.__setattr__(self, "shift", tuple(s))

    @property
    def width(self) -> int:
        return self.resolution[0]

    @property
    def height(self) -> int:
        return self.resolution[1]

    @property
    def tan_half(self) -> tuple[float, float]:
        """(tan(fov_x/2), tan(fov_y/2)) — square pixels."""
        tx = np.tan(np.radians(self.fov_deg) / 2)
        return float(tx), float(tx * self.height / self.width)

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(right, up, forward) orthonormal vectors."""
        p = np.asarray(self.position_mm)
        f = np.asarray(self.look_at_mm) - p
        f = f / np.linalg.norm(f)
        r = np.cross(f, np.asarray(self.up))
        r /= np.linalg.norm(r)
        u = np.cross(r, f)
        return r, u, f

    def pixel_directions(self, rows=None, cols=None) -> np.ndarray:
        """Unit ray directions through pixel centres, (len(rows), len(cols), 3) (all pixels
        by default; fractional indices allowed)."""
        w, h = self.resolution
        rows = np.arange(h, dtype=float) if rows is None else np.asarray(rows, float)
        cols = np.arange(w, dtype=float) if cols is None else np.asarray(cols, float)
        tx, ty = self.tan_half
        u = (2 * (cols + 0.5) / w - 1 + self.shift[0]) * tx
        v = (1 - 2 * (rows + 0.5) / h + self.shift[1]) * ty
        r, up, f = self.basis()
        d = f[None, None, :] + u[None, :, None] * r[None, None, :] + v[:, None, None] * up[None, None, :]
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    def pixel_solid_angle(self, directions: np.ndarray) -> np.ndarray:
        """Solid angle (sr) of the pixel whose centre ray is ``directions`` (..., 3):
        Ω = (Δu Δv) cos³α on the unit image plane, α the angle to the optical axis."""
        tx, ty = self.tan_half
        _, _, f = self.basis()
        c = np.asarray(directions) @ f
        return (2 * tx / self.width) * (2 * ty / self.height) * c ** 3

    def project(self, points_mm) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Continuous pixel coordinates (col, row) of points (..., 3) and a mask of those in
        front of the camera."""
        r, up, f = self.basis()
        d = np.asarray(points_mm, float) - np.asarray(self.position_mm)
        z = d @ f
        tx, ty = self.tan_half
        with np.errstate(divide="ignore", invalid="ignore"):
            u = (d @ r) / (z * tx) - self.shift[0]
            v = (d @ up) / (z * ty) - self.shift[1]
        col = (u + 1) / 2 * self.width - 0.5
        row = (1 - v) / 2 * self.height - 0.5
        return col, row, z > 0


def stereo_pair(position_mm=(0.0, 0.0, 400.0), look_at_mm=(0.0, 0.0, 0.0), interocular_mm: float = 65.0,
                up=(0.0, 1.0, 0.0), fov_deg: float = 20.0, resolution=(512, 341)):
    """Left and right eye cameras: centres ``position_mm ∓ interocular/2 · right``, both
    looking along the same axis (towards ``look_at_mm`` from the midpoint), frusta shifted
    off-axis so that they coincide on the plane through ``look_at_mm`` (the viewing
    distance, where the stereo display sits). Returns ``(left, right)``."""
    e = float(check_finite(interocular_mm, "interocular_mm"))
    if not 0 <= e < 1000:
        raise InvalidInputError(f"interocular_mm must lie in [0, 1000) mm (about 63-65 mm for adults), got {e!r}")
    mid = PinholeCamera(position_mm, look_at_mm, up, fov_deg, resolution)
    r, _, f = mid.basis()
    dist = float(np.linalg.norm(np.asarray(mid.look_at_mm) - np.asarray(mid.position_mm)))
    s = (e / 2) / (dist * mid.tan_half[0])
    p = np.asarray(mid.position_mm)
    cams = []
    for sign in (-1.0, 1.0):
        pe = p + sign * e / 2 * r
        cams.append(PinholeCamera(tuple(pe), tuple(pe + f * dist), mid.up, fov_deg, mid.resolution, (-sign * s, 0.0)))
    return cams[0], cams[1]
