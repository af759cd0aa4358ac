"""Plate renderer: analytic radiance of Lambertian plates, sRGB white, glint statistics vs
the statistical flake BRDF, stereo glint shifts, determinism, bad input."""

import numpy as np
import pytest

from nmmm.appearance.render import (
    DirectionalLight,
    LambertianBRDF,
    PaintedPlate,
    PinholeCamera,
    PointLight,
    UniformEnvironment,
    default_wavelengths,
    render_plate,
    render_stereo_plate,
    seed_metallic_plate,
    stereo_pair,
)
from nmmm.errors import DataFileError, InvalidInputError, OutOfRangeError

W = default_wavelengths()


def d65_on_grid():
    import colour

    sd = colour.SDS_ILLUMINANTS["D65"]
    return np.interp(W, sd.wavelengths, sd.values)


@pytest.fixture(scope="module")
def small_metallic_plate():
    return seed_metallic_plate(cells=(40, 30), rng=1)


def test_default_grid_has_81_wavelengths():
    assert W.size == 81 and W[0] == 380 and W[-1] == 780


def test_white_lambertian_plate_radiance_is_E_cos_over_pi():
    """L = ρ E⊥ cos θi / π for a Lambertian plate under a distant light (analytic), with the
    D65 SPD taken from colour-science directly."""
    plate = PaintedPlate(LambertianBRDF(1.0), size_mm=(150, 100))
    cam = PinholeCamera((0, -100, 400), (0, 0, 0), fov_deg=20, resolution=(64, 43))
    light = DirectionalLight.from_angles(35.0, 40.0, "D65", irradiance=2.0)
    img = render_plate(plate, cam, light)
    expected = 2.0 * np.cos(np.radians(35.0)) / np.pi * d65_on_grid()
    on = img.on_plate
    assert on.mean() > 0.9
    np.testing.assert_allclose(img.radiance[on], np.broadcast_to(expected, (on.sum(), W.size)), rtol=1e-5)


def test_white_lambertian_plate_is_srgb_white_at_unit_exposure():
    plate = PaintedPlate(LambertianBRDF(1.0), size_mm=(150, 100))
    cam = PinholeCamera((0, 0, 500), (0, 0, 0), fov_deg=10, resolution=(32, 20))
    img = render_plate(plate, cam, DirectionalLight.from_angles(0.0, 0.0, "D65", 1.0))
    rgb = img.to_srgb(exposure=1.0)
    np.testing.assert_allclose(rgb, 1.0, atol=2e-3)
    # half the exposure: linear 0.5 encoded by the sRGB curve (IEC 61966-2-1)
    half = 1.055 * 0.5 ** (1 / 2.4) - 0.055
    np.testing.assert_allclose(img.to_srgb(exposure=0.5), half, atol=2e-3)
    # Display P3: the white is display white too; a saturated render differs from sRGB
    np.testing.assert_allclose(img.to_display_rgb("Display P3"), 1.0, atol=2e-3)
    # an 18 % grey card under the same light
    grey = render_plate(PaintedPlate(LambertianBRDF(0.18)), cam, DirectionalLight.from_angles(0.0, 0.0, "D65", 1.0))
    np.testing.assert_allclose(grey.to_srgb(), 1.055 * 0.18 ** (1 / 2.4) - 0.055, atol=2e-3)


def test_point_light_inverse_square_law():
    """E = I cos θ / r² (r in m) at every pixel, Lambertian radiance ρ E / π."""
    plate = PaintedPlate(LambertianBRDF(0.5), size_mm=(150, 100))
    cam = PinholeCamera((0, 0, 300), (0, 0, 0), fov_deg=30, resolution=(48, 32))
    lp = np.array([30.0, -20.0, 250.0])
    img = render_plate(plate, cam, PointLight(tuple(lp), 1.0, intensity=3.0), coarse_step=1)
    d = cam.pixel_directions()
    t = -300.0 / d[..., 2]
    P = np.asarray(cam.position_mm) + t[..., None] * d
    v = lp - P
    r = np.linalg.norm(v, axis=-1)
    E = 3.0 * (v[..., 2] / r) / (r * 1e-3) ** 2
    on = img.on_plate
    assert on.mean() > 0.8
    np.testing.assert_allclose(img.radiance[..., 40][on], (0.5 * E / np.pi)[on], rtol=1e-4)


