"""Aluminium flakes in the seed's 450 µm × 450 µm × 20 µm metallic unit cell.

The deposit is kept as an analytic list (a few hundred flakes) and rasterised on demand
with anisotropic voxels. Run: python examples/microstructure_flakes.py [output_dir]
"""

import sys
from pathlib import Path

import nmmm.microstructure as M

out = Path(sys.argv[1] if len(sys.argv) > 1 else "microstructure_out")
out.mkdir(exist_ok=True)
deposit = M.flake_deposit(diameter_nm=("lognormal", 20_000.0, 6_000.0), thickness_nm=300.0, fraction=0.02,
                          tilt_std_deg=3.0, exclusion_nm=100.0, seed=1)
print(deposit.summary())
cell = deposit.rasterize(voxel_nm=(1000.0, 1000.0, 100.0))  # 450 x 450 x 200 voxels, 40 MB
M.save_microstructure(cell, out / "flakes_cell.npz")
window = deposit.window((0.0, 0.0), (50_000.0, 50_000.0)).rasterize(voxel_nm=(250.0, 250.0, 50.0))
print(cell, window, sep="\n")
