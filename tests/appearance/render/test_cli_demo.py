"""``nmmm render`` CLI, small sizes (the demo hook: tests/demo/test_rendering.py)."""

import json

import pytest
from click.testing import CliRunner

from nmmm.appearance.render.cli import render


def test_cli_plate_writes_exr_and_png(tmp_path):
    out = tmp_path / "p"
    res = CliRunner().invoke(render, ["plate", str(out), "--width", "40", "--height", "30", "--cells", "20", "15",
                                      "--paint", "white", "--light-zenith-deg", "0"])
    assert res.exit_code == 0, res.output
    info = json.loads(res.output)
    assert (tmp_path / "p.exr").exists() and (tmp_path / "p.png").exists()
    assert len(info["files"]) == 2


def test_cli_stereo_and_errors(tmp_path):
    res = CliRunner().invoke(render, ["plate", str(tmp_path / "s"), "--stereo", "--width", "32", "--height", "20",
                                      "--cells", "20", "15", "--camera-mm", "0", "-40", "300", "--fov-deg", "3"])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "s_left.exr").exists() and (tmp_path / "s_right.png").exists()
    bad = CliRunner().invoke(render, ["plate", str(tmp_path / "x"), "--light", str(tmp_path / "none.csv")])
    assert bad.exit_code != 0 and "not found" in bad.output
    away = CliRunner().invoke(render, ["plate", str(tmp_path / "y"), "--look-at-mm", "0", "0", "900",
                                       "--width", "8", "--height", "8"])
    assert away.exit_code != 0 and "looks away" in away.output


@pytest.mark.slow
def test_cli_object_with_mitsuba(tmp_path):
    try:
        from nmmm.appearance.render.mitsuba_paint import require_mitsuba

        require_mitsuba()
    except Exception as exc:  # noqa: BLE001
        pytest.skip(f"Mitsuba unavailable: {exc}")
    res = CliRunner().invoke(render, ["object", str(tmp_path / "o"), "--width", "24", "--height", "24", "--spp", "4",
                                      "--shape", "sphere"])
    assert res.exit_code == 0, res.output
    from nmmm.appearance.render import read_spectral_exr

    w, v, rgb, hdr = read_spectral_exr(tmp_path / "o.exr")
    assert w.size == 81 and v.shape == (24, 24, 81) and hdr["spectralLayoutVersion"] == "1.0"
