"""RVE (Kanit et al. 2003) against the analytic variance of a Boolean model; files; CLI."""

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

import nmmm.microstructure as M
from nmmm.errors import InvalidInputError


def test_fit_rve_recovers_known_power_law():
    # synthetic data following D^2(V) = D2z (A/V)^alpha exactly (Kanit 2003, eq. 14)
    rng = np.random.default_rng(0)
    A, alpha, D2z, mean = 500.0, 1.0, 0.21, 0.3
    vols = np.array([1e4, 4e4, 1.6e5, 6.4e5])
    vals = []
    for V in vols:
        z = rng.standard_normal(4000)
        z = (z - z.mean()) / z.std(ddof=1)
        vals.append(mean + math.sqrt(D2z * (A / V) ** alpha) * z)
    fit = M.fit_rve(vols, vals, point_variance=D2z, ndim=2)
    assert fit.alpha == pytest.approx(1.0, rel=1e-6)
    assert fit.integral_range == pytest.approx(A, rel=1e-6)
    # eps = 2 D(V) / (Z sqrt(n))  ->  V = A (4 D2z / (n eps^2 Z^2))^(1/alpha)
    V = fit.volume_for(0.01, n_realisations=5)
    assert V == pytest.approx(A * 4 * D2z / (5 * 1e-4 * mean**2))
    assert fit.realisations_for(0.01, V) == 5


def test_rve_of_boolean_area_fraction_matches_integral_range():
    # windows of a Boolean model of discs: D^2(V) = p q A / V for V >> A with A the
    # analytic integral range (Lantuejoul 1991), i.e. alpha = 1
    R, p = 4.0, 0.3
    A_th = M.boolean_integral_range(p, R, "disc")
    big = [M.boolean_spheres((512, 512), 1.0, R, fraction=p, seed=s).labels > 0 for s in range(4)]
    sizes = [32, 64, 128]
    vals = []
    for L in sizes:
        z = [im[i:i + L, j:j + L].mean() for im in big for i in range(0, 512, L) for j in range(0, 512, L)]
        vals.append(np.array(z))
    fit = M.fit_rve([L * L for L in sizes], vals, point_variance=p * (1 - p), ndim=2)
    assert fit.alpha == pytest.approx(1.0, abs=0.15)
    fit1 = M.fit_rve([L * L for L in sizes], vals, point_variance=p * (1 - p), ndim=2, fix_alpha=1.0)
    assert fit1.integral_range == pytest.approx(A_th, rel=0.2)
    edge = fit1.size_for(0.01, 1)
    assert edge == pytest.approx(math.sqrt(4 * p * (1 - p) * A_th / (1e-4 * p**2)), rel=0.2)


def test_fit_rve_bad_input():
    with pytest.raises(InvalidInputError):
        M.fit_rve([1.0, 2.0], [np.array([1.0]), np.array([1.0, 2.0])])
    with pytest.raises(InvalidInputError):
        M.fit_rve([1.0, 2.0], [np.array([1.0, np.nan]), np.array([1.0, 2.0])])


@pytest.mark.parametrize("suffix", [".tif", ".npz"])
def test_save_load_round_trip(tmp_path, suffix):
    m = M.hardcore_pseudocubes((40, 48, 24), (10.0, 10.0, 20.0), 250.0, 0.05, seed=1)
    path = M.save_microstructure(m, tmp_path / f"cell{suffix}")
    m2 = M.load_microstructure(path)
    assert np.array_equal(m2.labels, m.labels)
    assert m2.voxel_nm == m.voxel_nm and m2.periodic and m2.phases == m.phases
    assert m2.params["model"] == "hardcore_pseudocubes" and m2.params["size_nm"]["mean_nm"] == 250.0
    if suffix == ".tif":  # ImageJ order: pages = z, rows = y, columns = x
        import tifffile

        assert tifffile.imread(path).shape == (24, 48, 40)


def test_cli_generate_and_analyze(tmp_path):
    from nmmm.microstructure.cli import micro

    cfg = tmp_path / "model.toml"
    cfg.write_text('model = "hardcore_spheres"\nshape = [128, 128]\nvoxel_nm = 10.0\nradius_nm = 60.0\n'
                   'fraction = 0.2\nexclusion_nm = 30.0\nseed = 2\n')
    out = tmp_path / "cell.tif"
    r = CliRunner().invoke(micro, ["generate", str(cfg), "-o", str(out)])
    assert r.exit_code == 0, r.output
    m = M.load_microstructure(out)
    assert m.shape == (128, 128)
    from PIL import Image

    png = tmp_path / "sem.png"
    Image.fromarray((m.labels.T * 200 + 20).astype(np.uint8)).save(png)
    r = CliRunner().invoke(micro, ["analyze", str(png), "--pixel-nm", "10", "--json"])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "sem_analysis.png").exists()
    est = json.loads(r.output[: r.output.rindex("}") + 1])
    # the model that made the image: discs of 60 nm with a 30 nm gap, i.e. exclusion
    # radius 60 + 30/2 = 75 nm (RSA reaches contact); pixel 10 nm
    assert est["exclusion_radius_nm"] == pytest.approx(75.0, abs=10.0)
    assert est["area_fraction"] == pytest.approx(m.volume_fraction(), abs=0.01)
    bad = tmp_path / "bad.toml"
    bad.write_text('model = "hardcore_spheres"\nshape = [64, 64, 64]\nvoxel_nm = 1.0\nradius_nm = 4\nfraction = 0.5\n')
    r = CliRunner().invoke(micro, ["generate", str(bad)])
    assert r.exit_code != 0 and "0.38278" in str(r.exception)
