"""Image analysis: round trips against known models, analytic covariance and integral range."""

import math

import numpy as np
import pytest
from scipy import ndimage

import nmmm.microstructure as M
from nmmm.errors import DataFileError, InvalidInputError


def _sem_like(m, blur_px=1.5, noise=0.15, seed=0):
    rng = np.random.default_rng(seed)
    img = ndimage.gaussian_filter(m.labels.astype(float), blur_px, mode="wrap")
    return img + rng.normal(0.0, noise, img.shape)


def test_covariance_of_boolean_discs_matches_matheron():
    p, R = 0.3, 6.0
    m = M.boolean_spheres((512, 512), 1.0, R, fraction=p, seed=2)
    h, c = M.covariance_profile(m, 1.0, max_lag_nm=30)
    pm = m.volume_fraction()
    assert c[0] == pytest.approx(pm)
    # analytic C(h) with the realised fraction; tolerance from the statistical error of
    # the covariance (~ sqrt(p q A / |W|)) plus digitisation of the discs
    c_th = M.boolean_covariance(h, pm, R, "disc")
    assert np.max(np.abs(c - c_th)) < 0.01
    assert c[-1] == pytest.approx(pm**2, abs=0.01)


def test_periodic_covariance_sums_to_p_squared_over_cell():
    m = M.boolean_spheres((128, 128), 1.0, 5.0, fraction=0.2, seed=0)
    c = M.covariance(m)
    p = m.volume_fraction()
    assert c.mean() == pytest.approx(p * p, rel=1e-10)  # why the integral range uses half the cell


def test_integral_range_matches_analytic_boolean():
    # Boolean discs: A = int (C - p^2) / (p q) dh, computed by quadrature of Matheron's C(h)
    R, p = 5.0, 0.3
    A_th = M.boolean_integral_range(p, R, "disc")
    est = [M.integral_range(M.boolean_spheres((384, 384), 1.0, R, fraction=p, seed=s)) for s in range(6)]
    mean, sem = np.mean(est), np.std(est, ddof=1) / math.sqrt(len(est))
    assert abs(mean - A_th) < 3 * sem + 0.05 * A_th


def test_round_trip_boolean_discs_with_blur_and_noise():
    R, p, pix = 60.0, 0.35, 10.0
    m = M.boolean_spheres((768, 768), pix, R, fraction=p, seed=4)
    # blur of 1 px (PSF sigma) and noise; heavier blur acts as a closing that fills the
    # narrow gaps between overlapping grains and biases R upwards (+8 % at 1.8 px total)
    b = M.binarize(_sem_like(m, blur_px=1.0), smooth_px=0.0)
    est = M.estimate_boolean(b, pix, "disc")
    # radius: statistical + segmentation error of a fraction of a pixel on R = 6 px
    assert est["radius_nm"] == pytest.approx(R, rel=0.05)
    # fraction: within 4 sigma, sigma = sqrt(p q A / |W|)
    A = M.boolean_integral_range(p, R, "disc")
    sigma = math.sqrt(p * (1 - p) * A / (768 * pix) ** 2)
    assert abs(est["fraction"] - p) < 4 * sigma + 0.01
    theta = -math.log(1 - p) / (math.pi * R**2)
    assert est["intensity"] == pytest.approx(theta, rel=0.15)


def test_round_trip_spheres_from_a_section():
    # a section of a 3-D Boolean model of spheres has the sphere covariogram in-plane
    R = 40.0
    m = M.boolean_spheres((160, 160, 160), 5.0, R, fraction=0.2, seed=6)
    est = M.estimate_boolean(m.section(axis=2).labels > 0, 5.0, "sphere")
    assert est["radius_nm"] == pytest.approx(R, rel=0.08)


def test_round_trip_hardcore_exclusion_zone():
    R, gap, pix = 80.0, 60.0, 10.0
    m = M.hardcore_spheres((768, 768), pix, R, 0.25, exclusion_nm=gap, seed=5)
    b = M.binarize(_sem_like(m), smooth_px=1.0, min_size_px=10)
    for periodic in (True, False):
        est = M.estimate_hardcore(b, pix, periodic=periodic)
        assert est["radius_nm"] == pytest.approx(R, rel=0.03)
        # the hard-core distance 2R + gap is reached by RSA contacts; centroids are
        # accurate to a fraction of a pixel
        assert est["exclusion_radius_nm"] == pytest.approx(R + gap / 2, abs=0.5 * pix)
        assert est["fraction"] == pytest.approx(m.volume_fraction(), abs=0.01)
    assert est["n_particles"] == pytest.approx(m.params["n_particles"], rel=0.05)


def test_granulometry_of_equal_discs_is_a_step():
    m = M.hardcore_spheres((256, 256), 1.0, 8.0, 0.2, seed=1)
    g = M.granulometry(m, [0.0, 4.0, 6.0, 9.0], 1.0)
    assert g["fraction"][0] == pytest.approx(m.volume_fraction())
    assert g["fraction"][1] == pytest.approx(m.volume_fraction(), rel=0.02)
    assert g["fraction"][3] == 0.0


def test_periodic_labelling_merges_across_edges():
    b = np.zeros((20, 20), bool)
    b[0:3, 5:8] = True
    b[18:20, 5:8] = True
    _, n_open = M.label_particles(b, periodic=False)
    _, n_per = M.label_particles(b, periodic=True)
    assert (n_open, n_per) == (2, 1)
    st = M.particle_statistics(b, 1.0, periodic=True)
    assert st.count == 1 and st.areas_nm2[0] == 15
    assert st.centroids_nm[0, 0] == pytest.approx(0.5, abs=1e-9) or st.centroids_nm[0, 0] == pytest.approx(
        20.5 - 20, abs=1e-9)


def test_analyze_image_and_figure(tmp_path):
    m = M.hardcore_spheres((256, 256), 10.0, 60.0, 0.2, exclusion_nm=40, seed=3)
    res = M.analyze_image(_sem_like(m), 10.0)
    s = res.summary()
    assert s["area_fraction"] == pytest.approx(m.volume_fraction(), abs=0.02)
    out = res.plot(tmp_path / "fig.png")
    assert (tmp_path / "fig.png").stat().st_size > 10_000 and out.endswith("fig.png")


def test_bad_images(tmp_path):
    with pytest.raises(DataFileError, match="not found"):
        M.read_image(tmp_path / "missing.png")
    bad = tmp_path / "bad.png"
    bad.write_text("not an image")
    with pytest.raises(DataFileError, match="cannot read"):
        M.read_image(bad)
    fake = tmp_path / "fake.npz"
    fake.write_text("not an archive")
    with pytest.raises(DataFileError, match="not a .npz"):
        M.load_microstructure(fake)
    with pytest.raises(InvalidInputError, match="NaN"):
        M.binarize(np.array([[0.0, np.nan], [1.0, 0.5]]))
    with pytest.raises(InvalidInputError, match="binary"):
        M.area_fraction(np.array([[0.0, 0.3], [1.0, 0.5]]))
    with pytest.raises(InvalidInputError, match="uniform"):
        M.binarize(np.ones((8, 8)))
