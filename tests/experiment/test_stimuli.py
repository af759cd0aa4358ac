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


def test_restart_reuses_the_content_addressed_cache(tmp_path):
    from experiment_helpers import make_pairs, write_image

    from nmmm.experiment.pairs import load_pairs
    from nmmm.experiment.stimuli import StimulusStore

    toml = make_pairs(tmp_path, n_pairs=3)
    ps = load_pairs(toml)
    first = StimulusStore(ps, tmp_path / "cache")
    assert first.counts == {"prepared": 6, "reused": 0}
    again = StimulusStore(ps, tmp_path / "cache")          # a restarted server
    assert again.counts == {"prepared": 0, "reused": 6}
    for pair in ps.pairs:
        for role in ("rendered", "photo"):
            assert again.raw(pair.pair_id, role) == first.raw(pair.pair_id, role)
            assert again.raw(pair.pair_id, role) == prepare_pixels_bytes(pair.image(role), first.size(pair.pair_id))
    # a damaged entry is prepared again, never served
    victim = sorted((tmp_path / "cache").glob("*.rgb"))[0]
    data = bytearray(victim.read_bytes())
    data[0] ^= 0xFF
    victim.write_bytes(bytes(data))
    assert StimulusStore(ps, tmp_path / "cache").counts == {"prepared": 1, "reused": 5}
    # a changed image is a new key: the old pixels are not reused for it
    write_image(ps.pairs[0].rendered, size=(48, 32), colour=(10, 200, 10), seed=99)
    changed = StimulusStore(ps, tmp_path / "cache")
    assert changed.counts == {"prepared": 1, "reused": 5}
    assert changed.raw(ps.pairs[0].pair_id, "rendered") != first.raw(ps.pairs[0].pair_id, "rendered")


def prepare_pixels_bytes(path, size):
    from nmmm.experiment.stimuli import prepare_pixels

    return prepare_pixels(path, size).tobytes()


def test_served_encodings_have_content_independent_lengths(tmp_path):
    from nmmm.experiment.stimuli import bmp_length, encode_bmp

    rng = np.random.default_rng(1)
    for w, h in [(1, 1), (5, 7), (48, 32), (33, 2)]:
        noisy = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
        flat = np.zeros((h, w, 3), np.uint8)
        a, b = encode_bmp(noisy), encode_bmp(flat)
        assert len(a) == len(b) == bmp_length(w, h) and a[:54] == b[:54]
        im = Image.open(io.BytesIO(a))
        assert im.format == "BMP" and im.size == (w, h) and np.array_equal(np.asarray(im), noisy)
