"""Benchmark: nmmm.microstructure generators against PoreSpy and a plain SciPy approach.

Run: python benchmarks/bench_microstructure.py

Comparable work (one run, same machine, medians of 3 calls on every side after a warm-up
call that compiles Numba; nmmm generates periodic cells, the rivals non-periodic ones):
- hard-core spheres (RSA) in 256³ at 10 %: nmmm.hardcore_spheres (periodic, exact
  fraction) vs porespy.generators.random_spheres (non-periodic, voxel-based RSA);
- Boolean (overlapping) spheres in 256³ at 30 %: nmmm.boolean_spheres (periodic, exact
  Poisson model) vs porespy.generators.overlapping_spheres (non-periodic, iterates on the
  porosity) and vs a straightforward SciPy approach (EDT of random seed voxels).
PoreSpy is optional (pip install porespy); without it only the SciPy baseline runs.
"""

from __future__ import annotations

import math
import time

import numpy as np
from scipy import ndimage

import nmmm.microstructure as M


def timed(fn, repeat=3):
    """Median seconds of ``repeat`` calls (same count for nmmm and its rivals) and the last output."""
    ts = []
    out = None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t)
    return float(np.median(ts)), out


def scipy_boolean(shape, r, fraction, seed):
    rng = np.random.default_rng(seed)
    theta = -math.log(1 - fraction) / (4 / 3 * math.pi * r**3)
    n = rng.poisson(theta * np.prod(shape))
    seeds = np.ones(shape, bool)
    idx = tuple(rng.integers(0, s, n) for s in shape)
    seeds[idx] = False
    return ndimage.distance_transform_edt(seeds) <= r


def main():
    shape, r = (256, 256, 256), 5
    M.hardcore_spheres((32, 32, 32), 1.0, 3, 0.1, seed=0)  # warm-up (Numba compile/cache)
    M.boolean_spheres((32, 32, 32), 1.0, 3, fraction=0.1, seed=0)
    t_hc, m = timed(lambda: M.hardcore_spheres(shape, 1.0, r, 0.10, seed=1))
    t_bo, mb = timed(lambda: M.boolean_spheres(shape, 1.0, r, fraction=0.30, seed=1))
    t_sp, bs = timed(lambda: scipy_boolean(shape, r, 0.30, 1))
    print(f"nmmm hardcore_spheres 256^3 r={r} 10 %: {t_hc:.3f} s (fraction {m.volume_fraction():.4f})")
    print(f"nmmm boolean_spheres  256^3 r={r} 30 %: {t_bo:.3f} s (fraction {mb.volume_fraction():.4f})")
    print(f"scipy EDT Boolean     256^3 r={r} 30 %: {t_sp:.3f} s (fraction {bs.mean():.4f})"
          f"  -> nmmm is {t_sp / t_bo:.1f}x faster")
    try:
        import porespy as ps
    except ImportError:
        print("porespy not installed: PoreSpy comparison skipped")
        return
    ps.settings.tqdm["disable"] = True
    ps.generators.random_spheres(shape=[32, 32, 32], r=3, phi=0.1, seed=0)  # warm-up
    t_ps, im = timed(lambda: ps.generators.random_spheres(shape=list(shape), r=r, phi=0.10, seed=1))
    print(f"porespy random_spheres 256^3 r={r} 10 %: {t_ps:.3f} s (fraction {im.mean():.4f})"
          f"  -> nmmm is {t_ps / t_hc:.1f}x faster")
    t_po, im = timed(lambda: ps.generators.overlapping_spheres(shape=list(shape), r=r, porosity=0.70, seed=1))
    print(f"porespy overlapping_spheres 256^3 r={r} 30 %: {t_po:.3f} s (fraction {1 - im.mean():.4f})"
          f"  -> nmmm is {t_po / t_bo:.1f}x faster")


if __name__ == "__main__":
    main()
