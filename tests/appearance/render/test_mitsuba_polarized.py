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
