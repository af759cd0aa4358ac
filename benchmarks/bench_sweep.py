"""Sweep overhead per point against the physics time of the point, in one run.

For the shipped hematite paint recipe (Mie over a log-normal size distribution + Kubelka–Munk
+ colorimetry) on a grid of pigment fractions × grain sizes:

- serial (in this process): wall time per point vs the physics time measured inside the
  point (recipe validation, compute) — the overhead is Parquet writing and bookkeeping;
- Dask LocalCluster (2 worker processes, warmed up first so that imports and Numba caches
  are not counted): wall time × workers per point vs physics per point — the overhead is
  scheduling, serialisation, result transfer and the client's Parquet writes;
- the bare Dask round trip of a no-op task, for scale.

Usage: ``python benchmarks/bench_sweep.py [--points N] [--step-nm S]``
"""

from __future__ import annotations

import argparse
import tempfile
import time
import tomllib
import warnings
from pathlib import Path


def _raw(step_nm):
    from nmmm.recipes.schema import example_path

    raw = tomllib.loads(example_path("hematite_paint").read_text())
    raw["spectral"]["step_nm"] = step_nm
    return raw


def _noop(x):
    return x


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, default=24, help="grid points (fractions x 4 sizes)")
    ap.add_argument("--step-nm", type=float, default=10.0)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    warnings.simplefilter("ignore")

    from dask.distributed import Client, LocalCluster

    from nmmm.recipes.sweep import sweep

    n_frac = max(1, args.points // 4)
    vary = [f"pigment.fraction=0.02:0.12:{n_frac}", "pigment.body_diagonal_nm=150,250,400,600"]
    raw = _raw(args.step_nm)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        sweep(raw, ["pigment.fraction=0.05"], tmp / "warm", serial=True, progress=False, plots=False)
        s = sweep(raw, vary, tmp / "serial", serial=True, progress=False, plots=False)
        n = s["n_points"]
        ser_wall, ser_phys = s["wall_s"] / n, s["physics_s"] / n
        print(f"grid: {n} points, {len(s['results']['wavelength_nm'][0])} wavelengths each")
        print(f"serial     : {ser_wall * 1e3:8.1f} ms wall/point, {ser_phys * 1e3:8.1f} ms physics/point, "
              f"overhead {(ser_wall - ser_phys) * 1e3:6.1f} ms/point = {(ser_wall - ser_phys) / ser_phys:.1%} of the physics")

        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
        try:
            sweep(raw, ["pigment.fraction=0.01,0.015,0.025,0.035"], tmp / "warm2", client=client, progress=False, plots=False)
            t0 = time.perf_counter()
            client.gather(client.map(_noop, range(200), pure=False))
            noop = (time.perf_counter() - t0) / 200
            d = sweep(raw, vary, tmp / "dask", client=client, progress=False, plots=False)
            wall_pp = d["wall_s"] * args.workers / n
            phys_pp = d["physics_s"] / n
            print(f"dask x{args.workers}    : {d['wall_s'] / n * 1e3:8.1f} ms wall/point ({wall_pp * 1e3:.1f} ms worker-time/point), "
                  f"{phys_pp * 1e3:8.1f} ms physics/point, overhead {(wall_pp - phys_pp) * 1e3:6.1f} ms/point "
                  f"= {(wall_pp - phys_pp) / phys_pp:.1%} of the physics")
            print(f"dask no-op : {noop * 1e3:8.2f} ms per task round trip (200 tasks)")
            print(f"speed-up of the sweep with {args.workers} workers vs serial: {s['wall_s'] / d['wall_s']:.2f}x "
                  "(bounded by the cores actually free on this machine)")
        finally:
            client.close()
            cluster.close()


if __name__ == "__main__":
    main()
