"""Stimulus preparation: one format, one colour space, one size, no metadata."""

from __future__ import annotations

import io

import numpy as np
from PIL import Image, ImageCms

from nmmm.experiment.pairs import check_image
from nmmm.experiment.stimuli import prepare_image


def _png(data):
    im = Image.open(io.BytesIO(data))
    im.load()
    return im


def test_sixteen_bit_and_alpha_inputs_become_8bit_rgb(tmp_path):
    a16 = (np.linspace(0, 65535, 32 * 16).reshape(16, 32)).astype(np.uint16)
    Image.fromarray(a16).save(tmp_path / "g16.png")
    out = _png(prepare_image(tmp_path / "g16.png", (32, 16)))
    assert out.mode == "RGB" and out.size == (32, 16)
    arr = np.asarray(out)
    assert arr[0, 0, 0] == 0 and arr[-1, -1, 0] == 255
    rgba = np.zeros((8, 8, 4), np.uint8)
    rgba[..., 0] = 255
    rgba[:4, :, 3] = 255      # top half opaque red, bottom half transparent -> neutral grey
    Image.fromarray(rgba, "RGBA").save(tmp_path / "a.png")
    arr = np.asarray(_png(prepare_image(tmp_path / "a.png", (8, 8))))
    assert tuple(arr[0, 0]) == (255, 0, 0) and tuple(arr[-1, -1]) == (128, 128, 128)


def test_icc_profile_is_applied_then_dropped(tmp_path):
    rgb = np.full((8, 8, 3), (200, 120, 40), np.uint8)
    srgb = ImageCms.ImageCmsProfile(ImageCms.createProfile("sRGB")).tobytes()
    Image.fromarray(rgb).save(tmp_path / "s.jpg", quality=100, icc_profile=srgb)
    out = _png(prepare_image(tmp_path / "s.jpg", (8, 8)))
    assert "icc_profile" not in out.info and "exif" not in out.info
    # an sRGB-tagged image keeps its sRGB values (within JPEG and CMS rounding)
    assert np.abs(np.asarray(out).astype(int) - rgb).max() <= 3


def test_exif_orientation_is_applied(tmp_path):
    im = Image.fromarray(np.zeros((20, 40, 3), np.uint8))   # stored 40 wide x 20 high
    exif = Image.Exif()
    exif[0x0112] = 6                                         # displayed rotated by 90 degrees
    im.save(tmp_path / "rot.jpg", exif=exif.tobytes())
    assert check_image(tmp_path / "rot.jpg") == (20, 40)
    assert _png(prepare_image(tmp_path / "rot.jpg", (10, 20))).size == (10, 20)
