"""Tests of nmmm.appearance.sparkle on synthetic images with known content."""

import numpy as np
import pytest

from nmmm.appearance.sparkle import relative_luminance, sparkle_graininess
from nmmm.errors import InvalidInputError


def _spots(n=40, size=300, seed=0, amp=2.0):
    rng = np.random.default_rng(seed)
    img = np.full((size, size), 0.2) + rng.normal(0, 0.003, (size, size))
    # well separated spots on a grid, jittered
    g = int(np.ceil(np.sqrt(n)))
    cells = [(i, j) for i in range(g) for j in range(g)][:n]
    step = size // g
    for i, j in cells:
        y = i * step + step // 2 + rng.integers(-3, 4)
        x = j * step + step // 2 + rng.integers(-3, 4)
        img[y - 1:y + 2, x - 1:x + 2] += amp
    return img


def test_counts_known_sparkles_and_density():
    img = _spots(40)
    m = sparkle_graininess(img, pixel_size_um=10.0)
    assert m.n_sparkles == 40
    assert np.isclose(m.density_per_mm2, 40 / (3.0 * 3.0))
    assert np.isclose(m.area_fraction, 40 * 9 / 300 ** 2, rtol=0.05)
    assert m.mean_contrast == pytest.approx(2.0 / 0.2, rel=0.1)


def test_exposure_and_encoding_invariance():
    img = _spots(25, seed=3)
    m1 = sparkle_graininess(img, 10.0)
    m2 = sparkle_graininess(img * 13.0, 10.0)
    v = img / img.max()
    enc = np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)  # IEC 61966-2-1
    m3 = sparkle_graininess((enc * 65535).round().astype(np.uint16), 10.0, encoding="srgb")
    for m in (m2, m3):
        assert m.n_sparkles == m1.n_sparkles
        assert m.sparkle_intensity == pytest.approx(m1.sparkle_intensity, rel=1e-3)
        assert m.graininess == pytest.approx(m1.graininess, rel=1e-3)


def test_uniform_image_has_no_sparkle_and_no_grain():
    m = sparkle_graininess(np.full((120, 100), 0.4), 5.0)
    assert m.n_sparkles == 0 and m.sparkle_intensity == 0 and m.graininess == pytest.approx(0, abs=1e-12)


def test_graininess_grows_with_texture_contrast():
    rng = np.random.default_rng(1)
    from scipy import ndimage

    tex = ndimage.gaussian_filter(rng.normal(size=(200, 200)), 3)
    tex /= tex.std()
    g = [sparkle_graininess(0.5 + a * tex, 10.0, threshold_contrast=5.0).graininess for a in (0.02, 0.04, 0.08)]
    assert g[0] < g[1] < g[2]
    assert g[2] / g[1] == pytest.approx(2.0, rel=0.05)


def test_rgb_luminance_weights():
    rgb = np.zeros((2, 2, 3))
    rgb[..., 1] = 1.0
    assert np.allclose(relative_luminance(rgb), 0.7152)


def test_bad_input():
    with pytest.raises(InvalidInputError):
        sparkle_graininess(np.ones((10, 10)), 0.0)
    with pytest.raises(InvalidInputError):
        sparkle_graininess(np.ones((10, 10, 2)), 1.0)
    with pytest.raises(InvalidInputError):
        sparkle_graininess(-np.ones((10, 10)), 1.0)
    with pytest.raises(InvalidInputError):
        relative_luminance(np.ones((4, 4)), encoding="gamma")


def test_flake_glint_image_radiometry_matches_the_statistical_lobe():
    """Mean of a glint image of many flakes = π/cosθo ∫ f_flakes cosθ K_acceptance dω."""
    from nmmm.appearance.brdf import ClearCoat, PaintBRDF
    from nmmm.appearance.flakes import FlakeList, aluminium_flakes, gaussian_tilt
    from nmmm.appearance.sparkle import flake_glint_image

    w = np.arange(400.0, 701.0, 50.0)
    fl = FlakeList.random(aluminium_flakes(), gaussian_tilt(10.0), 30000, region_nm=(2e6, 2e6),
                          mean_diameter_nm=10e3, diameter_cv=0.0, rng=11)
    paint = PaintBRDF(ClearCoat(1.5), 0.0, fl.to_flake_layer())
    wi = np.array([np.sin(np.radians(45)), 0, np.cos(np.radians(45))])
    tv = np.radians(35.0)
    wo = np.array([-np.sin(tv), 0, np.cos(tv)])
    sig = 4.0
    img = flake_glint_image(paint, fl, w, wi, wo, pixel_size_um=20.0, acceptance_deg=sig, background=False)
    # expected value by quadrature over directions around wo
    from nmmm.colour import weighting_factors

    Wy = weighting_factors(w, illuminant=np.ones_like(w), observer="10")[:, 1] / 100.0
    s = np.radians(sig)
    u = np.linspace(-4 * s, 4 * s, 61)
    du = u[1] - u[0]
    U, V = np.meshgrid(u, u, indexing="ij")
    e1 = np.array([np.cos(tv), 0, np.sin(tv)])  # tangent vectors at wo
    e2 = np.array([0.0, 1.0, 0.0])
    d = wo + U[..., None] * e1 + V[..., None] * e2
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    K = np.exp(-0.5 * (U ** 2 + V ** 2) / s ** 2) / (2 * np.pi * s * s)
    f = paint(w, wi, d, components="flakes") @ Wy
    expected = np.pi / wo[2] * np.sum(f * d[..., 2] * K) * du * du
    assert img.mean() == pytest.approx(expected, rel=0.1)


def test_empty_image_raises():
    with pytest.raises(InvalidInputError, match="no pixels"):
        sparkle_graininess(np.zeros((0, 0)), 1.0)
