"""Issue 21: outputs complete or absent, folders locked, sweeps verified, recipe files confined,
recipe errors one line with exit 2 (never a traceback)."""

import errno
import os
import warnings
from pathlib import Path

import pytest
from click.testing import CliRunner

from nmmm import atomic_io
from nmmm.cli import main
from nmmm.errors import DataFileError, InvalidInputError, RecipeError
from nmmm.recipes import cli
from nmmm.recipes.run import run_recipe
from nmmm.recipes.schema import example_path, files_outside_allowed, load_recipe
from nmmm.recipes.sweep import MANIFEST, load_results, sweep, verified_points


@pytest.fixture
def recipe(tmp_path):
    p = tmp_path / "paint.toml"
    p.write_text(example_path("interference_pigment").read_text().replace("step_nm = 5", "step_nm = 40"))
    return p


def _main(args, capsys):
    rc = main(args)
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


# -- integrity: two runs into one folder, a full disk --------------------------------------

def test_second_run_into_a_folder_in_use_is_refused_before_any_physics(recipe, tmp_path, capsys):
    out = tmp_path / "out"
    with atomic_io.folder_lock(out):  # another run holds the folder
        with pytest.raises(InvalidInputError, match="in use by another nmmm run"):
            run_recipe(str(recipe), out, progress=False)
        rc, _, err = _main(["run", str(recipe), "-o", str(out), "--no-progress"], capsys)
    assert rc == 2 and err.startswith("error: output folder") and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    assert not out.exists()  # nothing half-written
    run_recipe(str(recipe), out, progress=False)  # free again once the other run is done
    assert (out / "report.html").exists() and (out / atomic_io.MANIFEST_NAME).exists()


def test_a_full_disk_leaves_no_truncated_report_and_keeps_the_previous_run(recipe, tmp_path, monkeypatch, capsys):
    out = tmp_path / "out"
    run_recipe(str(recipe), out, progress=False)
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    import nmmm.recipes.report as report

    real = report.write_report

    def full_disk(sections, path, **kw):
        Path(path).write_text("<html><body>trunc")  # a partial write, then the disk is full
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(report, "write_report", full_disk)
    with pytest.raises(DataFileError, match="No space left on device"):
        run_recipe(str(recipe), out, progress=False)
    after = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    assert after == before  # the complete previous run, untouched
    assert not [p for p in tmp_path.iterdir() if ".incomplete-" in p.name]  # no temporary folder left
    rc, _, err = _main(["run", str(recipe), "-o", str(tmp_path / "new"), "--no-progress"], capsys)
    assert rc == 2 and "No space left on device" in err and "Traceback" not in err
    assert not (tmp_path / "new").exists()
    monkeypatch.setattr(report, "write_report", real)


def test_a_rerun_replaces_the_outputs_of_a_different_recipe(recipe, tmp_path):
    out = tmp_path / "out"
    run_recipe(str(recipe), out, progress=False)
    stale = out / "image_old.png"  # listed as an output of the previous run
    stale.write_bytes(b"x")
    import json

    man = json.loads((out / atomic_io.MANIFEST_NAME).read_text())
    (out / atomic_io.MANIFEST_NAME).write_text(json.dumps({"files": man["files"] + ["image_old.png"]}))
    (out / "mine.txt").write_text("a user's own file")  # never listed: kept
    run_recipe(str(recipe), out, progress=False)
    assert not stale.exists() and (out / "mine.txt").exists()


def test_atomic_write_keeps_the_old_file_when_the_write_fails(tmp_path):
    p = tmp_path / "a.txt"
    atomic_io.atomic_write_text(p, "old")
    with pytest.raises(RuntimeError):
        with atomic_io.atomic_path(p) as tmp:
            tmp.write_text("new but half")
            raise RuntimeError("killed")
    assert p.read_text() == "old" and sorted(x.name for x in tmp_path.iterdir()) == ["a.txt"]


