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
