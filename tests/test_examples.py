"""The scripts in examples/ end in exit 0, or in one clear line naming what is missing (issue 14).

- every ``examples/*.py`` runs in a subprocess from a scratch folder: exit 0 and no traceback
  (the ones measured over 20 s on 2 cores are marked ``slow``: homogenize_flakes 38-42 s;
  render_plate 38 s and render_object 23 s on a first run, 9 s and 11 s once the JIT caches
  are warm);
- ``examples/render_object.py`` and ``nmmm render object`` with Mitsuba 3 missing, or with only
  an old libLLVM, are simulated the way :mod:`nmmm.appearance.render.mitsuba_paint` detects them
  (``mitsuba`` not importable; ``_llvm_versions`` finding libLLVM 15 only): one line with the
  install command, exit 1 for the example and 2 for the command, never a traceback;
- ``examples/data`` (the README's inputs): every file is small, ``make_example_data.py``
  rewrites them, and the fit and image analysis find the truth the files were made from.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
DATA = EXAMPLES / "data"

#: measured wall time over 20 s on 2 cores (render_polarized.py: 31 s and 27 s at load 5-7 on the shared
#: 2 cores; mitsuba_crosscheck.py, 13 s and 18 s, stays in the quick run)
SLOW = {"homogenize_flakes.py", "render_plate.py", "render_object.py", "render_polarized.py"}
SCRIPTS = sorted(p.name for p in EXAMPLES.glob("*.py"))


def _env() -> dict:
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")])
    env["MPLBACKEND"] = "Agg"
    return env


def _run(args, cwd, timeout=600):
    proc = subprocess.run(args, cwd=cwd, env=_env(), capture_output=True, text=True, timeout=timeout)
    return proc, proc.stdout + proc.stderr


def _mitsuba_works() -> bool:
    code = "from nmmm.appearance.render.mitsuba_paint import require_mitsuba; require_mitsuba()"
    return subprocess.run([sys.executable, "-c", code], capture_output=True, timeout=120).returncode == 0


def _one_install_line(out: str) -> str:
    lines = out.strip().splitlines()
    assert "Traceback" not in out, f"a traceback instead of one line:\n{out}"
    assert len(lines) == 1, f"want exactly one line, got {len(lines)}:\n{out}"
    assert "apt-get install libllvm19" in lines[0] or "pip install 'nmmm[mitsuba]'" in lines[0], lines[0]
    return lines[0]


@pytest.mark.parametrize("script", [pytest.param(s, marks=pytest.mark.slow) if s in SLOW else s for s in SCRIPTS])
def test_example_runs(script, tmp_path):
    proc, out = _run([sys.executable, str(EXAMPLES / script)], tmp_path)
    if script == "render_object.py" and not _mitsuba_works():
        assert proc.returncode == 1, out
        _one_install_line(out)
        return
    assert proc.returncode == 0, f"examples/{script} exited with {proc.returncode}:\n{out[-4000:]}"
    assert "Traceback" not in out, f"examples/{script} printed a traceback:\n{out[-4000:]}"


#: run TARGET ('cli' or a script) with Mitsuba made unavailable as MODE says
_SIMULATE = textwrap.dedent("""
    import runpy, sys
    mode, target = sys.argv[1], sys.argv[2]
    del sys.argv[1:3]
    if mode == "old-llvm":
        import nmmm.appearance.render.mitsuba_paint as mp
        mp._llvm_versions = lambda: [(15, "/usr/lib/x86_64-linux-gnu/libLLVM-15.so.1")]
    else:
        sys.modules["mitsuba"] = None   # import mitsuba raises ImportError
    if target == "cli":
        from nmmm.cli import run_main
        sys.argv[0] = "nmmm"
        run_main()
    else:
        sys.argv[0] = target
        runpy.run_path(target, run_name="__main__")
