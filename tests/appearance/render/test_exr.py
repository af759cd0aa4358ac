"""Spectral OpenEXR (Fichet et al. 2021 layout) round trips through the openexr package;
channel names parsed with colour-science's independent Fichet 2021 pattern."""

import re

import numpy as np
import pytest

from nmmm.appearance.render import (
    DirectionalLight,
    LambertianBRDF,
    PaintedPlate,
    PinholeCamera,
    read_spectral_exr,
    render_plate,
    spectral_channel_name,
    write_spectral_exr,
)
from nmmm.errors import DataFileError, InvalidInputError


def test_channel_name_format():
    assert spectral_channel_name(380) == "S0.380,000000nm"
    assert spectral_channel_name(552.5) == "S0.552,500000nm"


def test_exr_round_trip_with_openexr(tmp_path):
    import OpenEXR
    from colour.io.fichet2021 import PATTERN_FICHET2021, match_groups_to_nm

    w = np.arange(380.0, 781.0, 5.0)
    rng = np.random.default_rng(0)
    values = rng.random((7, 9, w.size)).astype(np.float32)
    rgb = rng.random((7, 9, 3)).astype(np.float32)
    p = write_spectral_exr(tmp_path / "s.exr", w, values, rgb=rgb)
    with OpenEXR.File(str(p), separate_channels=True) as f:
        header = f.header()
        chans = f.channels()
        assert header["spectralLayoutVersion"] == "1.0"
        assert header["emissiveUnits"] == "W.m^-2.sr^-1"
        assert {"R", "G", "B"} <= set(chans)
        pat = re.compile(rf"^(S[0-3])\.*{PATTERN_FICHET2021}$")
        found = {}
        for name, ch in chans.items():
            m = pat.match(name)
            if m:
                found[match_groups_to_nm(m.group(2), m.group(4) or "", m.group(5))] = np.asarray(ch.pixels)
        assert sorted(found) == pytest.approx(list(w))
        np.testing.assert_array_equal(found[550.0], values[..., 34])
        assert "S0.380,000000nm" in chans
    w2, v2, rgb2, hdr = read_spectral_exr(p)
    np.testing.assert_array_equal(w2, w)
    np.testing.assert_array_equal(v2, values)
    np.testing.assert_array_equal(rgb2, rgb)


def test_rendered_image_to_exr_and_png(tmp_path):
    img = render_plate(PaintedPlate(LambertianBRDF(0.5)), PinholeCamera(fov_deg=10, resolution=(12, 8)),
                       DirectionalLight(spectrum="D65"))
    p = img.write_exr(tmp_path / "plate.exr")
    w, v, rgb, hdr = read_spectral_exr(p)
    assert w.size == 81
    np.testing.assert_allclose(v, img.radiance, rtol=1e-6)
    # preview: a neutral grey under D65 has R = G = B (linear sRGB of XYZ / 100)
    np.testing.assert_allclose(rgb[..., 0], rgb[..., 2], rtol=2e-3)
    png = img.write_png(tmp_path / "plate.png")
    from PIL import Image

    a = np.asarray(Image.open(png))
    assert a.shape == (8, 12, 3)
    # 0.5 reflectance, exposure 1 -> sRGB(0.5) = 188/255
    assert np.all(np.abs(a.astype(int) - 188) <= 1)


def test_exr_bad_input(tmp_path):
    with pytest.raises(InvalidInputError):
        write_spectral_exr(tmp_path / "x.exr", [400, 500], np.zeros((2, 2, 3)))
    with pytest.raises(DataFileError, match="not found"):
        read_spectral_exr(tmp_path / "none.exr")
    bad = tmp_path / "bad.exr"
    bad.write_text("not an exr")
    with pytest.raises(DataFileError):
        read_spectral_exr(bad)
