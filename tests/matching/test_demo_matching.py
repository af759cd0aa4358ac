"""The matching section of ``nmmm demo`` (issue 17 item 6, matching part)."""

import numpy as np

from nmmm.demo import sections
from nmmm.demo.matching import HIDDEN, demo


def test_matching_demo(tmp_path):
    assert ("Colour matching: a hidden mixture matched back to a recipe (nmmm.matching)", "nmmm.demo.matching:demo") in sections.HOOKS
    r = demo(tmp_path)
    assert (tmp_path / "matching.png").is_file() and (tmp_path / "matching.csv").is_file()
    rows = r["tables"]["Hidden and matched fractions"]
    assert [row["hidden fraction"] for row in rows] == list(HIDDEN.values())
    ratio = np.array([row["matched fraction"] for row in rows]) / rows[1]["matched fraction"]
    np.testing.assert_allclose(ratio, np.array(list(HIDDEN.values())) / HIDDEN["pigments.1.fraction"], rtol=0.05)
    de = float(r["text"][0].split("ΔE00 = ")[1].split()[0])
    assert de <= 0.5  # issue 17 acceptance with noise 0.002
