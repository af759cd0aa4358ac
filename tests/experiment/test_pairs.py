"""pairs.toml: loading, writing, and clear errors for bad files and images."""

from __future__ import annotations

import pytest

from nmmm.errors import DataFileError, InvalidInputError
from nmmm.experiment.pairs import check_image, load_pairs, make_pairs_file

from experiment_helpers import make_pairs, write_image


def test_make_pairs_file_roundtrip(tmp_path):
    toml = make_pairs(tmp_path, n_pairs=3, repetitions=2, viewing_distance_cm=60)
    ps = load_pairs(toml)
    assert len(ps) == 3 and ps.n_trials == 6
    assert ps.settings.viewing_distance_cm == 60
    assert [p.label for p in ps.pairs] == ["plate 0", "plate 1", "plate 2"]
    assert ps.pairs[0].rendered == (tmp_path / "img" / "r0.png").resolve()
    text = toml.read_text()
    assert '"img/r0.png"' in text  # written relative to the toml
    assert "60 cm" in ps.settings.calibration_text()


def test_paths_relative_to_toml_not_cwd(tmp_path, monkeypatch):
    toml = make_pairs(tmp_path)
    monkeypatch.chdir("/")
    assert load_pairs(toml).pairs[0].photo.is_file()


def test_duplicate_labels_get_unique_ids(tmp_path):
    r = write_image(tmp_path / "r.png")
    p = write_image(tmp_path / "p.png", seed=1)  # not a byte-identical copy of r (refused since issue 21)
    toml = make_pairs_file([(r, p, "same"), (r, p, "same")], tmp_path / "pairs.toml")
    assert [q.pair_id for q in load_pairs(toml).pairs] == ["same", "same-2"]


def test_stereo_pairs(tmp_path):
    ps = load_pairs(make_pairs(tmp_path, n_pairs=2, stereo=True))
    assert ps.settings.stereo
    assert ps.pairs[0].image("photo", "right").name == "p0_R.png"


def _write(tmp_path, text):
    p = tmp_path / "pairs.toml"
    p.write_text(text)
    return p


def test_missing_file(tmp_path):
    with pytest.raises(DataFileError, match="not found"):
        load_pairs(tmp_path / "nope.toml")


def test_malformed_toml(tmp_path):
    with pytest.raises(DataFileError, match="not valid TOML"):
        load_pairs(_write(tmp_path, "[[pair]\nrendered = 'a.png'"))


def test_no_pairs(tmp_path):
    with pytest.raises(DataFileError, match=r"no \[\[pair\]\] entries"):
        load_pairs(_write(tmp_path, "[experiment]\ntitle = 'x'\n"))


def test_unknown_keys(tmp_path):
    write_image(tmp_path / "a.png")
    with pytest.raises(DataFileError, match="unknown key.*'photograph'"):
        load_pairs(_write(tmp_path, "[[pair]]\nrendered = 'a.png'\nphotograph = 'a.png'\n"))
    with pytest.raises(DataFileError, match=r"unknown \[experiment\] key.*'blank'"):
        load_pairs(_write(tmp_path, "[experiment]\nblank = 3\n[[pair]]\nrendered = 'a.png'\nphoto = 'a.png'\n"))


def test_missing_key_and_bad_setting(tmp_path):
    write_image(tmp_path / "a.png")
    with pytest.raises(DataFileError, match="missing 'photo'"):
        load_pairs(_write(tmp_path, "[[pair]]\nrendered = 'a.png'\n"))
    with pytest.raises(DataFileError, match="blank_ms"):
        load_pairs(_write(tmp_path, "[experiment]\nblank_ms = -5\n[[pair]]\nrendered = 'a.png'\nphoto = 'a.png'\n"))


def test_missing_image_at_load_time(tmp_path):
    write_image(tmp_path / "a.png")
    with pytest.raises(DataFileError, match=r"pair 1 .*photo image .*missing\.jpg.*not found.*relative to the"):
        load_pairs(_write(tmp_path, "[[pair]]\nrendered = 'a.png'\nphoto = 'missing.jpg'\n"))
    with pytest.raises(DataFileError, match="not found"):
        make_pairs_file([(tmp_path / "a.png", tmp_path / "gone.png", "x")], tmp_path / "out.toml")


def test_non_image_and_oversized(tmp_path):
    write_image(tmp_path / "a.png")
    (tmp_path / "fake.png").write_text("this is not an image")
    with pytest.raises(DataFileError, match="not an image"):
        load_pairs(_write(tmp_path, "[[pair]]\nrendered = 'a.png'\nphoto = 'fake.png'\n"))
    (tmp_path / "empty.png").write_bytes(b"")
    with pytest.raises(DataFileError, match="empty"):
        check_image(tmp_path / "empty.png")
    big = write_image(tmp_path / "big.png", size=(300, 200))
    with pytest.raises(DataFileError, match="pixels"):
        check_image(big, max_pixels=10_000)
    with pytest.raises(DataFileError, match="MiB"):
        check_image(big, max_bytes=100)
    p = _write(tmp_path, "[[pair]]\nrendered = 'a.png'\nphoto = 'big.png'\n")
    with pytest.raises(DataFileError, match="pixels"):
        load_pairs(p, max_pixels=10_000)


def test_aspect_ratio_mismatch_is_refused(tmp_path):
    write_image(tmp_path / "a.png", size=(48, 32))
    write_image(tmp_path / "b.png", size=(48, 48))
    with pytest.raises(DataFileError, match="aspect ratio"):
        load_pairs(_write(tmp_path, "[[pair]]\nrendered = 'a.png'\nphoto = 'b.png'\n"))


def test_stereo_needs_views_and_duplicate_ids(tmp_path):
    write_image(tmp_path / "a.png")
    with pytest.raises(DataFileError, match="stereo = true needs 'rendered_stereo'"):
        load_pairs(_write(tmp_path, "[experiment]\nstereo = true\n[[pair]]\nrendered = 'a.png'\nphoto = 'a.png'\n"))
    with pytest.raises(DataFileError, match="used twice"):
        load_pairs(_write(tmp_path, "[[pair]]\nid='x'\nrendered = 'a.png'\nphoto = 'a.png'\n"
                                    "[[pair]]\nid='x'\nrendered = 'a.png'\nphoto = 'a.png'\n"))


def test_make_pairs_file_rejects_bad_arguments(tmp_path):
    with pytest.raises(InvalidInputError, match="unknown experiment setting"):
        make_pairs_file([], tmp_path / "x.toml", blank=3)
    with pytest.raises(InvalidInputError, match="at least one"):
        make_pairs_file([], tmp_path / "x.toml")


def test_make_pairs_file_from_rendered_arrays(tmp_path):
    import numpy as np
    from PIL import Image

    photo = write_image(tmp_path / "photo.jpg", size=(40, 20))
    render = np.linspace(0, 1, 20 * 40 * 3).reshape(20, 40, 3)
    toml = make_pairs_file([(render, photo, "plate A")], tmp_path / "exp" / "pairs.toml")
    pair = load_pairs(toml).pairs[0]
    assert pair.rendered == (tmp_path / "exp" / "rendered" / "plate-A.png").resolve()
    back = np.asarray(Image.open(pair.rendered))
    np.testing.assert_array_equal(back, np.round(render * 255).astype(np.uint8))
    with pytest.raises(InvalidInputError, match=r"in \[0, 1\]"):
        make_pairs_file([(render * 2, photo, "x")], tmp_path / "bad.toml")
    with pytest.raises(InvalidInputError, match="height, width, 3"):
        make_pairs_file([(np.zeros((4, 4)), photo, "x")], tmp_path / "bad.toml")