""")


@pytest.mark.parametrize("mode", ["mitsuba-missing", "old-llvm"])
def test_render_object_example_without_mitsuba_says_what_to_install(mode, tmp_path):
    if mode == "old-llvm":
        pytest.importorskip("mitsuba")  # the libLLVM check comes after a successful import
    proc, out = _run([sys.executable, "-c", _SIMULATE, mode, str(EXAMPLES / "render_object.py"), str(tmp_path)],
                     tmp_path)
    assert proc.returncode == 1, out
    line = _one_install_line(out)
    assert line.startswith("render_object: ")
    assert ("libLLVM >= 17" in line) if mode == "old-llvm" else ("not installed" in line)
    assert not list(tmp_path.glob("*.png"))


@pytest.mark.parametrize("mode", ["mitsuba-missing", "old-llvm"])
def test_render_object_command_without_mitsuba_exits_2_with_one_line(mode, tmp_path):
    if mode == "old-llvm":
        pytest.importorskip("mitsuba")
    proc, out = _run([sys.executable, "-c", _SIMULATE, mode, "cli", "render", "object", "out/sphere",
                      "--width", "16", "--height", "16", "--spp", "1"], tmp_path)
    assert proc.returncode == 2, out
    assert _one_install_line(out).startswith("error: nmmm render object: ")  # the one CLI voice (issue 21)


# --------------------------------------------------------------------------------------
# examples/data


def test_example_data_files_are_small():
    files = [p for p in DATA.rglob("*") if p.is_file() and "__pycache__" not in p.parts]
    assert files
    big = {str(p.relative_to(ROOT)): p.stat().st_size for p in files if p.stat().st_size > 200 * 1024}
    assert not big, f"example files over 200 kB: {big}"


def test_make_example_data_rewrites_the_files(tmp_path):
    proc, out = _run([sys.executable, str(DATA / "make_example_data.py"), str(tmp_path)], tmp_path)
    assert proc.returncode == 0 and "Traceback" not in out, out
    for name in ("epoxy_on_si.csv", "sem_hardcore.png", "pairs.toml", "responses.sqlite"):
        assert (tmp_path / name).is_file(), name
    # deterministic: the data files are the shipped ones
    assert (tmp_path / "epoxy_on_si.csv").read_text() == (DATA / "epoxy_on_si.csv").read_text()
    assert (tmp_path / "sem_hardcore.png").read_bytes() == (DATA / "sem_hardcore.png").read_bytes()
    assert (tmp_path / "pairs.toml").read_text() == (DATA / "pairs.toml").read_text()


def test_ellipsometry_example_fit_finds_the_film_the_data_were_made_from():
    import importlib.util

    from nmmm.ellipsometry.data import read_data
    from nmmm.ellipsometry.model import read_model

    spec = importlib.util.spec_from_file_location("make_example_data", DATA / "make_example_data.py")
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    res = read_model(DATA / "epoxy_on_si.toml").fit(read_data(DATA / "epoxy_on_si.csv"))
    assert 0.7 < res.mse < 1.3  # the noise is the stated sigma: reduced chi2 near 1
    for key in ("thickness_nm", "A", "B", "C"):
        name = f"epoxy.{key}"
        assert abs(res[name] - gen.TRUTH[key]) < 4 * res.stderr[name], (name, res[name], res.stderr[name])


def test_sem_example_analysis_finds_the_discs_it_was_made_from():
    from nmmm.microstructure.analysis import analyze_image, read_image

    s = analyze_image(read_image(DATA / "sem_hardcore.png"), 10.0).summary()
    # made from discs of radius 60 nm at area fraction 0.15 (blur and noise bias it slightly)
    assert abs(s["area_fraction"] - 0.15) < 0.015
    assert abs(s["hardcore_radius_nm"] - 60.0) < 3.0
    assert abs(s["mean_equivalent_diameter_nm"] - 120.0) < 6.0
    assert np.isfinite(s["exclusion_radius_nm"])
