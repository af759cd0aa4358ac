"""Random models: fractions against analytic values, hard-core exclusion, jamming errors."""

import math

import numpy as np
import pytest

import nmmm.microstructure as M
from nmmm.errors import ConvergenceError, InvalidInputError


def test_boolean_spheres_fraction_matches_matheron():
    # p = 1 - exp(-theta V) (Matheron 1975); statistical error from the analytic integral
    # range: std(p) = sqrt(p q A / V)
    R, vox, n = 4.0, 1.0, 96
    m = M.boolean_spheres((n, n, n), vox, R, intensity=0.2 / (4 / 3 * math.pi * R**3), seed=7)
    p_th = 1 - math.exp(-0.2)
    A = M.boolean_integral_range(p_th, R, "sphere")
    sigma = math.sqrt(p_th * (1 - p_th) * A / n**3)
    # digitisation of spheres of radius 4 voxels: the voxel count of a ball differs from
    # 4/3 pi R^3 by < 1 %; allow it on top of 4 sigma
    assert abs(m.volume_fraction() - p_th) < 4 * sigma + 0.01 * p_th


def test_boolean_discs_2d_fraction_and_intensity():
    m = M.boolean_spheres((512, 512), 2.0, 10.0, fraction=0.4, seed=1)
    A = M.boolean_integral_range(0.4, 10.0, "disc")
    sigma = math.sqrt(0.24 * A / (1024.0**2))
    assert abs(m.volume_fraction() - 0.4) < 4 * sigma + 0.005
    assert m.params["intensity_per_nm"] == pytest.approx(-math.log(0.6) / (math.pi * 100))


def test_boolean_cubes_and_platelets_reach_fraction():
    # given the realised number N of grains, p = 1 - exp(-N V / |cell|) up to the
    # (small) fluctuation of the overlaps and the digitisation
    m = M.boolean_cubes((64, 64, 64), 1.0, 8.0, fraction=0.25, seed=3)
    p_n = 1 - math.exp(-m.params["n_particles"] * 8.0**3 / 64**3)
    assert abs(m.volume_fraction() - p_n) < 0.02
    d = M.boolean_discs((96, 96, 96), 1.0, 16.0, fraction=0.1, thickness_nm=3.0, seed=3)
    p_n = 1 - math.exp(-d.params["n_particles"] * math.pi * 64 * 3.0 / 96**3)
    assert abs(d.volume_fraction() - p_n) < 0.015


def test_reproducible_with_seed_and_periodic_wrap():
    a = M.hardcore_spheres((48, 48, 48), 1.0, 3.0, 0.1, seed=11)
    b = M.hardcore_spheres((48, 48, 48), 1.0, 3.0, 0.1, seed=11)
    c = M.hardcore_spheres((48, 48, 48), 1.0, 3.0, 0.1, seed=12)
    assert np.array_equal(a.labels, b.labels)
    assert not np.array_equal(a.labels, c.labels)
    # a sphere straddling a face is split across opposite faces: total voxel count equals
    # the count of the same sphere at the centre
    ps = M.ParticleSet(np.array([[0.0, 10.0, 10.0]]), np.eye(3)[None], np.full((1, 3), 5.0), np.array([0]),
                       np.array([2.0]), np.array([1]), (20.0, 20.0, 20.0))
    ps2 = M.ParticleSet(np.array([[10.0, 10.0, 10.0]]), np.eye(3)[None], np.full((1, 3), 5.0), np.array([0]),
                        np.array([2.0]), np.array([1]), (20.0, 20.0, 20.0))
    assert ps.rasterize(1.0).labels.sum() == ps2.rasterize(1.0).labels.sum()


def test_hardcore_spheres_no_overlap_and_fraction():
    box = (200.0, 200.0, 200.0)
    ps = M.hardcore_particles(box, "sphere", 8.0, 0.25, exclusion_nm=2.0, seed=5)
    c = ps.centres_nm
    from scipy.spatial import cKDTree

    d, _ = cKDTree(c, boxsize=box).query(c, k=2)
    assert d[:, 1].min() >= 2 * 8.0 + 2.0 - 1e-9  # exclusion distance respected (periodic)
    assert ps.nominal_fraction() == pytest.approx(0.25, rel=0.01)
    m = ps.rasterize(1.0)
    assert m.volume_fraction() == pytest.approx(0.25, rel=0.03)  # digitisation only


