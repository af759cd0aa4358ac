"""The ``nmmm ema`` command group."""

import numpy as np
from click.testing import CliRunner

from nmmm.ema.cli import ema


def test_methods_and_mix_csv():
    r = CliRunner().invoke(ema, ["methods"])
    assert r.exit_code == 0 and "bruggeman" in r.output
    r = CliRunner().invoke(ema, ["mix", "--host", "main/SiO2/Malitson", "--inclusion", "main/Au/Johnson:0.0005",
                                 "--start-nm", "500", "--stop-nm", "560", "--step-nm", "10"])
    assert r.exit_code == 0, r.output
    rows = np.array([[float(x) for x in line.split(",")] for line in r.output.strip().splitlines()[1:]])
    assert 520 <= rows[np.argmax(rows[:, 2]), 0] <= 535  # the gold plasmon band in silica (issue 3)


def test_bad_inclusion_spec():
    r = CliRunner().invoke(ema, ["mix", "--host", "main/SiO2/Malitson", "--inclusion", "main/Au/Johnson"])
    assert r.exit_code != 0
    r = CliRunner().invoke(ema, ["mix", "--host", "main/SiO2/Malitson", "--inclusion", "main/Au/Johnson:0.1:blob"])
    assert r.exit_code != 0 and "shape" in str(r.exception)