def test_uniform_environment_on_lambertian_and_background():
    plate = PaintedPlate(LambertianBRDF(0.4), size_mm=(20, 20))
    cam = PinholeCamera((0, 0, 300), (0, 0, 0), fov_deg=8, resolution=(40, 30))
    img = render_plate(plate, cam, environment=UniformEnvironment(1.0, radiance=2.0))
    assert img.on_plate.any() and (~img.on_plate).any()
    np.testing.assert_allclose(img.radiance[img.on_plate], 0.8, rtol=1e-5)
    np.testing.assert_allclose(img.radiance[~img.on_plate], 2.0, rtol=1e-6)


def test_glints_average_to_statistical_flake_brdf(small_metallic_plate):
    """Mean radiance of the discrete flakes over many pixels = the statistical BRDF of
    nmmm.appearance.brdf (same flake layer) under the same light, within sampling noise."""
    # many small flakes per cell, off-specular view (flake tilts near the mode of the
    # distribution glint): the cell's sample of normals is then representative
    plate = seed_metallic_plate(cells=(40, 30), mean_diameter_um=5.0, rng=2)
    light = DirectionalLight.from_angles(25.0, 90.0, 1.0, 1.0)
    cam = PinholeCamera((0, 40, 430), (0, 0, 0), fov_deg=2.0, resolution=(96, 64))
    disc = render_plate(plate, cam, light, glint_spread_deg=1.5)
    stat = render_plate(PaintedPlate(plate.smooth_brdf, size_mm=plate.size_mm), cam, light)
    assert disc.metadata["n_glints"] > 2000
    band = slice(30, 50)
    m_disc = disc.radiance[..., band].mean()
    m_stat = stat.radiance[..., band].mean()
    assert m_stat > 0
    assert abs(m_disc / m_stat - 1) < 0.08
    # glints make the image far more contrasted than the smooth statistical one
    assert disc.radiance[..., 40].std() > 5 * stat.radiance[..., 40].std()


def test_glints_of_flakes_that_transmit_average_to_statistical_brdf():
    """The same for interference flakes (interference_paint(τ = 3), TiO2/mica: they transmit
    most of the red): each glint is dimmed by the flakes above it with the BRDF's extinction
    per direction (τ a(μ)(1 − T̄(μ, λ))/μ in and out, _Tables.ext_tab), so the rendered mean is
    the statistical BRDF's (measured 0.99-1.00; 3 % asserted) at 450/550/650 nm. With the mean τ_e
    the glints made the image 0.91/0.72 (light at 25°) and 0.91/0.81 (50°) of it at 550/650 nm."""
    from nmmm.appearance.brdf import interference_paint
    from nmmm.appearance.flakes import FlakeList

    paint = interference_paint(optical_depth=3.0)
    cell, d_um = 450e3, 5.0
    n = int(round(3.0 * cell * cell / (np.pi * (d_um * 1e3) ** 2 / 4 * (1 + 0.3 ** 2))))
    fl = FlakeList.random(paint.flakes.optics, paint.flakes.tilt, n, region_nm=(cell, cell),
                          mean_diameter_nm=d_um * 1e3, diameter_cv=0.3, depth_range_nm=(2e3, 18e3), n_binder=1.5,
                          rng=2)
    plate = PaintedPlate(paint, fl, (40 * 0.45, 30 * 0.45))
    w = np.array([450.0, 550.0, 650.0])
    assert not plate.smooth_brdf.prepare(w).tau_e_const  # the flakes transmit
    for zenith, eye in ((25.0, (0, 40, 430)), (50.0, (0, 120, 400))):
        light = DirectionalLight.from_angles(zenith, 90.0, 1.0, 1.0)
        cam = PinholeCamera(eye, (0, 0, 0), fov_deg=2.0, resolution=(96, 64))
        disc = render_plate(plate, cam, light, wavelength_nm=w, glint_spread_deg=1.5)
        stat = render_plate(PaintedPlate(plate.smooth_brdf, size_mm=plate.size_mm), cam, light, wavelength_nm=w)
        assert disc.metadata["n_glints"] > 20000
        ratio = disc.radiance.mean(axis=(0, 1)) / stat.radiance.mean(axis=(0, 1))
        assert np.all(np.abs(ratio - 1) < 0.03), (zenith, ratio)


