"""Issue 19 item 7 in Mitsuba 3's spectral-polarized variant: the ``nmmm_paint`` BSDF returns the
clear coat's reflection as a Mueller matrix (from nmmm.layers.fresnel's r_s, r_p). A black smooth-coated
plate (n = 1.5) under a uniform unpolarized sky, seen through Mitsuba's ``stokes`` integrator: the degree
of linear polarization equals Fresnel's (Rs - Rp)/(Rs + Rp) at the viewing angle — 1 at Brewster's
angle — and nmmm's own Stokes render of the same plate. Skipped without Mitsuba / libLLVM >= 17."""

import numpy as np
import pytest

from nmmm.appearance.brdf import opaque_paint
from nmmm.appearance.render import PaintedPlate, PinholeCamera, UniformEnvironment
from nmmm.appearance.render.plate.stokes import render_plate_stokes

W = np.arange(400.0, 701.0, 20.0)


def _mitsuba():
    try:
        from nmmm.appearance.render.mitsuba_paint import require_mitsuba

        return require_mitsuba("llvm_ad_spectral_polarized")
    except Exception as exc:  # noqa: BLE001
        pytest.skip(f"Mitsuba's polarized variant unavailable: {exc}")


def _sine_tangent_dop(theta_deg, n=1.5):
    ti = np.radians(theta_deg)
    tt = np.arcsin(np.sin(ti) / n)
    rs = np.sin(ti - tt) ** 2 / np.sin(ti + tt) ** 2
    rp = np.tan(ti - tt) ** 2 / np.tan(ti + tt) ** 2
    return (rs - rp) / (rs + rp)


