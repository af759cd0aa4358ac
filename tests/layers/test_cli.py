"""``nmmm layers`` commands: results against published/analytic values, errors on bad input."""

import csv
import io

import numpy as np
import pytest
from click.testing import CliRunner

from nmmm.errors import InvalidInputError
from nmmm.layers.cli import layers, parse_index


def _rows(output):
    text = "\n".join(line for line in output.splitlines() if not line.startswith("#"))
    return list(csv.DictReader(io.StringIO(text)))


def test_mie_reproduces_the_bhmie_listing():
    # Bohren & Huffman (1983), appendix A, p. 482: m = 1.55, r = 0.525 um, lambda = 0.6328 um
    r = CliRunner().invoke(layers, ["mie", "--particle", "1.55", "--diameter-nm", "1050",
                                    "--start-nm", "632.8", "--stop-nm", "640", "--step-nm", "10"])
    assert r.exit_code == 0, r.output
    row = _rows(r.output)[0]
    assert float(row["qext"]) == pytest.approx(3.10543, abs=1e-5)
    assert float(row["qback"]) == pytest.approx(2.92534, abs=1e-5)


def test_stack_quarter_wave_and_brewster():
    # Macleod (2010) §3.2: R = ((ns - n1^2)/(ns + n1^2))^2 for a quarter-wave layer at 550 nm;
    # tan(theta_B) = ns: Rp = 0 for the bare substrate
    n1, ns = 1.38, 1.52
    r = CliRunner().invoke(layers, ["stack", "--layer", f"{n1}:{550 / (4 * n1)!r}", "--substrate", str(ns),
                                    "--start-nm", "550", "--stop-nm", "560", "--step-nm", "10"])
    assert r.exit_code == 0, r.output
    assert float(_rows(r.output)[0]["R"]) == pytest.approx(((ns - n1**2) / (ns + n1**2)) ** 2, rel=1e-6)
    theta_b = float(np.degrees(np.arctan(ns)))
    r = CliRunner().invoke(layers, ["stack", "--substrate", str(ns), "--angle-deg", repr(theta_b),
                                    "--start-nm", "500", "--stop-nm", "510", "--step-nm", "10"])
    assert r.exit_code == 0, r.output
    assert float(_rows(r.output)[0]["Rp"]) < 1e-12


def test_film_without_absorption_on_white_reflects_everything(tmp_path):
    # a lossless film over a white Lambertian substrate returns all light (energy conservation)
    out = tmp_path / "film.csv"
    r = CliRunner().invoke(layers, ["film", "--pigment", "1.9", "--binder", "1.5", "--diameter-nm", "250",
                                    "--fraction", "0.1", "--thickness-um", "5", "--substrate-reflectance", "1",
                                    "--step-nm", "100", "-o", str(out)])
    assert r.exit_code == 0, r.output
    rows = _rows(out.read_text())
    assert len(rows) == 5
    for row in rows:
        assert float(row["R_km"]) == pytest.approx(1.0, abs=1e-9)
        assert float(row["R_ad"]) == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize(
    "args",
    [
        ["mie", "--particle", "1.5-0.1j", "--diameter-nm", "100"],  # k < 0
        ["mie", "--particle", "1.5", "--diameter-nm", "-100"],
        ["mie", "--particle", "1.5", "--medium", "1.33+0.01j", "--diameter-nm", "100"],  # absorbing host
        ["stack", "--layer", "1.5:0"],
        ["stack", "--layer", "glass:100"],
        ["film", "--pigment", "2.0", "--diameter-nm", "100", "--fraction", "1.5"],
    ],
)
def test_bad_input_is_an_nmmm_error(args):
    r = CliRunner().invoke(layers, args)
    assert r.exit_code != 0
    assert isinstance(r.exception, InvalidInputError)


def test_parse_index():
    assert parse_index("2.9+0.1i") == 2.9 + 0.1j
    assert parse_index("1.5") == 1.5
    with pytest.raises(InvalidInputError, match="neither a refractive index"):
        parse_index("glass")
