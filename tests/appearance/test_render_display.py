"""Display like a calibrated screen (issue 19 item 3): the exposure rule (a white tile at the
plate centre is display white), the documented knee tone-mapping operator (identity below
the knee, continuous slope at it, monotone, below white above it, chromaticity kept), and
the clipped-pixel statistics."""

import numpy as np
import pytest

from nmmm.appearance.render import LambertianBRDF, PaintedPlate, PinholeCamera, SpectralImage, ViewingBooth, render_plate
from nmmm.appearance.render.plate.spectral_image import TONE_MAP_KNEE
from nmmm.errors import InvalidInputError

W = np.arange(400.0, 701.0, 20.0)


def _image(values):
    """A 1-row image of flat spectra of the given radiances; the white tile has radiance 1."""
    v = np.asarray(values, float)
    rad = np.broadcast_to(v[None, :, None], (1, v.size, W.size)).astype(np.float32)
    return SpectralImage(W, rad, np.ones((1, v.size), bool), np.ones(W.size))


def test_white_tile_maps_to_display_white_and_greys_below_the_knee_are_linear():
    rgb, st = _image([1.0, 0.5, 0.2]).to_display(tone_map="none")
    np.testing.assert_allclose(rgb[0, 0], 1.0, atol=2e-3)
    import colour

    lin = colour.models.eotf_sRGB(rgb[0, 1:])  # decode: linear light, proportional to the radiance
    np.testing.assert_allclose(lin[:, 1], [0.5, 0.2], rtol=5e-3)
    assert st["clipped_fraction"] == 0.0 and st["display_white_cd_m2"] == 120.0
    assert st["plate_mean_cd_m2"] == pytest.approx(120.0 * (1 + 0.5 + 0.2) / 3, rel=5e-3)


def test_knee_operator_is_documented_shape():
    k = TONE_MAP_KNEE
    x = np.array([0.3, k - 1e-4, k + 1e-4, 1.0, 2.0, 10.0, 100.0])
    import colour

    rgb, st = _image(x).to_display(tone_map="knee")
    y = colour.models.eotf_sRGB(rgb[0])[:, 1]
    expect = np.where(x > k, k + (1 - k) * (1 - np.exp(-(x - k) / (1 - k))), x)  # the docstring's formula
    np.testing.assert_allclose(y, expect, rtol=5e-3, atol=1e-4)
    assert np.all(np.diff(y[:6]) > 0) and np.all(np.diff(y) >= 0) and y[-1] <= 1.0  # monotone, never above white
    assert (y[2] - y[1]) / (x[2] - x[1]) == pytest.approx(1.0, rel=0.02)  # slope 1 at the knee
    assert st["clipped_fraction"] == 0.0 and st["over_white_fraction"] == pytest.approx(3 / 7)
    none = _image(x).to_display(tone_map="none")[1]
    assert none["clipped_fraction"] == pytest.approx(3 / 7)


def test_booth_scene_clips_at_most_one_percent_with_the_knee():
    booth = ViewingBooth()
    plate = PaintedPlate(LambertianBRDF(0.3), None, (150.0, 100.0))
    cam = PinholeCamera((0.0, -300.0, 300.0), (0.0, 0.0, 0.0), fov_deg=40.0, resolution=(48, 32))
    img = render_plate(plate, cam, **booth.scene(plate, W), wavelength_nm=W)
    rgb, st = img.to_display(tone_map="knee")
    assert st["clipped_fraction"] <= 0.01 and np.all((rgb >= 0) & (rgb <= 1))
    # a matt plate of reflectance 0.3: about 0.3 of display white (the booth adds its inter-reflections)
    assert 0.25 * 120 < st["plate_mean_cd_m2"] < 0.45 * 120


def test_bad_display_settings_name_the_key():
    img = _image([1.0])
    for kw, key in [({"tone_map": "reinhard"}, "tone_map"), ({"knee": 1.5}, "knee"),
                    ({"display_white_cd_m2": -1.0}, "display_white_cd_m2"), ({"exposure": 0.0}, "exposure"),
                    ({"colourspace": "Adobe"}, "colourspace")]:
        with pytest.raises(InvalidInputError, match=key):
            img.to_display(**kw)