# -- verified sweeps ----------------------------------------------------------------------

VARY = ["thin_film.layers[1].thickness_nm=100,140,180"]


def test_sweep_resume_recomputes_truncated_flipped_and_empty_points_with_a_warning(recipe, tmp_path):
    out = tmp_path / "sw"
    first = sweep(str(recipe), VARY, out, serial=True, progress=False, plots=False)
    files = sorted((out / "points").glob("*.parquet"))
    assert len(files) == 3 and len((out / MANIFEST).read_text().splitlines()) == 3
    data = files[0].read_bytes()
    files[0].write_bytes(data[: len(data) // 2])  # truncated
    flipped = bytearray(files[1].read_bytes())
    flipped[len(flipped) // 2] ^= 0x01  # one bit flipped
    files[1].write_bytes(bytes(flipped))
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        assert len(load_results(out)) == 1  # the damaged points are left out, named
    assert any(files[0].name in str(w.message) for w in rec)
    with pytest.warns(UserWarning, match="recomputed") as rec:
        again = sweep(str(recipe), VARY, out, serial=True, progress=False, plots=False)
    msg = " ".join(str(w.message) for w in rec)
    assert files[0].name in msg and files[1].name in msg
    assert again["n_computed"] == 2 and again["n_skipped"] == 1 and len(again["warnings"]) == 1
    cols = ["L_D65", "a_D65", "b_D65"]
    assert again["results"][cols].to_numpy().tolist() == first["results"][cols].to_numpy().tolist()
    files[2].write_bytes(b"")  # empty
    third = sweep(str(recipe), VARY, out, serial=True, progress=False, plots=False)
    assert third["n_computed"] == 1 and verified_points(out)[1] == []


def test_sweep_refuses_zero_workers_and_huge_grids_with_the_estimate(recipe, tmp_path, capsys):
    with pytest.raises(InvalidInputError, match="at least 1 worker"):
        sweep(str(recipe), VARY, tmp_path / "a", n_workers=0, progress=False)
    with pytest.raises(InvalidInputError, match=r"20,000 points.*--max-points 20000"):
        sweep(str(recipe), ["thin_film.layers[1].thickness_nm=50:300:200", "thin_film.layers[0].thickness_nm=100:200:100"],
              tmp_path / "b", serial=True, progress=False)
    with pytest.raises(RecipeError, match="more than 1,000,000"):
        sweep(str(recipe), ["thin_film.layers[1].thickness_nm=0.01:0.2:10000000"], tmp_path / "c", progress=False)
    rc, _, err = _main(["sweep", str(recipe), "--vary", VARY[0], "-n", "0", "-o", str(tmp_path / "d")], capsys)
    assert rc == 2 and err.startswith("error: ") and "--workers" in err and len(err.strip().splitlines()) == 1
    rc, _, err = _main(["sweep", str(recipe), "--vary", "thin_film.layers[1].thickness_nm=0.01:0.2:10000000",
                        "-o", str(tmp_path / "e")], capsys)
    assert rc == 2 and "1,000,000" in err and "Traceback" not in err


def test_sweep_max_points_raises_the_limit(recipe, tmp_path):
    s = sweep(str(recipe), VARY, tmp_path / "sw", serial=True, progress=False, plots=False, max_points=3)
    assert s["n_points"] == 3
    with pytest.raises(InvalidInputError, match="more than the limit of 2 points"):
        sweep(str(recipe), VARY, tmp_path / "sw2", serial=True, progress=False, plots=False, max_points=2)


# -- confinement ----------------------------------------------------------------------------

def _file_recipe(folder: Path, file: str) -> Path:
    text = example_path("gold_ruby_glass").read_text()
    p = folder / "r.toml"
    import tomllib

    raw = tomllib.loads(text)
    name = next(iter(raw["compounds"]))
    spec = raw["compounds"][name]
    for k in ("database", "uniaxial", "model", "params", "n", "k"):
        spec.pop(k, None)
    spec["file"] = file
    from nmmm.recipes.run import _dump_toml

    p.write_text(_dump_toml(raw))
    return p


@pytest.mark.parametrize("file", ["../../../../etc/passwd", "/etc/passwd", "/proc/self/environ"])
def test_recipe_files_outside_the_recipe_folder_are_refused_without_echoing_them(tmp_path, file, capsys):
    d = tmp_path / "recipes"
    d.mkdir()
    p = _file_recipe(d, file)
    with pytest.raises(RecipeError, match="outside the recipe's folder"):
        load_recipe(str(p))
    rc, out, err = _main(["run", str(p), "-o", str(tmp_path / "o"), "--no-progress"], capsys)
    assert rc == 2 and "outside the recipe's folder" in err and "--allow-outside-files" in err
    assert "root:" not in err + out and "PATH=" not in err + out


def test_a_symlink_out_of_the_folder_is_refused_and_allowed_files_never_echo_contents(tmp_path, capsys):
    d = tmp_path / "recipes"
    d.mkdir()
    secret = tmp_path / "secret.csv"
    secret.write_text("root:x:0:0:root:/root:/bin/bash\nHOME=/root,PATH=/usr/bin,SECRET=1\n")
    (d / "link.csv").symlink_to(secret)
    p = _file_recipe(d, "link.csv")
    with pytest.raises(RecipeError, match="outside"):
        load_recipe(str(p))
    with files_outside_allowed():
        load_recipe(str(p))  # the explicit option lets it be read ...
    rc, out, err = _main(["run", str(p), "-o", str(tmp_path / "o"), "--allow-outside-files", "--no-progress"], capsys)
    assert rc == 2 and ("secret.csv" in err or "link.csv" in err), err
    assert "root:" not in err and "SECRET" not in err and "PATH=" not in err  # ... but never echoed


def test_base_dir_cannot_be_set_by_a_recipe():
    text = example_path("gold_ruby_glass").read_text()
    with pytest.raises(RecipeError, match="base_dir: not a recipe key"):
        load_recipe('base_dir = "/"\n' + text)


# -- malformed recipe files: one line, exit 2 ----------------------------------------------------

def test_malformed_recipe_files_are_one_line_errors(tmp_path, capsys):
    deep = tmp_path / "deep.toml"
    deep.write_text("a = " + "[" * 5000 + "]" * 5000 + "\n")
    latin = tmp_path / "latin.toml"
    latin.write_bytes('name = "peinture ocre \xe9"\n'.encode("latin-1"))
    nested = tmp_path / "nested.toml"
    nested.write_text("[" + ".".join(["t"] * 100) + "]\nx = 1\n")
    folder = tmp_path / "folder.toml"
    folder.mkdir()
    for p, what in [(deep, "nested"), (latin, "not UTF-8"), (nested, "nested more than"), (folder, "folder")]:
        rc, out, err = _main(["run", str(p), "-o", str(tmp_path / "o"), "--no-progress"], capsys)
        assert rc == 2, (p, err)
        assert err.startswith("error: ") and what in err and len(err.strip().splitlines()) == 1, err
        assert "Traceback" not in err + out
    r = CliRunner().invoke(cli.run, [str(latin), "-o", str(tmp_path / "o2"), "--no-progress"])
    assert r.exit_code == 2 and "not UTF-8" in r.output  # recipe errors exit 2 also without nmmm.cli.main


def test_recipe_errors_exit_2_with_the_key(recipe, tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(recipe.read_text().replace("thickness_nm = 120", "thickness_nm = -120", 1))
    rc, _, err = _main(["run", str(bad), "-o", str(tmp_path / "o"), "--no-progress"], capsys)
    assert rc == 2 and err.startswith("error: thin_film.layers[1].thickness_nm") and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()
    assert not [n for n in os.listdir(tmp_path) if n.startswith(".o.")]  # no temporary folder left
