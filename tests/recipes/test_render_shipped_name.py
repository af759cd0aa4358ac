"""`nmmm render plate --paint NAME` takes a shipped recipe's name, as `nmmm run` does; an unknown
name is one clear line naming the three kinds of value accepted."""

import subprocess
import sys

import numpy as np
from PIL import Image


def _nmmm(*args, cwd):
    return subprocess.run([sys.executable, "-m", "nmmm", *args], cwd=cwd, capture_output=True, text=True, timeout=600)


def test_render_plate_takes_a_shipped_recipe_name(tmp_path):
    p = _nmmm("render", "plate", str(tmp_path / "hem"), "--paint", "hematite_paint", "--width", "60", "--height", "40",
              cwd=tmp_path)
    assert p.returncode == 0, p.stdout + p.stderr
    rgb = np.asarray(Image.open(tmp_path / "hem.png").convert("RGB"), float)
    assert rgb.shape[:2] == (40, 60)
    centre = rgb[15:25, 25:35].mean(axis=(0, 1))
    assert centre[0] > centre[1] and centre[0] > centre[2]  # the hematite plate reads red


def test_unknown_paint_name_is_one_clear_line(tmp_path):
    p = _nmmm("render", "plate", str(tmp_path / "x"), "--paint", "no_such_paint", cwd=tmp_path)
    assert p.returncode == 2
    assert "Traceback" not in p.stderr
    assert "shipped recipe's name" in p.stderr and "no_such_paint" in p.stderr
