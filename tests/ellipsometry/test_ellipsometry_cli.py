"""The command line: simulate -> fit -> plots and Material files; examples (the demo hook: tests/demo)."""

import numpy as np
import pytest
from click.testing import CliRunner

from nmmm.ellipsometry.cli import ellipsometry

MODEL = """
name = "film on Si"
[substrate]
material = "main/Si/Green-2008"
[[layers]]
name = "film"
thickness_nm = {value = %s, min = 10, max = 2000}
model = "cauchy"
A = {value = %s, min = 1.3, max = 1.9}
B = {value = 0.006, min = -0.05, max = 0.1}
"""


def test_simulate_fit_pseudo(tmp_path):
    runner = CliRunner()
    truth = tmp_path / "truth.toml"
    truth.write_text(MODEL % (310.0, 1.56))
    start = tmp_path / "start.toml"
    start.write_text(MODEL % (290.0, 1.52))
    data = tmp_path / "data.csv"
    r = runner.invoke(ellipsometry, ["simulate", "--model", str(truth), "--wavelengths", "400:900:10",
                                     "--angles", "60,70", "--sigma-psi", "0.02", "--sigma-delta", "0.05",
                                     "--seed", "3", "-o", str(data)])
    assert r.exit_code == 0, r.output
    out = tmp_path / "out"
    r = runner.invoke(ellipsometry, ["fit", str(data), "--model", str(start), "-o", str(out),
                                     "--save-material", "film", "--point-by-point", "film"])
    assert r.exit_code == 0, r.output
    assert "film.thickness_nm" in r.output and "±" in r.output and "correlation matrix" in r.output
    assert (out / "data_fit.png").stat().st_size > 10_000
    from nmmm.materials import read_csv

    film = read_csv(out / "film_nk.csv")
    assert film.n(600.0) == pytest.approx(1.56 + 0.006 / 0.36, abs=2e-3)
    assert (out / "film_point_by_point.csv").exists()
    # a film's pseudo-dielectric function has <eps2> < 0 somewhere: no Material, a clear error
    r = runner.invoke(ellipsometry, ["pseudo", str(data), "--angle", "70", "-o", str(tmp_path / "pd.csv")])
    assert r.exit_code != 0 and "bulk absorber" in str(r.exception)


def test_pseudo_of_bulk_silicon(tmp_path, silicon):
    runner = CliRunner()
    bulk = tmp_path / "bulk.toml"
    bulk.write_text('[substrate]\nmaterial = "main/Si/Green-2008"\n')
    data = tmp_path / "si.csv"
    r = runner.invoke(ellipsometry, ["simulate", "--model", str(bulk), "--wavelengths", "300:900:20",
                                     "--angles", "70", "-o", str(data)])
    assert r.exit_code == 0, r.output
    r = runner.invoke(ellipsometry, ["pseudo", str(data), "-o", str(tmp_path / "pd.csv")])
    assert r.exit_code == 0, r.output
    from nmmm.materials import read_csv

    w = np.arange(300.0, 901.0, 20.0)
    np.testing.assert_allclose(read_csv(tmp_path / "pd.csv").nk(w), silicon.nk(w), rtol=1e-7)


def test_top_level_command_reports_bad_file(tmp_path, capsys):
    from nmmm.cli import main

    p = tmp_path / "bad.csv"
    p.write_text("wavelength_nm,angle_deg,psi_deg\n500,70,20\n")
    m = tmp_path / "m.toml"
    m.write_text(MODEL % (300.0, 1.5))
    code = main(["ellipsometry", "fit", str(p), "--model", str(m)])
    assert code == 2
    assert "missing column" in capsys.readouterr().err


def test_joint_fit_of_two_files(tmp_path):
    """'fit a.csv b.csv --model ... --model ... --shared A,B': joint fit, a plot per file; bad
    combinations of options are usage errors."""
    runner = CliRunner()
    files = []
    for t in (300.0, 900.0):
        truth = tmp_path / f"truth{t:.0f}.toml"
        truth.write_text(MODEL % (t, 1.56))
        files.append(tmp_path / f"film{t:.0f}.csv")
        r = runner.invoke(ellipsometry, ["simulate", "--model", str(truth), "--wavelengths", "400:900:20",
                                         "--angles", "70", "--sigma-psi", "0.02", "--sigma-delta", "0.05",
                                         "--seed", str(int(t)), "-o", str(files[-1])])
        assert r.exit_code == 0, r.output
    starts = []
    for t in (305.0, 895.0):
        starts.append(tmp_path / f"start{t:.0f}.toml")
        starts[-1].write_text(MODEL % (t, 1.54))
    out = tmp_path / "joint"
    args = ["fit", str(files[0]), str(files[1]), "--model", str(starts[0]), "--model", str(starts[1]),
            "--shared", "A,B", "-o", str(out), "--save-material", "film"]
    r = runner.invoke(ellipsometry, args)
    assert r.exit_code == 0, r.output
    assert "film.thickness_nm[1]" in r.output and "film.A " in r.output and "joint fit of 2" in r.output
    assert (out / "film300_fit.png").is_file() and (out / "film900_fit.png").is_file()
    assert (out / "film_nk.csv").is_file()
    r = runner.invoke(ellipsometry, ["fit", str(files[0]), str(files[1]), "--model", str(starts[0])])
    assert r.exit_code != 0 and "--shared" in r.output
    r = runner.invoke(ellipsometry, args[:3] + ["--model", str(starts[0])] * 3 + ["--shared", "A"])
    assert r.exit_code != 0 and "one per data file" in r.output