def test_pseudocubes_volume_and_diagonal():
    # exact cube (exponent inf): edge = diagonal / sqrt(3)
    from nmmm.microstructure.hardcore import pseudocube_half_size
    from nmmm.microstructure.particles import superball_volume

    assert 2 * pseudocube_half_size(250.0, math.inf) == pytest.approx(250 / math.sqrt(3))
    # exponent 2 is a sphere of diameter = diagonal
    a = pseudocube_half_size(250.0, 2.0)
    assert a == pytest.approx(125.0)
    assert float(superball_volume([a, a, a], 2.0)) == pytest.approx(4 / 3 * math.pi * 125.0**3)
    m = M.hardcore_pseudocubes((96, 96, 96), 10.0, 250.0, 0.07, seed=2)
    assert m.volume_fraction() == pytest.approx(0.07, rel=0.08)
    assert m.phases[1] == "hematite"


@pytest.mark.parametrize("shape,fraction,limit", [((64, 64, 64), 0.40, "0.38278"), ((256, 256), 0.56, "0.547069")])
def test_jamming_limit_error_names_the_limit(shape, fraction, limit):
    with pytest.raises(InvalidInputError, match=limit):
        M.hardcore_spheres(shape, 1.0, 3.0, fraction, seed=0)


def test_cube_jamming_limit_scaled_by_shape():
    # cubes in their circumscribed spheres: 0.38278 * 2/(pi sqrt 3) = 0.1407
    with pytest.raises(InvalidInputError, match="0.1407"):
        M.hardcore_pseudocubes((64, 64, 64), 10.0, 250.0, 0.15, exponent=math.inf)


def test_rsa_centres_bad_input():
    with pytest.raises(InvalidInputError, match="exclusion_radii_nm must be > 0"):
        M.rsa_centres((100.0, 100.0), np.array([-1.0, 2.0]), seed=0)
    with pytest.raises(InvalidInputError, match="exclusion_radii_nm contains NaN"):
        M.rsa_centres((100.0, 100.0), np.array([np.nan, 2.0]), seed=0)
    with pytest.raises(InvalidInputError, match="box_nm"):
        M.rsa_centres((-100.0, 100.0), np.array([1.0, 2.0]), seed=0)


def test_close_to_jamming_raises_convergence_error():
    with pytest.raises(ConvergenceError, match="jamming"):
        M.hardcore_particles((300.0, 300.0), "sphere", 3.0, 0.53, seed=0, max_attempts=20_000)


def test_bad_inputs():
    with pytest.raises(InvalidInputError, match="radius_nm contains NaN"):
        M.boolean_spheres((32, 32, 32), 1.0, float("nan"), fraction=0.1)
    with pytest.raises(InvalidInputError, match="radius_nm must be > 0"):
        M.hardcore_spheres((32, 32, 32), 1.0, -3.0, 0.1)
    with pytest.raises(InvalidInputError, match="diagonal_nm must be > 0"):
        M.hardcore_pseudocubes((32, 32, 32), 10.0, 0.0, 0.05)
    with pytest.raises(InvalidInputError):
        M.boolean_spheres((32, 32, 32), 1.0, 3.0, fraction=1.2)
    with pytest.raises(InvalidInputError):
        M.hardcore_spheres((32, 32, 32), 1.0, 3.0, float("nan"))
    with pytest.raises(InvalidInputError):
        M.Microstructure(np.zeros((4, 4)) + 0.5, 1.0)



