"""Bilinear environment-map lookup (the coat's mirror image of the booth walls without the
nearest-texel staircase), checked against an analytic smooth map; and the plate render at
coarse_step=1 (float32, the BRDF scaled in place) against the float64 BRDF evaluated directly."""

import numpy as np
import pytest

from nmmm.appearance.brdf import metallic_paint, opaque_paint
from nmmm.appearance.render import (
    DirectionalLight,
    LatLongEnvironment,
    PaintedPlate,
    PinholeCamera,
    UniformEnvironment,
    render_plate,
)
from nmmm.appearance.render.plate.renderer import _plate_hits

W = np.linspace(400.0, 700.0, 7)


def _g(th, ph):
    """A smooth radiance field over the sphere, (n,) angles -> (n, L) (each wavelength a different mix)."""
    k = np.arange(W.size)[None, :]
    th, ph = np.asarray(th)[:, None], np.asarray(ph)[:, None]
    return 1.0 + 0.4 * (np.cos(th) * (1 + 0.1 * k) + 0.5 * np.sin(th) * np.cos(ph - 0.3 * k))


def _analytic_map(h, wd):
    th = (np.arange(h) + 0.5) / h * np.pi
    ph = (np.arange(wd) + 0.5) / wd * 2 * np.pi
    T, P = np.meshgrid(th, ph, indexing="ij")
    return LatLongEnvironment(W, _g(T.ravel(), P.ravel()).reshape(h, wd, W.size), name="analytic")


def _directions(rng, n, upper=True):
    th = np.arccos(rng.uniform(0.05, 0.95, n)) if upper else np.arccos(-rng.uniform(0.05, 0.95, n))
    ph = rng.uniform(0, 2 * np.pi, n)
    return np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1), th, ph


def test_bilinear_lookup_matches_a_smooth_map_to_second_order():
    rng = np.random.default_rng(1)
    env = _analytic_map(32, 64)
    d, th, ph = _directions(rng, 4000)
    exact = _g(th, ph)
    got = env.lookup(W, d)
    nearest = env.radiance.reshape(-1, W.size)[env.texel(d)]
    err_bi = np.abs(got - exact).max()
    err_nn = np.abs(nearest - exact).max()
    # bilinear error <= max|g''| h² / 8 per axis: |g''| <= 0.4 * 1.6, h = π/32 (θ) and 2π/64 (φ)
    assert err_bi <= 2 * 0.64 * (np.pi / 32) ** 2 / 8
    assert err_nn > 10 * err_bi  # nearest texel is first order: a staircase
    # exact at the texel centres, and periodic across φ = 0
    c = np.array([[np.sin(np.pi * 10.5 / 32) * np.cos(2 * np.pi * 5.5 / 64),
                   np.sin(np.pi * 10.5 / 32) * np.sin(2 * np.pi * 5.5 / 64), np.cos(np.pi * 10.5 / 32)]])
    np.testing.assert_allclose(env.lookup(W, c)[0], env.radiance[10, 5], rtol=1e-12)
    seam = np.array([[np.sin(1.0), -1e-9, np.cos(1.0)], [np.sin(1.0), 1e-9, np.cos(1.0)]])
    a, b = env.lookup(W, seam)
    np.testing.assert_allclose(a, b, rtol=1e-9)


def test_lookup_does_not_blend_across_the_horizon():
    """Above the horizon only rows above it are read (the sky/walls, not the floor)."""
    r = np.ones((16, 32, W.size))
    r[8:] = 50.0  # a bright floor below the horizon
    env = LatLongEnvironment(W, r)
    up = np.array([[1.0, 0.0, 1e-4], [0.0, 1.0, 0.02]])
    np.testing.assert_allclose(env.lookup(W, up), 1.0)
    np.testing.assert_allclose(env.lookup(W, -up), 50.0)


def test_coat_mirror_of_a_smooth_map_has_no_staircase():
    """A black paint under a smooth coat shows F(θ) × the map at the mirror direction: with the
    bilinear lookup each pixel equals F × the analytic radiance to the interpolation error."""
    env = _analytic_map(16, 32)
    paint = opaque_paint(0.0)
    plate = PaintedPlate(paint, None, (150.0, 100.0))
    cam = PinholeCamera((0.0, -250.0, 300.0), (0.0, 0.0, 0.0), fov_deg=30.0, resolution=(64, 48))
    img = render_plate(plate, cam, environment=env, wavelength_nm=W, coarse_step=1)
    dirs = cam.pixel_directions()
    hit, P = _plate_hits(cam, dirs)
    on = hit & (np.abs(P[..., 0]) <= 75) & (np.abs(P[..., 1]) <= 50)
    wo = -dirs[on]
    F = paint.specular_reflectance(W, wo)
    m = np.stack([-wo[:, 0], -wo[:, 1], wo[:, 2]], -1)
    th, ph = np.arccos(m[:, 2]), np.mod(np.arctan2(m[:, 1], m[:, 0]), 2 * np.pi)
    ok = th < np.pi / 2 - np.pi / 16  # away from the horizon row (clamped there)
    exact = F * _g(th, ph)
    rel = np.abs(img.radiance[on][ok] - exact[ok]) / exact[ok]
    assert rel.max() < 0.01  # bilinear: O(h²) (the nearest texel: up to 3.5 % here)
    nearest = F * env.radiance.reshape(-1, W.size)[env.texel(m)]
    assert (np.abs(nearest[ok] - exact[ok]) / exact[ok]).max() > 4 * rel.max()
    # the background is the map itself, read the same way
    np.testing.assert_allclose(img.radiance[~on], env.lookup(W, dirs[~on]), rtol=1e-6)