def test_glint_positions_shift_between_eyes(small_metallic_plate):
    plate = small_metallic_plate
    light = DirectionalLight.from_angles(20.0, 90.0, "D65", 1.0)
    kw = dict(position_mm=(0, -60, 400), fov_deg=3.0, resolution=(120, 80), lights=light, glint_spread_deg=0.5)
    left, right = render_stereo_plate(plate, interocular_mm=65.0, **kw)
    same_l, same_r = render_stereo_plate(plate, interocular_mm=0.0, **kw)

    def glints(img):
        y = img.radiance[..., 40]
        return y > 3 * np.median(y)

    gl, gr = glints(left), glints(right)
    assert gl.sum() > 20 and gr.sum() > 20
    jaccard = (gl & gr).sum() / (gl | gr).sum()
    assert jaccard < 0.2
    np.testing.assert_array_equal(glints(same_l), glints(same_r))
    # the off-axis frusta coincide on the plane through the target, normal to the view
    # axis: the (slightly inclined) plate's outline is nearly the same in both images
    assert (left.on_plate != right.on_plate).mean() < 0.01


def test_stereo_cameras_converge_on_target():
    left, right = stereo_pair((0, -50, 400), (0, 0, 0), interocular_mm=64, resolution=(101, 61))
    for cam in (left, right):
        col, row, front = cam.project(np.array([0.0, 0.0, 0.0]))
        assert front and abs(col - 50) < 1e-6 and abs(row - 30) < 1e-6
    assert np.isclose(np.linalg.norm(np.subtract(left.position_mm, right.position_mm)), 64)


def test_render_is_deterministic(small_metallic_plate):
    cam = PinholeCamera((0, -100, 300), (0, 0, 0), fov_deg=4, resolution=(40, 30))
    light = DirectionalLight.from_angles(20.0, 90.0, "A", 1.0)
    a = render_plate(small_metallic_plate, cam, light)
    b = render_plate(small_metallic_plate, cam, light)
    np.testing.assert_array_equal(a.radiance, b.radiance)


def test_camera_looking_away_is_an_error():
    plate = PaintedPlate(LambertianBRDF(1.0))
    light = DirectionalLight()
    with pytest.raises(InvalidInputError, match="looks away"):
        render_plate(plate, PinholeCamera((0, 0, 300), (0, 0, 600)), light)
    with pytest.raises(InvalidInputError, match="behind the plate"):
        render_plate(plate, PinholeCamera((0, 0, -300), (0, 0, 0)), light)
    with pytest.raises(InvalidInputError, match="no pixel"):
        render_plate(plate, PinholeCamera((0, 0, 300), (500, 0, 0), fov_deg=5), light)
    with pytest.raises(InvalidInputError, match="no light"):
        render_plate(plate, PinholeCamera(), [])


def test_spd_files_and_names(tmp_path):
    import colour

    from nmmm.appearance.render import read_spd_csv, spd

    sd = colour.SDS_ILLUMINANTS["D65"]
    f = tmp_path / "lamp.csv"
    f.write_text("wavelength_nm,power\n" + "\n".join(f"{a},{b}" for a, b in zip(sd.wavelengths, sd.values)))
    np.testing.assert_allclose(read_spd_csv(f).on(W), spd("D65").on(W))
    plate = PaintedPlate(LambertianBRDF(1.0))
    cam = PinholeCamera(fov_deg=10, resolution=(8, 6))
    a = render_plate(plate, cam, DirectionalLight(spectrum=str(f)))
    b = render_plate(plate, cam, DirectionalLight(spectrum="D65"))
    np.testing.assert_allclose(a.radiance, b.radiance, rtol=1e-6)
    with pytest.raises(DataFileError, match="not found"):
        read_spd_csv(tmp_path / "missing.csv")
    bad = tmp_path / "bad.csv"
    bad.write_text("wavelength_nm,power\n400,1\n410,abc\n")
    with pytest.raises(DataFileError, match="row 3"):
        read_spd_csv(bad)
    neg = tmp_path / "neg.csv"
    neg.write_text("400,1\n410,-2\n")
    with pytest.raises(DataFileError, match="negative"):
        read_spd_csv(neg)
    with pytest.raises(InvalidInputError, match="unknown light spectrum"):
        spd("D66")
    short = tmp_path / "short.csv"
    short.write_text("400,1\n700,1\n")
    with pytest.raises(OutOfRangeError, match="covers 400-700"):
        render_plate(plate, cam, DirectionalLight(spectrum=str(short)))