@pytest.mark.parametrize("box", [(-100.0, 100.0), (100.0, float("nan")), (100.0,), (0.0, 100.0, 100.0)])
def test_bad_cell_sizes_are_named(box):
    for make in (
        lambda: M.boolean_particles(box, "sphere", 3.0, fraction=0.1, seed=0),
        lambda: M.hardcore_particles(box, "sphere", 3.0, 0.1, seed=0),
        lambda: M.aggregate_particles(box, 3.0, 10.0, 4, 0.1, seed=0),
    ):
        with pytest.raises(InvalidInputError, match="box_nm must hold 2 or 3 positive lengths"):
            make()


def test_anisotropic_voxels_and_section():
    m = M.boolean_spheres((40, 40, 80), (2.0, 2.0, 1.0), 6.0, fraction=0.2, seed=4)
    assert m.voxel_nm == (2.0, 2.0, 1.0)
    assert m.size_nm == (80.0, 80.0, 80.0)
    s = m.section(axis=2)
    assert s.shape == (40, 40) and s.voxel_nm == (2.0, 2.0)


def test_aggregates_cluster_more_than_poisson():
    # the clustered model has a larger integral range than a Boolean model of the same
    # particles at the same fraction (a cluster process is over-dispersed)
    agg = M.aggregates((256, 256), 1.0, 3.0, 12.0, 6, 0.1, seed=1)
    boo = M.boolean_spheres((256, 256), 1.0, 3.0, fraction=agg.volume_fraction(), seed=1)
    assert M.integral_range(agg) > 2 * M.integral_range(boo)


def test_aggregate_counts_follow_the_cluster_process():
    # parents: Poisson number with mean p|W| / (mu V); children per parent 1 + Poisson(mu - 1)
    # (mean mu, variance mu - 1): both within 4 standard errors
    p, mu, r, box = 0.02, 6.0, 5.0, (4000.0, 4000.0)
    ps = M.aggregate_particles(box, r, 40.0, mu, p, seed=3)
    n_agg = ps.params["n_aggregates"]
    lam = p * box[0] * box[1] / (mu * math.pi * r**2)
    assert abs(n_agg - lam) < 4 * math.sqrt(lam)
    assert abs(len(ps) / n_agg - mu) < 4 * math.sqrt((mu - 1) / n_agg)
    # clustered: the median nearest-neighbour distance is well below that of a Poisson
    # process of the same density, sqrt(ln 2 / (pi rho)) (here about half of it)
    from scipy.spatial import cKDTree

    d, _ = cKDTree(ps.centres_nm[:, :2], boxsize=box).query(ps.centres_nm[:, :2], k=2)
    rho = len(ps) / (box[0] * box[1])
    assert np.median(d[:, 1]) < 0.7 * math.sqrt(math.log(2) / (math.pi * rho))


def test_flake_deposit_statistics_and_rasterisation():
    f = M.flake_deposit(box_nm=(100_000.0, 100_000.0, 20_000.0), diameter_nm=15_000.0, thickness_nm=400.0,
                        fraction=0.03, tilt_std_deg=3.0, exclusion_nm=100.0, seed=3)
    s = f.summary()
    # half-normal tilts with scale sigma have mean sigma sqrt(2/pi)
    assert s["mean_tilt_deg"] == pytest.approx(3.0 * math.sqrt(2 / math.pi), rel=0.25)
    assert np.all(f.centres_nm[:, 2] - f.half_height_nm >= -1e-6)  # above the substrate
    assert s["max_height_nm"] <= 20_000.0
    assert f.volume_fraction() == pytest.approx(0.03, rel=0.3)  # Poisson number of flakes
    m = f.rasterize(voxel_nm=(500.0, 500.0, 100.0))
    # flakes do not overlap (deposit with exclusion): voxel fraction ~ nominal fraction
    assert m.volume_fraction() == pytest.approx(f.volume_fraction(), rel=0.1)
    w = f.window((0.0, 0.0), (30_000.0, 30_000.0))
    assert w.box_nm == (30_000.0, 30_000.0, 20_000.0) and not w.periodic and len(w) > 0


def test_flake_deposit_too_thin_layer_is_an_error():
    with pytest.raises(InvalidInputError, match="layer thickness"):
        M.flake_deposit(box_nm=(100_000.0, 100_000.0, 5_000.0), fraction=0.1, seed=0)