@pytest.mark.parametrize("paint", [metallic_paint(), opaque_paint(0.4)], ids=["metallic", "solid"])
def test_per_pixel_render_equals_the_float64_brdf(paint):
    """coarse_step=1: the float32 image (BRDF written as float32, scaled in place, no copy into an
    interpolated image) equals f(wi, wo) E(λ) + albedo(wo) L_env computed in float64, to 2e-6."""
    w = np.linspace(380.0, 780.0, 21)
    plate = PaintedPlate(paint, None, (150.0, 100.0))
    cam = PinholeCamera((0.0, -180.0, 420.0), (0.0, 0.0, 0.0), fov_deg=24.0, resolution=(48, 32))
    light = DirectionalLight.from_angles(35.0, 90.0, "D65")
    sky = UniformEnvironment("D65", 0.01)
    img = render_plate(plate, cam, light, sky, wavelength_nm=w, coarse_step=1)
    dirs = cam.pixel_directions()
    hit, P = _plate_hits(cam, dirs)
    on = hit & (np.abs(P[..., 0]) <= 75) & (np.abs(P[..., 1]) <= 50)
    wo = -dirs[on]
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi = np.broadcast_to(np.asarray(light.direction), wo.shape)
    ref = (paint.evaluate(w, wi, wo) * (light.spectral(w) * light.direction[2])[None, :]
           + paint.albedo(w, wo) * sky.spectral(w)[None, :])
    np.testing.assert_allclose(img.radiance[on], ref, rtol=2e-6, atol=1e-7 * ref.max())
    assert img.radiance.dtype == np.float32


def test_smooth_coat_environment_integral_on_sparser_nodes():
    """A smooth coat's environment integral (broad non-Dirac lobes) evaluated on nodes up to
    ENVMAP_NODE_DEG apart and interpolated equals the integral at every coarse node to 1e-3."""
    from nmmm.appearance.render import ViewingBooth, seed_metallic_plate
    from nmmm.appearance.render.plate.environment import _envmap_smooth
    from nmmm.appearance.render.plate.renderer import _envmap_sub

    w = np.linspace(400.0, 700.0, 7)
    cam = PinholeCamera((0.0, -180.0, 420.0), (0.0, 0.0, 0.0), fov_deg=8.0, resolution=(256, 171))
    brdf = seed_metallic_plate(cells=(2, 2)).smooth_brdf
    sub = _envmap_sub(brdf, cam, 4)
    assert sub > 4 and _envmap_sub(opaque_paint(0.3, roughness=0.05), cam, 4) == 4
    rows = np.unique(np.r_[np.arange(0, 171, 4), 170]).astype(float)
    cols = np.unique(np.r_[np.arange(0, 256, 4), 255]).astype(float)
    cd = cam.pixel_directions(rows, cols).reshape(-1, 3)
    hit, _ = _plate_hits(cam, cd)
    wo = -cd / np.linalg.norm(cd, axis=1, keepdims=True)
    env = ViewingBooth(size_mm=(1000.0, 1000.0, 800.0)).environment(w, 64, 128)
    args = (brdf, w, env, wo.reshape(rows.size, cols.size, 3), hit.reshape(rows.size, cols.size))
    ref = _envmap_smooth(*args, sub=1)
    got = _envmap_smooth(*args, sub=sub)
    m = ref > 1e-3 * ref.max()
    assert m.sum() > 0.5 * m.size
    assert (np.abs(got - ref)[m] / ref[m]).max() < 1e-3


def test_booth_map_texels_average_their_directions():
    """The booth map's texels are box means over supersample² directions (anti-aliased wall and
    floor edges): equal to the 4×4 block means of a 4×-finer single-sample map, and the texels
    across the floor-wall edge take intermediate values instead of jumping between two levels."""
    from nmmm.appearance.render import ViewingBooth

    w = np.array([550.0])
    booth = ViewingBooth()
    coarse = booth.environment(w, 32, 64, supersample=4).radiance[..., 0]
    fine = booth.environment(w, 128, 256, supersample=1).radiance[..., 0]
    np.testing.assert_allclose(coarse, fine.reshape(32, 4, 64, 4).mean(axis=(1, 3)), rtol=1e-12)
    col = coarse[17:, 16]  # below the horizon (past its seam row), a column crossing the floor-wall edge
    one = booth.environment(w, 32, 64, supersample=1).radiance[17:, 16, 0]
    jump = np.argmax(np.diff(one))  # the floor-wall edge: the only rise down the column
    lo, hi = sorted((one[jump], one[jump + 1]))
    assert np.any((col > lo + 0.05 * (hi - lo)) & (col < hi - 0.05 * (hi - lo)))
