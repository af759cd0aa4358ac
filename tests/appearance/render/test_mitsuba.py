"""Mitsuba 3 paint BSDF and scenes (skipped when Mitsuba or a suitable libLLVM is missing):
the plate renderer and Mitsuba agree on a flake-free plate within Monte-Carlo noise."""

import numpy as np
import pytest

from nmmm.appearance.render import DirectionalLight, PaintedPlate, PinholeCamera, UniformEnvironment, render_plate
from nmmm.errors import InvalidInputError


def _mitsuba():
    try:
        from nmmm.appearance.render.mitsuba_paint import require_mitsuba

        return require_mitsuba("llvm_ad_spectral")
    except Exception as exc:  # noqa: BLE001
        pytest.skip(f"Mitsuba unavailable: {exc}")


def test_unsupported_variant_is_a_clear_error():
    from nmmm.appearance.render.mitsuba_paint import require_mitsuba

    with pytest.raises(InvalidInputError, match="spectral"):
        require_mitsuba("llvm_ad_rgb")


@pytest.mark.slow
def test_paint_table_reproduces_brdf():
    """The tabulated + compressed BRDF vs direct evaluation at off-grid directions."""
    from nmmm.appearance.brdf import opaque_paint
    from nmmm.appearance.render.mitsuba_paint import paint_table, rusinkiewicz_coordinates

    paint = opaque_paint(0.5, roughness=0.2)
    w = np.arange(380.0, 781.0, 5.0)
    tab = paint_table(paint, w, n_theta_h=64, n_theta_d=64, n_phi_d=16)
    assert tab["residual"] < 1e-3
    rng = np.random.default_rng(0)
    th_i, th_o = np.radians(rng.uniform(5, 60, 50)), np.radians(rng.uniform(5, 60, 50))
    ph = rng.uniform(0, 2 * np.pi, 50)
    wi = np.stack([np.sin(th_i), 0 * th_i, np.cos(th_i)], -1)
    wo = np.stack([np.sin(th_o) * np.cos(ph), np.sin(th_o) * np.sin(ph), np.cos(th_o)], -1)
    th, td, pd = rusinkiewicz_coordinates(wi, wo)
    from scipy.interpolate import RegularGridInterpolator

    P = np.linspace(0, np.pi / 2, 16)
    D = np.linspace(0, np.pi / 2, 64)
    S = np.linspace(0, 1, 64)
    interp = RegularGridInterpolator((P, D, S), tab["coeff"].astype(float))
    f_tab = interp(np.stack([pd, td, np.sqrt(th / (np.pi / 2))], -1)) @ tab["basis"].T
    f = paint.evaluate(w, wi, wo)
    # compare the integrated (diffuse-dominated) values; the GGX lobe is resolved at a few %
    np.testing.assert_allclose(f_tab.mean(axis=1), f.mean(axis=1), rtol=0.06)


def test_mitsuba_plate_matches_plate_renderer():
    _mitsuba()
    from nmmm.appearance.brdf import opaque_paint
    from nmmm.appearance.render.mitsuba_scene import render_object

    paint = opaque_paint(0.5)
    light = DirectionalLight.from_angles(30, 90, "D65", 1.0)
    env = UniformEnvironment("D65", 0.1)
    pos = (0.0, -150.0, 400.0)
    (mimg,) = render_object(paint, "plate", [light], env, position_mm=pos, fov_deg=10, resolution=(32, 24), spp=256)
    pimg = render_plate(PaintedPlate(paint), PinholeCamera(pos, (0, 0, 0), (0, 0, 1), 10, (32, 24)), light, env)
    m, p = mimg.radiance, pimg.radiance
    # mean radiance within Monte-Carlo noise (standard error from the pixel scatter)
    per_pixel = m.mean(axis=2)
    se = per_pixel.std() / np.sqrt(per_pixel.size) + 0.002 * per_pixel.mean()
    assert abs(per_pixel.mean() - p.mean()) < 4 * se + 0.01 * p.mean()
    # the spectra agree band by band (12 bands of ~35 nm)
    mb = m.mean(axis=(0, 1))[:-1].reshape(8, 10).mean(axis=1)
    pb = p.mean(axis=(0, 1))[:-1].reshape(8, 10).mean(axis=1)
    np.testing.assert_allclose(mb, pb, rtol=0.04)
    # same image orientation: the column / row profiles follow each other
    assert np.corrcoef(m.mean(axis=(1, 2)), p.mean(axis=(1, 2)))[0, 1] > 0.8 or np.ptp(p.mean(axis=(1, 2))) < 1e-3 * p.mean()


