"""Hematite pseudo-cubes (250 nm large diagonal) at 5-10 % in epoxy: generate, section, analyse.

Run: python examples/microstructure_hematite.py [output_dir]
"""

import sys
from pathlib import Path

import numpy as np
from scipy import ndimage

import nmmm.microstructure as M

out = Path(sys.argv[1] if len(sys.argv) > 1 else "microstructure_out")
out.mkdir(exist_ok=True)
for p in (0.05, 0.07, 0.10):
    cell = M.hardcore_pseudocubes((200, 200, 100), 10.0, diagonal_nm=250.0, fraction=p, exclusion_nm=20.0, seed=1)
    M.save_microstructure(cell, out / f"hematite_{int(100 * p)}pc.tif")
    section = cell.section(axis=2)
    sem = ndimage.gaussian_filter(section.labels.astype(float), 1.0)
    sem += np.random.default_rng(0).normal(0, 0.1, sem.shape)
    res = M.analyze_image(sem, section.voxel_nm, smooth_px=0.0)
    res.plot(out / f"hematite_{int(100 * p)}pc_analysis.png", title=f"hematite {p:.0%}")
    print(p, cell.volume_fraction(), res.summary()["exclusion_radius_nm"])
