"""Issue 21, "silently wrong or accepted": the cases left open by the first pass, each now a
clean error or a warning that says what would be right.

- a coherent 1 m layer in a Stack (aliased fringes): a warning saying the layer should be incoherent;
- a spectral power file that is all zero (error) or covers only 500-510 nm (warning naming the range);
- a pairs file whose rendered image is the photograph (same path, a link, or a byte-identical copy): error;
- ``experiment stats --alpha 2`` : a message naming alpha and its valid range (it said "... got -3.0");
- a plate render too large for the machine: refused with its memory estimate (unbounded work).
"""

import shutil
import warnings

import numpy as np
import pytest

from nmmm.errors import DataFileError, InvalidInputError


def test_coherent_metre_thick_layer_warns_to_make_it_incoherent():
    from nmmm.layers import Stack

    w = np.arange(400.0, 701.0, 10.0)
    with pytest.warns(UserWarning, match=r"layer 0 .*1e\+09 nm.*coherent.*should be incoherent.*coherent=False"):
        Stack([(1.5, 1e9)], substrate=1.5).rt(w)
    # a 20 µm clear coat sampled every 10 nm is aliased as well
    with pytest.warns(UserWarning, match="aliased"):
        Stack([(1.5, 20_000.0)], substrate=1.5).rt(w)
    # thin films, and thick layers declared incoherent, stay quiet
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Stack([(1.5, 1200.0)], substrate=3.8).rt(np.arange(300.0, 1001.0, 5.0))
        Stack([(1.5, 1e9, False)], substrate=1.5).rt(w)
        Stack([(1.38, 100.0)], substrate=1.52).rt(550.0)


def test_spectral_power_file_all_zero_or_narrow(tmp_path):
    from nmmm.appearance.render import read_spd_csv

    zero = tmp_path / "zero.csv"
    zero.write_text("wavelength_nm,power\n" + "".join(f"{w},0\n" for w in range(380, 781, 10)))
    with pytest.raises(DataFileError, match="zero at every wavelength.*380-780 nm"):
        read_spd_csv(zero)
    narrow = tmp_path / "narrow.csv"
    narrow.write_text("wavelength_nm,power\n500,1\n505,2\n510,1\n")
    with pytest.warns(UserWarning, match="covers only 500-510 nm, not the visible 380-780 nm"):
        s = read_spd_csv(narrow)
    with pytest.raises(InvalidInputError, match="500-510 nm"):
        s.on(np.arange(380.0, 781.0, 5.0))
    full = tmp_path / "full.csv"
    full.write_text("wavelength_nm,power\n" + "".join(f"{w},1\n" for w in range(360, 831, 10)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_spd_csv(full)


def _pairs(tmp_path, rendered, photo):
    p = tmp_path / "pairs.toml"
    p.write_text(f"[[pair]]\nrendered = '{rendered}'\nphoto = '{photo}'\n")
    return p


def test_pairs_file_with_the_same_image_twice_is_refused(tmp_path):
    from PIL import Image

    from nmmm.experiment.pairs import load_pairs

    rng = np.random.default_rng(0)
    for name in ("a.png", "b.png"):
        Image.fromarray(rng.integers(0, 255, (32, 48, 3), dtype=np.uint8)).save(tmp_path / name)
    shutil.copy(tmp_path / "a.png", tmp_path / "copy.png")
    (tmp_path / "link.png").symlink_to(tmp_path / "a.png")
    for photo in ("a.png", "./a.png", "copy.png", "link.png"):
        with pytest.raises(DataFileError, match="'rendered' and 'photo' are the same image"):
            load_pairs(_pairs(tmp_path, "a.png", photo))
    assert len(load_pairs(_pairs(tmp_path, "a.png", "b.png"))) == 1


def test_stats_alpha_out_of_range_names_alpha_and_its_range():
    from nmmm.experiment.stats import analyse_responses

    rows = [{"participant_id": "p1", "pair_id": "a", "correct": 1, "n_trials": 2},
            {"participant_id": "p1", "pair_id": "a", "correct": 0, "n_trials": 2}]
    for alpha in (2, 0, -1, 0.5):
        with pytest.raises(InvalidInputError, match=r"alpha .* must be in \(0, 0.5\).*got"):
            analyse_responses(rows, alpha=alpha)
    with pytest.raises(InvalidInputError, match=r"confidence must be in \(0, 1\)"):
        analyse_responses(rows, confidence=95)


def test_plate_render_too_large_is_refused_with_its_estimate():
    from nmmm.appearance.render import DirectionalLight, LambertianBRDF, PaintedPlate, PinholeCamera, render_plate

    plate = PaintedPlate(LambertianBRDF(0.5), size_mm=(150, 100))
    light = DirectionalLight.from_angles(0.0, 0.0, "D65", 1.0)
    cam = PinholeCamera((0, -100, 400), (0, 0, 0), fov_deg=20, resolution=(200_000, 133_333))
    with pytest.raises(InvalidInputError, match=r"200000 x 133333 render at \d+ wavelengths needs about .* GB.*max_memory_gb"):
        render_plate(plate, cam, light)
    small = PinholeCamera((0, -100, 400), (0, 0, 0), fov_deg=20, resolution=(64, 43))
    with pytest.raises(InvalidInputError, match="above the 1e-05 GB limit"):
        render_plate(plate, small, light, max_memory_gb=1e-5)
    assert render_plate(plate, small, light).radiance.shape[:2] == (43, 64)