@pytest.mark.slow
def test_mitsuba_stereo_converges_and_sphere_renders():
    _mitsuba()
    from nmmm.appearance.brdf import grey_metallic_paint
    from nmmm.appearance.render.mitsuba_scene import render_object

    left, right = render_object(grey_metallic_paint(), "sphere", DirectionalLight.from_angles(40, 60, "D65"),
                                UniformEnvironment("D65", 0.05), distance_mm=400, fov_deg=20, resolution=(40, 40),
                                spp=16, stereo=True, wavelength_nm=np.arange(400.0, 701.0, 20.0))
    for img in (left, right):
        y = img.radiance.mean(axis=2)
        bg = np.median(np.r_[y[0], y[-1]])
        mask = np.abs(y - bg) > 0.2 * bg
        rows, cols = np.nonzero(mask)
        # the sphere (at the convergence point) is centred in both eyes' images
        assert abs(cols.mean() - 19.5) < 2.0 and abs(rows.mean() - 19.5) < 3.0
    assert not np.allclose(left.radiance, right.radiance)


@pytest.mark.slow
def test_nmmm_envmap_irradiance_matches_analytic():
    """A Lambertian plate (ρ = 0.5) under a sky L(θ) = 0.5 + 1.5 cos θ (black ground):
    L = ρ · 2∫ L(μ) μ dμ = 0.5 · 1.5 = 0.75 (analytic), through the nmmm_envmap emitter."""
    mi = _mitsuba()
    from nmmm.appearance.render.mitsuba_envmap import envmap_emitter, latlong_environment, register_nmmm_envmap

    register_nmmm_envmap(mi)
    w = np.arange(380.0, 781.0, 5.0)
    env = latlong_environment(w, 2.0, 0.5, ground=0.0, height=64, width=8)
    scene = mi.load_dict({
        "type": "scene", "integrator": {"type": "path", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 10,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 300], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": 8, "height": 8, "pixel_format": "xyz"},
                   "sampler": {"type": "independent", "sample_count": 512}},
        "env": envmap_emitter(env, w),
        "plate": {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale([200, 200, 1]),
                  "bsdf": {"type": "diffuse", "reflectance": {"type": "spectrum", "value": 0.5}}}})
    img = np.asarray(mi.render(scene))
    assert abs(img[..., 1].mean() - 0.75) < 0.01


def test_missing_mitsuba_or_llvm_says_what_to_install(monkeypatch):
    import sys

    from nmmm.appearance.render import mitsuba_paint

    monkeypatch.setitem(sys.modules, "mitsuba", None)
    with pytest.raises(mitsuba_paint.MitsubaUnavailableError, match=r"pip install 'nmmm\[mitsuba\]'"):
        mitsuba_paint.require_mitsuba()
    monkeypatch.undo()
    pytest.importorskip("mitsuba")
    monkeypatch.setattr(mitsuba_paint, "_llvm_versions", lambda: [(15, "/usr/lib/libLLVM-15.so.1")])
    with pytest.raises(mitsuba_paint.MitsubaUnavailableError, match="libllvm19"):
        mitsuba_paint.require_mitsuba("llvm_ad_spectral")
