"""Area splatting of glints: a flake wider than a pixel lights the pixels its projected
disc covers (``render_plate(area_splat=True)``), not one pixel.

- energy: the glint's Σ_p L_p Ω_p over the covered pixels equals the point splat's L Ω
  (Ω_p the pinhole pixel solid angle (2 tan(fx/2)/W)(2 tan(fy/2)/H) cos³θ_p, Pharr et al.
  PBRT 4th ed. §5.2 — computed here from the camera geometry, not by the renderer);
- geometry: a disc of diameter D seen head-on at distance d by a pinhole of focal length
  f (pixels) images to a disc of radius r = (D/2) f / d pixels (similar triangles): the
  covered area Σ_p L_p / L_full must be π r², and the number of lit pixels lies between
  π (r − √2/2)² and π (r + √2/2)² (pixels cut by the rim).
"""

import math

import numpy as np
import pytest

from nmmm.appearance.flakes import FlakeList
from nmmm.appearance.render import DirectionalLight, PaintedPlate, PinholeCamera, seed_metallic_plate
from nmmm.appearance.render import plate as plate_module

W = np.array([450.0, 550.0, 650.0])


def _one_flake_plate(diameter_um, normal=(0.0, 0.0, 1.0), pos_um=(500.0, 500.0)):
    base = seed_metallic_plate(cells=(1, 1))
    f0 = base.flakes
    nrm = np.asarray(normal, float)
    fl = FlakeList(positions_nm=np.array([pos_um]) * 1e3, depth_nm=np.array([5e3]), normals=(nrm / np.linalg.norm(nrm))[None],
                   diameters_nm=np.array([diameter_um * 1e3]), optics=f0.optics, n_binder=f0.n_binder,
                   region_nm=(1e6, 1e6), tilt=f0.tilt)
    return PaintedPlate(base.brdf, fl, (1.0, 1.0))


def _glints(plate, cam, light, area_splat):
    """Glint radiance alone (no smooth part) from the renderer's glint pass."""
    dirs = cam.pixel_directions()
    hit, P = plate_module._plate_hits(cam, dirs)
    on = hit & (np.abs(P[..., 0]) <= 0.5) & (np.abs(P[..., 1]) <= 0.5)
    img = np.zeros(cam.resolution[::-1] + (W.size,), np.float32)
    n = plate_module._render_glints(plate, cam, [light], [light.spectral(W)], W, math.radians(1.0), P[on], img,
                                    False, 0, area_splat)
    return img.astype(float), n


def _solid_angles(cam):
    tx, ty = cam.tan_half
    Wd, Hd = cam.resolution
    u = (2 * (np.arange(Wd) + 0.5) / Wd - 1 + cam.shift[0]) * tx
    v = (1 - 2 * (np.arange(Hd) + 0.5) / Hd + cam.shift[1]) * ty
    cos = 1 / np.sqrt(1 + u[None, :] ** 2 + v[:, None] ** 2)
    return (2 * tx / Wd) * (2 * ty / Hd) * cos ** 3


# head-on, 50 mm above the flake, 2° field on 201 px: f = 100.5 / tan 1° px
CAM = PinholeCamera((0.0, 0.0, 50.0), (0.0, 0.0, 0.0), fov_deg=2.0, resolution=(201, 201))
SUN = DirectionalLight((0.0, 0.0, 1.0), "D65")


@pytest.mark.parametrize("normal,cam", [
    ((0.0, 0.0, 1.0), CAM),
    # tilted flake seen obliquely, off the image centre: an elongated ellipse
    ((0.25, -0.1, 1.0), PinholeCamera((3.0, -20.0, 45.0), (0.05, 0.02, 0.0), fov_deg=3.0, resolution=(240, 180))),
])
def test_area_splat_conserves_the_flake_power(normal, cam):
    nrm = np.asarray(normal) / np.linalg.norm(normal)
    # light placed so that the flake mirrors it towards the camera (same in both renders)
    plate = _one_flake_plate(150.0, normal=nrm)
    wo = np.asarray(cam.position_mm) / np.linalg.norm(cam.position_mm)
    n = plate.flakes.n_binder
    o = np.r_[wo[:2] / n, 0.0]
    o[2] = math.sqrt(1 - o[0] ** 2 - o[1] ** 2)
    i = 2 * (o @ nrm) * nrm - o
    wi = np.r_[i[:2] * n, 0.0]
    wi[2] = math.sqrt(1 - wi[0] ** 2 - wi[1] ** 2)
    light = DirectionalLight(tuple(wi), "D65")
    area, n_area = _glints(plate, cam, light, True)
    point, n_point = _glints(plate, cam, light, False)
    assert n_point == 1 and n_area > 50  # one record vs the covered pixels
    om = _solid_angles(cam)[..., None]
    tot_area = (area * om).sum(axis=(0, 1))
    tot_point = (point * om).sum(axis=(0, 1))
    assert np.all(tot_point > 0)
    np.testing.assert_allclose(tot_area, tot_point, rtol=1e-6)


def test_head_on_footprint_is_the_projected_disc():
    D_um, d_mm = 200.0, 50.0
    plate = _one_flake_plate(D_um)
    area, _ = _glints(plate, CAM, SUN, True)
    g = area[..., 1]
    f_px = CAM.resolution[0] / 2 / CAM.tan_half[0]
    r = D_um * 1e-3 / 2 * f_px / d_mm  # 11.5 px
    lit = np.count_nonzero(g > 0)
    assert math.pi * (r - math.sqrt(0.5)) ** 2 <= lit <= math.pi * (r + math.sqrt(0.5)) ** 2
    # covered area in pixels: full pixels hold the maximum (Ω_p varies by < 1e-4 here)
    covered = g.sum() / g.max()
    assert covered == pytest.approx(math.pi * r * r, rel=5e-3)
    # centred on the flake's image (the image centre), round
    rows, cols = np.nonzero(g > 0)
    assert np.average(rows, weights=g[rows, cols]) == pytest.approx(100.0, abs=0.05)
    assert np.average(cols, weights=g[rows, cols]) == pytest.approx(100.0, abs=0.05)
    assert (rows.max() - rows.min() + 1) == (cols.max() - cols.min() + 1)


def test_flakes_smaller_than_a_pixel_keep_the_point_splat():
    # 20 µm flake: 1.15 px wide at 50 mm — move the camera back to 200 mm (0.29 px)
    cam = PinholeCamera((0.0, 0.0, 200.0), (0.0, 0.0, 0.0), fov_deg=2.0, resolution=(201, 201))
    plate = _one_flake_plate(20.0)
    area, n_area = _glints(plate, cam, SUN, True)
    point, n_point = _glints(plate, cam, SUN, False)
    assert n_area == n_point == 1
    np.testing.assert_array_equal(area, point)