@pytest.mark.parametrize("theta_deg", [30.0, float(np.degrees(np.arctan(1.5))), 70.0])
def test_mitsuba_polarized_coat_reflection_is_fresnel(theta_deg):
    mi = _mitsuba()
    from nmmm.appearance.render.mitsuba_paint import paint_bsdf, register_nmmm_plugins

    register_nmmm_plugins(mi)
    paint = opaque_paint(0.0)
    e = np.radians(90.0 - theta_deg)
    pos = [0.0, -400.0 * np.cos(e), 400.0 * np.sin(e)]
    scene = mi.load_dict({
        "type": "scene", "integrator": {"type": "stokes", "integrator": {"type": "path", "max_depth": 3}},
        "sensor": {"type": "perspective", "fov": 2.0,
                   "to_world": mi.ScalarTransform4f().look_at(origin=pos, target=[0, 0, 0], up=[0, 0, 1]),
                   "film": {"type": "hdrfilm", "width": 4, "height": 4, "pixel_format": "luminance",
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": 128}},
        "sky": {"type": "constant", "radiance": {"type": "spectrum", "value": 1.0}},
        "plate": {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale([200.0, 200.0, 1.0]),
                  "bsdf": paint_bsdf(paint, wavelength_nm=W)}})
    img = np.asarray(mi.render(scene, seed=1))
    S = img.reshape(-1, img.shape[-1]).mean(axis=0)[1:].reshape(4, 3)  # S0..S3 x RGB
    dolp = np.hypot(S[1], S[2]) / S[0]
    np.testing.assert_allclose(dolp, _sine_tangent_dop(theta_deg), atol=5e-3)
    assert np.all(np.abs(S[3]) < 1e-3 * S[0])  # a dielectric coat: no circular part
    # nmmm's Stokes render of the same plate, same camera: the same degree of polarization
    cam = PinholeCamera(tuple(pos), (0, 0, 0), (0, 0, 1), 2.0, (5, 5))
    st = render_plate_stokes(PaintedPlate(paint, size_mm=(400.0, 400.0)), cam, [], UniformEnvironment(1.0, 1.0),
                             wavelength_nm=W, coarse_step=1)
    assert dolp.mean() == pytest.approx(st.degree_of_polarization()[2, 2], abs=5e-3)


def test_polarized_variants_are_supported_names():
    from nmmm.appearance.render.mitsuba_paint import SUPPORTED_VARIANTS

    assert {"llvm_ad_spectral_polarized", "scalar_spectral_polarized"} <= set(SUPPORTED_VARIANTS)


def test_mueller_matrices_are_mitsubas_specular_reflection():
    """nmmm's reflection Mueller matrix against Mitsuba 3's own ``mueller.specular_reflection`` (its
    fresnel_polarized, not nmmm's Fresnel code): a dielectric (the coat, n = 1.5, below and above
    Brewster's angle) element by element; a metal (nmmm's Al flake in the binder) likewise except the
    retardance elements M23, M32, whose sign is opposite: Mitsuba's amplitudes are the complex
    conjugates of nmmm's (its e^{+iwt} time convention vs nmmm.layers' e^{-iwt} with n + ik), so S3
    of a metal reflection has the opposite sign in the two (the linear part, S0..S2, is the same)."""
    mi = _mitsuba()
    import drjit as dr

    from nmmm.appearance.brdf import grey_metallic_paint
    from nmmm.appearance.brdf.mueller import reflection_mueller
    from nmmm.layers import fresnel
    from nmmm.materials import as_material

    th = np.array([0.0, 20.0, 45.0, float(np.degrees(np.arctan(1.5))), 70.0, 85.0])
    cos = mi.Float(np.cos(np.radians(th)))
    m_mi = np.moveaxis(np.asarray(mi.mueller.specular_reflection(cos, mi.Float(1.5))), -1, 0)
    c = fresnel(1.0, 1.5, th)
    np.testing.assert_allclose(reflection_mueller(c.rs, c.rp), m_mi, atol=2e-6)

    nk = complex(as_material(grey_metallic_paint().flakes.optics.material).nk(np.array([550.0]))[0])
    eta = nk / 1.5
    C = dr.llvm.ad.Complex2f
    m_mi = np.moveaxis(np.asarray(mi.mueller.specular_reflection(
        cos, C(mi.Float([eta.real] * th.size), mi.Float([eta.imag] * th.size)))), -1, 0)
    c = fresnel(1.5, nk, th)
    m_nm = reflection_mueller(c.rs, c.rp)
    assert np.abs(m_nm[:, 2, 3]).max() > 0.1  # a real retarder at oblique incidence
    flip = np.diag([1.0, 1.0, 1.0, -1.0])  # S3 -> -S3
    np.testing.assert_allclose(flip @ m_nm @ flip, m_mi, atol=2e-5)
    a_s, a_p = mi.fresnel_polarized(cos, C(mi.Float([eta.real] * th.size), mi.Float([eta.imag] * th.size)))[:2]
    np.testing.assert_allclose(np.asarray(dr.real(a_s)) + 1j * np.asarray(dr.imag(a_s)), np.conj(c.rs), atol=2e-6)
    np.testing.assert_allclose(np.asarray(dr.real(a_p)) + 1j * np.asarray(dr.imag(a_p)), np.conj(c.rp), atol=2e-6)


@pytest.mark.parametrize("roll_deg", [30.0, -25.0])
def test_stokes_frame_is_the_images_and_mitsubas(roll_deg):
    """The Stokes frame (x = image right, y = image up) checked with the camera rolled by ``roll_deg``
    about its axis, looking at a black coated plate at Brewster's angle under a uniform sky: the coat
    polarizes along s = the world x axis, so the angle of polarization at the image centre is the angle
    of the world x axis as projected into the image by the camera (PinholeCamera.project; counter-
    clockwise from the image's right, rows pointing down), the polarizer passing most light is at that
    angle, and Mitsuba's stokes integrator (its own Stokes frame rotations, sensor x = image right) gives
    the same angle and S2 sign."""
    mi = _mitsuba()
    from nmmm.appearance.render.mitsuba_paint import paint_bsdf, register_nmmm_plugins

    register_nmmm_plugins(mi)
    paint = opaque_paint(0.0)
    e = np.radians(90.0 - np.degrees(np.arctan(1.5)))
    pos = np.array([0.0, -400.0 * np.cos(e), 400.0 * np.sin(e)])
    f = -pos / np.linalg.norm(pos)
    r0 = np.cross(f, [0.0, 0.0, 1.0])
    r0 /= np.linalg.norm(r0)
    u0 = np.cross(r0, f)
    rho = np.radians(roll_deg)
    up = np.sin(rho) * r0 + np.cos(rho) * u0
    cam = PinholeCamera(tuple(pos), (0, 0, 0), tuple(up), 4.0, (9, 9))
    c0, r_0, _ = cam.project(np.zeros(3))
    c1, r_1, _ = cam.project(np.array([1.0, 0.0, 0.0]))
    expected = np.degrees(np.arctan2(-(r_1 - r_0), c1 - c0))
    st = render_plate_stokes(PaintedPlate(paint, size_mm=(300.0, 300.0)), cam, [], UniformEnvironment(1.0, 1.0),
                             wavelength_nm=W, coarse_step=1)
    assert st.angle_of_polarization_deg()[4, 4] == pytest.approx(expected, abs=0.2)
    angles = np.arange(-90.0, 90.0, 1.0)
    passed = [st.through_polarizer(a).radiance[4, 4].mean() for a in angles]
    assert angles[int(np.argmax(passed))] == pytest.approx(expected, abs=1.0)
    scene = mi.load_dict({
        "type": "scene", "integrator": {"type": "stokes", "integrator": {"type": "path", "max_depth": 3}},
        "sensor": {"type": "perspective", "fov": 2.0,
                   "to_world": mi.ScalarTransform4f().look_at(origin=pos.tolist(), target=[0, 0, 0], up=up.tolist()),
                   "film": {"type": "hdrfilm", "width": 4, "height": 4, "pixel_format": "luminance",
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": 64}},
        "sky": {"type": "constant", "radiance": {"type": "spectrum", "value": 1.0}},
        "plate": {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale([200.0, 200.0, 1.0]),
                  "bsdf": paint_bsdf(paint, wavelength_nm=W)}})
    img = np.asarray(mi.render(scene, seed=1))
    S = img.reshape(-1, img.shape[-1]).mean(axis=0)[1:].reshape(4, 3)[:, 0]
    assert 0.5 * np.degrees(np.arctan2(S[2], S[1])) == pytest.approx(expected, abs=0.5)
    assert np.sign(S[2]) == np.sign(st.stokes[2, 4, 4].mean()) == np.sign(roll_deg)
