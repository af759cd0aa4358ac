"""The viewing booth (issue 19 item 2): the source gives the stated illuminance at the plate
centre and falls off as cos θ / r² across it, the clear coat mirrors the booth with its
Fresnel factor and the source's highlight sits at the mirror point, pixels off the plate
show the booth's grey, and a plate larger than the booth is refused."""

import numpy as np
import pytest

from nmmm.appearance import brdf
from nmmm.appearance.render import LambertianBRDF, PaintedPlate, PinholeCamera, ViewingBooth, render_plate
from nmmm.appearance.render.plate import _plate_hits
from nmmm.errors import InvalidInputError

W = np.arange(400.0, 701.0, 20.0)
CAM = dict(position_mm=(0.0, -300.0, 300.0), look_at_mm=(0.0, 0.0, 0.0), fov_deg=40.0, resolution=(48, 32))


def _luminance(w, radiance):
    """683 ∫ ȳ L dλ (cd/m²) by colour-science's own integration (independent of the booth's weights)."""
    import colour

    sd = colour.SpectralDistribution(dict(zip(w, radiance)))
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    return 683.002 * colour.sd_to_XYZ(sd, cmfs=cmfs, k=1.0, method="Integration")[1]


def _pixel_at_plate_point(cam, x, y):
    hit, P = _plate_hits(cam, cam.pixel_directions())
    d = np.where(hit, np.hypot(P[..., 0] - x, P[..., 1] - y), np.inf)
    return np.unravel_index(np.argmin(d), d.shape), P


def test_source_gives_the_stated_illuminance_and_falls_off_as_cos_over_r2():
    booth = ViewingBooth(illuminance_lux=1500.0)
    plate = PaintedPlate(LambertianBRDF(1.0), None, (150.0, 100.0))
    cam = PinholeCamera(**CAM)
    wf = np.arange(380.0, 781.0, 5.0)
    img = render_plate(plate, cam, lights=booth.lights(), wavelength_nm=wf)  # the source alone
    (i, j), P = _pixel_at_plate_point(cam, 0.0, 0.0)
    s = booth.source_position_mm
    p0 = np.array([P[i, j, 0], P[i, j, 1], 0.0])  # the pixel centre's plate point, a few mm off the centre
    near_centre = (np.linalg.norm(s) / np.linalg.norm(s - p0)) ** 3
    # L = E / π for ρ = 1, E = 1500 lx at the centre times cos θ / r² relative to the centre
    assert _luminance(wf, img.radiance[i, j]) == pytest.approx(1500.0 / np.pi * near_centre, rel=0.005)
    for x, y in [(60.0, -40.0), (-60.0, 40.0)]:
        (a, b), _ = _pixel_at_plate_point(cam, x, y)
        p = np.array([P[a, b, 0], P[a, b, 1], 0.0])
        ratio = (np.linalg.norm(s - p0) / np.linalg.norm(s - p)) ** 3  # cos θ / r² = z_s / r³, relative
        assert img.radiance[a, b, 20] / img.radiance[i, j, 20] == pytest.approx(ratio, rel=0.01)


def test_coat_mirrors_the_booth_with_its_fresnel_factor_and_the_background_is_the_booth():
    booth = ViewingBooth()
    plate = PaintedPlate(brdf.opaque_paint(0.0), None, (150.0, 100.0))  # black body: only the coat's mirror
    cam = PinholeCamera(**CAM)
    env = booth.environment(W)
    img = render_plate(plate, cam, environment=env, wavelength_nm=W)
    dirs = cam.pixel_directions()
    hit, P = _plate_hits(cam, dirs)
    on = hit & (np.abs(P[..., 0]) <= 75) & (np.abs(P[..., 1]) <= 50)
    i, j = np.argwhere(on)[len(np.argwhere(on)) // 3]
    wo = -dirs[i, j]
    mirror = np.array([-wo[0], -wo[1], wo[2]])
    F = plate.brdf.specular_reflectance(W, wo[None])[0]
    expect = F * env.lookup(W, mirror[None])[0]
    np.testing.assert_allclose(img.radiance[i, j], expect, rtol=0.02)
    off = ~on
    assert off.any() and np.all(img.radiance[off].sum(-1) > 0)  # a grey booth behind the plate, not black
    np.testing.assert_allclose(img.radiance[off], env.lookup(W, dirs[off]), rtol=1e-5)


def test_wall_radiance_is_lambertian_under_the_source():
    """A texel of the back wall straight ahead (+y, horizon) against ρ/π (I cos θ / r² + E_inter)."""
    booth = ViewingBooth(wall_reflectance=0.3)
    env = booth.environment(W, height=64, width=128)
    I = booth.lights()[0].spectral(W)
    X = np.array([0.0, booth.size_mm[1] / 2, 0.0])  # the back wall at the plate's height
    to = booth.source_position_mm - X
    r = np.linalg.norm(to)
    e_direct = (-to[1] / r) / (r * 1e-3) ** 2
    Wd, D, H = booth.size_mm
    area = 2 * (Wd * D + Wd * H + D * H) * 1e-6
    rho_mean = (Wd * D * 0.2 + (Wd * D + 2 * Wd * H + 2 * D * H) * 0.3) / (2 * (Wd * D + Wd * H + D * H))
    e_inter = rho_mean * 4 * np.pi / (area * (1 - rho_mean))
    got = env.lookup(W, np.array([[0.0, 1.0, 1e-3]]))[0]
    np.testing.assert_allclose(got, 0.3 / np.pi * (e_direct + e_inter) * I, rtol=0.05)  # texel ≈ 1.4° off


def test_source_highlight_sits_at_the_mirror_point():
    booth = ViewingBooth()
    plate = PaintedPlate(brdf.opaque_paint(0.3), None, (150.0, 100.0))
    cam = PinholeCamera(position_mm=(0.0, -300.0, 250.0), look_at_mm=(0.0, 0.0, 0.0), fov_deg=40.0,
                        resolution=(96, 64))
    img = render_plate(plate, cam, **booth.scene(plate, W), wavelength_nm=W)
    c, s = np.asarray(cam.position_mm), booth.source_position_mm
    y_mirror = c[1] + (s[1] - c[1]) * c[2] / (c[2] + s[2])  # where the image source's ray meets z = 0
    hit, P = _plate_hits(cam, cam.pixel_directions())
    lum = img.radiance[..., 5] * hit
    disc = lum > 0.5 * lum.max()  # the mirror image of the source sphere
    assert 1 < disc.sum() < 0.05 * hit.sum()
    assert abs(P[disc, 1].mean() - y_mirror) < 4.0 and abs(P[disc, 0].mean()) < 4.0


def test_bad_booths_are_refused_naming_the_key():
    with pytest.raises(InvalidInputError, match="larger than the booth.*booth size_mm"):
        ViewingBooth(size_mm=(100.0, 800.0, 600.0)).check_plate(PaintedPlate(LambertianBRDF(), None, (150.0, 100.0)))
    with pytest.raises(InvalidInputError, match="wall_reflectance"):
        ViewingBooth(wall_reflectance=1.2)
    with pytest.raises(InvalidInputError, match="source_distance_mm"):
        ViewingBooth(source_distance_mm=5000.0)
    with pytest.raises(InvalidInputError, match="source must be"):
        ViewingBooth(source="sideways")
