"""``nmmm materials search/show/plot`` (the materials demo hook: tests/demo/test_materials.py)."""

import numpy as np
from click.testing import CliRunner

from nmmm.materials.cli import materials


def _malitson(w_nm):
    """Fused silica, Malitson, JOSA 55, 1205 (1965), eq. (1) with his published coefficients."""
    l2 = (np.asarray(w_nm) / 1000.0) ** 2
    B, C = (0.6961663, 0.4079426, 0.8974794), (0.0684043, 0.1162414, 9.896161)
    return np.sqrt(1 + sum(b * l2 / (l2 - c * c) for b, c in zip(B, C)))


def test_search_and_unknown():
    r = CliRunner().invoke(materials, ["search", "Fe2O3"])
    assert r.exit_code == 0 and [ln.split("\t")[0] for ln in r.output.splitlines()] == [
        "main/Fe2O3/Querry-e", "main/Fe2O3/Querry-o"]  # then range, coverage, title, source (test_search_binders)
    r = CliRunner().invoke(materials, ["search", "no-such-compound"])
    assert r.exit_code != 0


def test_show_prints_malitson_values():
    r = CliRunner().invoke(materials, ["show", "main/SiO2/Malitson", "--points", "5"])
    assert r.exit_code == 0, r.output
    assert "range: 210–6700 nm" in r.output and "Malitson" in r.output
    rows = np.array([[float(x) for x in line.split()] for line in r.output.splitlines()[4:]])
    assert rows.shape == (5, 3)
    np.testing.assert_allclose(rows[:, 1], _malitson(rows[:, 0]), atol=2e-5)  # printed to 5 decimals
    assert np.all(rows[:, 2] == 0)


def test_show_unknown_key_names_close_matches():
    r = CliRunner().invoke(materials, ["show", "main/Au/Jonson"])
    assert r.exit_code != 0 and "main/Au/Johnson" in str(r.exception)


def test_plot_writes_png(tmp_path):
    out = tmp_path / "au.png"
    r = CliRunner().invoke(materials, ["plot", "main/Au/Johnson", "main/SiO2/Malitson", "-o", str(out),
                                       "--range-nm", "400", "800"])
    assert r.exit_code == 0, r.output
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 10_000