def test_plate_from_microstructure_deposit_renders_glints():
    from nmmm.appearance.render import deposit_metallic_plate

    plate = deposit_metallic_plate(cells=(30, 20), seed=3)
    assert plate.cells == (30, 20) and len(plate.flakes) > 50
    cam = PinholeCamera((0, -40, 300), (0, 0, 0), fov_deg=3, resolution=(48, 32))
    img = render_plate(plate, cam, DirectionalLight.from_angles(20.0, 90.0, "D65"))
    assert img.metadata["n_glints"] > 0 and np.isfinite(img.radiance).all()


def test_mirror_image_of_a_lamp_in_the_clear_coat():
    """A smooth coat (n = 1.5) mirrors a spherical lamp: radiance F(θ) I / (π ρ²) with
    F = ((n − 1)/(n + 1))² = 0.04 at normal incidence (Fresnel, Born & Wolf §1.5)."""
    from nmmm.appearance.brdf import clear_dielectric

    plate = PaintedPlate(clear_dielectric(1.5), size_mm=(100, 100))
    cam = PinholeCamera((0, 0, 500), (0, 0, 0), fov_deg=10, resolution=(41, 41))
    lamp = PointLight((0, 0, 500), 1.0, intensity=2.0, radius_mm=20.0)  # behind the camera
    img = render_plate(plate, cam, lamp)
    centre = img.radiance[20, 20, 40]
    assert centre == pytest.approx(0.04 * 2.0 / (np.pi * 0.02 ** 2), rel=2e-3)
    # the disc's image: radius ρ/2 at the plate (mirror distance 2 × 500 mm), ~2 mm
    lit = img.radiance[20, :, 40] > 0.5 * centre
    pix_mm = 2 * 500 * np.tan(np.radians(5)) / 41
    assert abs(lit.sum() * pix_mm - 20.0) < 3 * pix_mm
    # the Sun (0.53 deg disc) seen in the coat: radiance E / Ω
    sun = DirectionalLight((0, 0, 1), 1.0, irradiance=1.0, angular_diameter_deg=0.53)
    img2 = render_plate(plate, cam, sun)
    omega = 2 * np.pi * (1 - np.cos(np.radians(0.265)))
    assert img2.radiance[20, 20, 40] == pytest.approx(0.04 / omega, rel=2e-3)


def test_latlong_environment_lambertian_and_uniform_limits():
    """Lambertian plate (ρ = 0.5) under a sky L(θ) = 0.5 + 1.5 cos θ, black ground:
    L = ρ · 2∫ L(μ) μ dμ = 0.75 (analytic). A constant map equals UniformEnvironment through
    the paint's albedo (reciprocity) within the 8 × 16 quadrature error."""
    from nmmm.appearance.brdf import opaque_paint
    from nmmm.appearance.render import LatLongEnvironment

    sky = LatLongEnvironment.sky(W, 2.0, 0.5, ground=0.0, height=64, width=16)
    cam = PinholeCamera((0, 0, 300), (0, 0, 0), fov_deg=8, resolution=(20, 16))
    img = render_plate(PaintedPlate(LambertianBRDF(0.5), size_mm=(200, 200)), cam, environment=sky)
    np.testing.assert_allclose(img.radiance[..., 40], 0.75, rtol=2e-3)
    paint = PaintedPlate(opaque_paint(0.4), size_mm=(200, 200))
    cam2 = PinholeCamera((0, -100, 300), (0, 0, 0), fov_deg=20, resolution=(32, 24))
    a = render_plate(paint, cam2, environment=LatLongEnvironment(W, np.ones((16, 32, W.size))))
    b = render_plate(paint, cam2, environment=UniformEnvironment(1.0, 1.0))
    np.testing.assert_allclose(a.radiance, b.radiance, rtol=5e-3)
    # the mirror image of the map in the smooth coat: a bright zenith patch only where the
    # mirrored view ray points into it
    spot = np.zeros((16, 32, W.size))
    spot[0] = 50.0
    c = render_plate(paint, PinholeCamera((0, 0, 300), (0, 0, 0), fov_deg=40, resolution=(33, 33)),
                     environment=LatLongEnvironment(W, spot))
    assert c.radiance[16, 16, 40] > 10 * c.radiance[0, 0, 40]
