"""``nmmm render plate --stokes / --polarizer DEG`` (issue 19 item 7): the Stokes EXR is written, and
a vertical polarizer dims the coat's reflection of the surroundings seen near Brewster's angle
while a horizontal one brightens it."""

from __future__ import annotations

import json

import numpy as np

from nmmm.cli import main

# a solid paint seen at 33.7 deg elevation: the plate centre at Brewster's angle of n = 1.5
ARGS = ["--paint", "solid", "--camera-mm", "0", "-333", "222", "--fov-deg", "30", "--width", "40", "--height", "30",
        "--irradiance", "0", "--environment", "D65", "--env-radiance", "1"]


def test_render_plate_stokes_and_polarizers(tmp_path, monkeypatch, capsys):
    import OpenEXR

    from nmmm.appearance.render.exr import read_spectral_exr

    monkeypatch.chdir(tmp_path)
    assert main(["render", "plate", "s", *ARGS, "--stokes"]) == 0, capsys.readouterr().err
    out = json.loads(capsys.readouterr().out)
    assert "s_stokes.exr" in " ".join(out["files"]) and 0 < out["polarization"]["mono"]["plate_mean_dolp"] < 1
    with OpenEXR.File(str(tmp_path / "s_stokes.exr"), separate_channels=True) as f:
        assert {n[:2] for n in f.channels() if n.endswith("nm")} == {"S0", "S1", "S2", "S3"}
    lum = {}
    for deg in (0, 90):
        assert main(["render", "plate", f"p{deg}", *ARGS, "--polarizer", str(deg)]) == 0, capsys.readouterr().err
        capsys.readouterr()
        _, v, _, _ = read_spectral_exr(tmp_path / f"p{deg}.exr")
        lum[deg] = v[10:20, 15:25].mean()
    _, s0, _, _ = read_spectral_exr(tmp_path / "s.exr")
    # I(0) + I(90) = S0; the coat's reflection is horizontally polarized -> I(90) < I(0)
    np.testing.assert_allclose(lum[0] + lum[90], s0[10:20, 15:25].mean(), rtol=1e-4)
    assert lum[90] < 0.8 * lum[0]
