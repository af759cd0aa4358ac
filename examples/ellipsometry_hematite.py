"""Bulk hematite crystal measured in two directions: ordinary, extraordinary and mean constants.

Hematite (α-Fe2O3) is uniaxial. A crystal cut with its c axis in the surface is measured with the
axis parallel, then perpendicular, to the plane of incidence (here synthetic data from Querry's
1985 constants, with noise). The exact inversion of both measurements together gives n + ik
ordinary and extraordinary at each wavelength; their mean ε = (2ε_o + ε_e)/3 is the isotropic
constant the pigment scale uses for randomly oriented grains.

Run: python examples/ellipsometry_hematite.py [output_dir]
"""

import sys

import numpy as np

from nmmm.demo.ellipsometry import hematite_two_orientations

out_dir = sys.argv[1] if len(sys.argv) > 1 else "ellipsometry_out"
res = hematite_two_orientations(out_dir)
r = res["result"]
mean = r.mean()
print(" wavelength   n_o+ik_o (±σn)            n_e+ik_e (±σn)            mean")
for i in range(0, r.wavelength_nm.size, 10):
    w = r.wavelength_nm[i]
    print(f" {w:6.0f} nm   {r.nk_ordinary[i]:.4f} (±{r.sigma_ordinary[i, 0]:.1e})   "
          f"{r.nk_extraordinary[i]:.4f} (±{r.sigma_extraordinary[i, 0]:.1e})   {complex(mean.nk(w)):.4f}")
print(f"\nlargest deviation from Querry: ordinary {res['max_dev_ordinary']:.1e}, "
      f"extraordinary {res['max_dev_extraordinary']:.1e}")
print(f"files: {', '.join(str(p) for p in res['files'].values())}\nfigure: {res['nk_png']}")
