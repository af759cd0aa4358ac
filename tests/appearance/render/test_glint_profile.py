"""Radial profile of the glints around a point light's highlight vs the statistical flake BRDF.

The grey metallic recipe (seed example 3) showed a ring of glints with a darker centre
around the mirror point of the point light. With a Gaussian tilt density per steradian
(σ = 12°) the number of glinting flakes per unit area is ∝ p(θh), θh the angle between
the surface normal and the half vector of the directions refracted into the binder: it
is *largest* at θh = 0, and over the few degrees spanned by the highlight it falls by
only 1 − exp(−θh²/2σ²) (0.3 % at 1°, 3.4 % at 3°). The smooth flake term of
:class:`nmmm.appearance.brdf.PaintBRDF` (an analytic integral over the tilt density,
independent of the renderer's discrete flakes) gives that profile; the renderer's
pixel radiance averaged over rings of equal θh must follow it.

Cause of the ring: the plate tiles one 450 µm cell of 2103 flakes and randomised each
tile only by a shift and a rotation about the normal, so every tile repeated the same
2103 tilt magnitudes; near θ = 0 the cell holds a handful (1.9 expected below 0.5°),
and its empirical histogram (here 0.75× the model below 0.75°, 1.6× at 0.75–1.5°) was
printed on the image around every highlight. The renderer now also moves the tilts per
tile (CDF rotation, ``plate._tilt_variants``).
"""

import numpy as np

from nmmm.appearance.render import PinholeCamera, PointLight, render_plate, seed_metallic_plate
from nmmm.appearance.render import plate as plate_module


def _refracted(v, n):
    t = v[:, :2] / n
    return np.c_[t, np.sqrt(1 - np.sum(t * t, axis=1))]


def test_highlight_profile_follows_statistical_flake_brdf():
    # the recipe's geometry: eye 40 cm away at 30°, point light at (0, 20, 35) cm, mirror
    # point near the plate centre; one wavelength (the profile is geometric)
    plate = seed_metallic_plate(cells=(334, 223), rng=0)
    light = PointLight((0.0, 200.0, 350.0), 1.0, intensity=1.0)
    cam = PinholeCamera((0.0, -200.0, 346.4), (0.0, 0.0, 0.0), fov_deg=25.0, resolution=(600, 400))
    w = np.array([550.0])
    img = render_plate(plate, cam, light, wavelength_nm=w, glint_spread_deg=1.0)

    on = img.on_plate
    d = cam.pixel_directions()[on]
    P = np.asarray(cam.position_mm) - d * (cam.position_mm[2] / d[:, 2])[:, None]
    wo = -d
    v = np.asarray(light.position_mm) - P
    r = np.linalg.norm(v, axis=1)
    wi = v / r[:, None]
    E = wi[:, 2] / (r * 1e-3) ** 2  # plane irradiance of a unit-intensity point light
    brdf = plate.smooth_brdf
    smooth = brdf.evaluate(w, wi, wo, components=("specular", "base", "multiple"))[:, 0] * E
    stat = brdf.evaluate(w, wi, wo, components=("flakes",))[:, 0] * E
    glint = img.radiance[on][:, 0] - smooth

    n = 1.5  # binder / coat index of the seed paint
    h = _refracted(wi, n) + _refracted(wo, n)
    th = np.degrees(np.arccos(h[:, 2] / np.linalg.norm(h, axis=1)))
    edges = np.array([0.0, 0.75, 1.5, 2.25, 3.0, 4.0, 5.0, 6.0])
    ratio, s_prof = [], []
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (th >= lo) & (th < hi)
        assert m.sum() > 2000
        ratio.append(glint[m].mean() / stat[m].mean())
        s_prof.append(stat[m].mean())
    ratio = np.array(ratio)
    # the analytic profile peaks at the mirror point and decreases slowly (σ = 12°)
    assert np.all(np.diff(s_prof) < 0)
    # the glints follow it ring by ring (before the fix: 0.75, 1.60, 1.11, 0.82, 0.81, 0.79, 0.49)
    assert abs(ratio[0] - 1) < 0.2, ratio
    assert np.all(np.abs(ratio[1:] - 1) < 0.08), ratio
    # no dark centre: the inner disc is as bright, relative to the model, as the ring around it
    inner = glint[th < 1.5].mean() / stat[th < 1.5].mean()
    ring = glint[(th >= 1.5) & (th < 3.0)].mean() / stat[(th >= 1.5) & (th < 3.0)].mean()
    assert inner / ring > 0.9, (inner, ring)


def test_tilt_variants_keep_the_tilt_distribution():
    """Each variant's tilts follow the cell's distribution; the union over variants fills
    the small tilts of a Gaussian (σ = 12°) as the analytic CDF 1 − exp(−θ²/2σ²) says."""
    plate = seed_metallic_plate(cells=(2, 2), rng=0)
    nv = plate_module._tilt_variants(plate.flakes, 64)
    assert nv.shape == (64, len(plate.flakes), 3)
    np.testing.assert_allclose(np.linalg.norm(nv, axis=-1), 1.0, atol=1e-12)
    np.testing.assert_allclose(nv[0], plate.flakes.normals, atol=1e-12)
    th = np.degrees(np.arccos(nv[..., 2])).ravel()
    for t0 in (0.5, 1.0, 2.0, 5.0):
        expected = 1 - np.exp(-np.radians(t0) ** 2 / (2 * np.radians(12.0) ** 2))  # small-angle Gaussian
        frac = np.mean(th < t0)
        assert abs(frac / expected - 1) < 0.1, (t0, frac, expected)
