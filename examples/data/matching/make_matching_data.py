"""Writes the synthetic measured files of examples/data/matching (run from the repository root).

- ``ladder.cgats`` — a hematite/rutile dilution ladder "measured" as CGATS.17: the tint recipe
  ``tint_base.toml`` with hematite's k x 1.25 (n corrected by Kramers-Kronig) and 15 % larger
  grains, plus noise 0.002 (seed 5); the ladder file ``ladder.toml`` calibrates it back.
- ``batch.cxf`` — one batch of the tint at hematite 0.021 (the recipe's own optics) as CxF3, a
  target for ``nmmm match``.
"""

from pathlib import Path

import numpy as np

from nmmm.matching.calibration import LadderSample, _Sample
from nmmm.matching.measured_files import MeasuredSpectra, write_cgats, write_cxf
from nmmm.matching.recipe_match import RecipeModel
from nmmm.recipes.schema import read_toml, set_key

HERE = Path(__file__).resolve().parent
LADDER = {"masstone": (0.05, 0.0), "1:1": (0.04, 0.04), "1:4": (0.02, 0.08), "1:9": (0.01, 0.09), "1:2": (0.03, 0.06)}


def main():
    raw, _, base = read_toml(HERE / "tint_base.toml")
    rng = np.random.default_rng(5)
    names, spectra = [], []
    for name, (h, r) in LADDER.items():
        rr = set_key(set_key(raw, "pigments.0.fraction", h), "pigments.1.fraction", r)
        s = _Sample(LadderSample(name, rr, np.zeros(16), base), "hematite")
        names.append(name)
        spectra.append(np.clip(s.reflectance(1.25, 1.15) + rng.normal(0, 0.002, 16), 0, 1))
    write_cgats(HERE / "ladder.cgats", MeasuredSpectra(s.w, np.stack(spectra), tuple(names), "de:8"), originator="synthetic (nmmm)")
    m = RecipeModel(HERE / "tint_base.toml", ["pigments.0.fraction=0.005:0.08"])
    write_cxf(HERE / "batch.cxf", MeasuredSpectra(m.wavelength_nm, m.reflectance([0.021])[None], ("batch 7",), "de:8"),
              creation_date="2026-12-02T00:00:00Z")  # fixed, so regenerating gives the same file


if __name__ == "__main__":
    main()
