"""Benchmark of nmmm.homogenize (FFT homogenization), all numbers measured in one run.

What it reports
---------------
1. Cost of one COCG iteration against the bare FFT pair a user would write: a vector field
   (d components) forward and back with scipy.fft (2 workers, in place). nmmm's iteration does
   one forward and one inverse FFT of a scalar field (the Willot operators' potential form, with
   the divergence and gradient stencils in real space). Target: ratio <= 1.3.
   Here x is not formed (``keep_x=False``, as ``fft_permittivity`` solves one loading: no x
   pass); ``run_all.py``'s FFT row forms it (one more pass: read x and p, write x).
2. Projections (iterations) against contrast for COCG (default), BiCGStab, GMRES,
   Eyre-Milton and the basic Moulinec-Suquet scheme, with the three Green operators, on a
   2-D Boolean model (metal ε = −50 + {20, 5, 1}i in ε = 2.25) and a 3-D one (64³, −50 + 2i).
3. Total wall time and peak memory (RSS) for a hematite-like microstructure (dielectric
   inclusions at 10 %) and a flake-like one (metal platelets) at 128³ and, with --big, 256³,
   in complex64.

Usage::

    python benchmarks/bench_homogenize.py            # 128³ and the iteration table
    python benchmarks/bench_homogenize.py --big      # also 256³ (several GB, minutes)
    python benchmarks/bench_homogenize.py --quick    # 64³ only

The machine's cores are shared: ratios measured in the same run are meaningful, absolute
times less so.

Session 6, 2026-12-05: the element-wise passes vectorise (issue 22; 128³ complex64, willot2015, x formed)
-------------------------------------------------------------------------------------
Per pass, medians of 7-9 timed in alternation in one process (ms; "pair" = one bare FFT pair):
- before, 1 thread (load 0.4-0.9): direction + ε 23.9-24.2, 3 forward FFTs 49.8-50.8, potential
  7.0-7.8, inverse FFT 14.0-16.3, stencil update (x and r) 23.3-23.7; iteration 117-121, pair
  96-102: 1.17-1.26. 2 threads (load 0.4-1.2): 12.8-14.0, 25.3-26.6, 4.1, 7.8-7.9, 12.1-12.5;
  iteration 64, pair 49-52: 1.25-1.31. Every pass ran on both threads (speed-ups 1.7-2.1); no
  pass was serial. The excess was the element-wise passes (55 of 121 ms at 1 thread), whose
  complex64 loops Numba left scalar (and the ε gather in the direction loop).
- after (kernels on real views, kernels.py), 1 thread (load 0.9-1.7): direction 12.9-13.1,
  potential 7.3, update 14.9-15.2 (x pass 6-7 of it); iteration 100-119, pair 98-102: 1.02-1.16.
  2 threads (load 1.1-1.7): 7.7-9.2, 4.5-4.7, 7.8-8.0; 4 FFTs 31-32; iteration 53, pair 48:
  1.10-1.11.
- run_all's measure (pair = 8 pairs in a row, old and new kernels interleaved in one process):
  1 thread old 1.19-1.58, new 0.97-1.17; 2 threads old 1.05-1.66, new 0.92-1.32 (load 1.6-3.7
  all session: one or two other jobs on the 2 cores; the 2-thread rows with a pair slower than
  at 1 thread had no second core). ``run_all.py --only fft`` twice at load 1.5-3.9: 1 thread
  1.22, 1.37; 2 threads 1.16, 1.14 — at this load the row moves by ±0.15 between runs. The
  target <= 1.3 at 2 threads is met on a machine with a free second core (1.10-1.11 per pass,
  1.13-1.32 in run_all's measure at load 1.7-2.3, and 1.30, 1.31 at load 0.9-1.5 with the pair at
  41 ms, old kernels 1.55, 1.56 there; 1 thread 1.18, 1.21, old 1.53, 1.62): not reliably. The pair in a loop is faster (42-43 ms at 2 threads) than one
  pair among the iteration's passes (47-48): its single 48 MiB field stays in cache, the
  iteration streams over x, r, p, q and ψ (~210 MiB).
- Floor of the element-wise passes: Numba streaming loops with the same traffic (real views,
  same chunks and threads; load 1.5): direction's (read 2, write 2 fields) 10.9 / 5.4 ms at 1 / 2
  threads, x update's (read 2, write 1) 4.8 / 2.5, one field read and written 2.9 / 1.4 (NumPy
  copyto 5.9 / 5.3: one thread). Memory bandwidth still doubles at 2 threads, so it is no floor
  here; the passes are at 1.2-1.7x their traffic floor (direction) and the whole element-wise
  work at ~1.5x (about 22 ms at 2 threads against ~12): with the FFTs at 31-32 ms and the pair
  at 42-48 the floor ratio is ~0.95-1.05.

Session 5, 2026-12-04: why 2 threads did not scale (issue 22; 128³ complex64, willot2015)
-------------------------------------------------------------------------------------
Measured with per-thread CPU times (/proc/self/task) because the shared machine stayed at load
5-8 all session, where wall-clock ratios at 2 threads moved by ±30 % between identical runs.
- The element-wise passes ran on ONE thread at "2 threads": the parallel=True and serial Numba
  builds of each kernel shared one on-disk cache entry (Numba keys it by function and
  signature, not options), so after a small serial call had filled the cache the "parallel"
  kernels were serial builds. Per iteration at 2 threads: main thread 54-60 ms CPU (direction
  + ε 25, potential 8, stencil update 25: all serial), the FFT threads 32-39 each.
- With the parallel builds restored, Numba's OpenMP workers spin after each kernel on the
  cores that the next scipy.fft call needs: 233 ms CPU per iteration at 2 threads against
  153 ms at 1 (load 7-8).
- Now (kernels.py): serial GIL-free builds over ranges of planes/chunks on a small Python
  thread pool: 130-132 ms CPU per iteration at 2 threads vs 125-130 at 1, spread over 4 threads
  at 29-40 ms each (main + pool thread for the kernels, 2 FFT threads); the kernels' own cost
  unchanged (update 24 ms, direction 23, potential 6.4 at 1 thread).
- ``run_all.py --only fft``, iteration / bare pair, alternating old and new code, load 4.4-7.6:
  before (c74fd96) 1 thread 1.19, 1.21; 2 threads 1.24, 1.29 — in both runs the bare pair was
  no faster at 2 threads than at 1 (101/101, 204/204 ms): the load left about one core, so
  these rows cannot show 2-thread scaling; after: 1 thread 1.22, 1.51; 2 threads 1.18, 1.28.
  On a quiet machine the CPU split above predicts about (55/2 + 70/2) / (100/2) ≈ 1.25 at 2
  threads (kernels and 3+1 FFTs halved, the bare pair halved): not measured here.

Session 4, 2026-12-02 (after the rank-one form of Γ: 3 forward FFTs + 1 inverse per iteration)
-------------------------------------------------------------------------------------
- Iteration / bare FFT pair (6 FFTs), 128³ complex64, Boolean spheres, willot2015:
  run_all.py at load 11: 1.23 (1 thread), 1.39 (2 threads); at load 6.6: 1.34 / 1.25 (around the 1.3
  target, not robustly below it); CPU time at 1 thread, load 5-11,
  medians of 5: 1.23-1.33 (warm-start path, x formed) — was 1.72 (1.89 in run_all). In-loop
  parts at 1 thread (ms): direction + ε 17-19, 3 FFTs 51-53, potential 12, 1 inverse FFT 18,
  stencil update 21 (bare pair 101-106).
- Peak memory (``--memory``, VmHWM of a fresh process, flake solve, complex64, one loading):
  128³ 384 MiB, 256³ 1484 MiB (x not formed for a single wavelength; 1868 MiB with it; the
  harness peaked at 4.1 GB before, with a separate FFT array and the kept fields).

Re-measured 2026-12-02 (benchmarks/run_all.py, medians of 5 alternating runs, load 4-5)
-------------------------------------------------------------------------------------
- Iteration / bare FFT pair, 128³ complex64, Boolean spheres: 1.89 at 1 thread, 1.56 at 2
  threads (issue 22 measured 1.46 at 64³, 1.69 at 128³, 1.31 at 256³). The 1.20 at 128³
  in the 2026-11-22 list below (best-of rounds) is not reproduced; the target 1.3 is not met.

Measured on the shared 2-core development machine (load average 5-9, 2026-11-22)
-------------------------------------------------------------------------------------
- Iteration / bare FFT (best of rounds): 512² 1.88 (c64), 1.63 (c128); 64³ 1.56 / 1.19;
  128³ 1.20 / 1.30; in the 128³ totals 1.45 (hematite) and 1.35 (flakes). The element-wise work is 3 fused
  passes (ε p with the direction update, the projection, the COCG update).
- Projections to 1e-6, 2-D Boolean discs 128², p = 0.3 (COCG / BiCGStab / GMRES(30) /
  Eyre-Milton / Moulinec-Suquet):
  ε = −50+20i: spectral 156/304/155/195/>3000, Willot 2014 36/52/39/195/>3000,
  Willot 2015 44/67/56/196/>3000; ε = −50+5i: spectral 554/1334/555/701/>3000,
  W2014 39/61/43/707/>3000, W2015 52/90/74/705/>3000; ε = −50+1i: COCG spectral 2012,
  W2014 40, W2015 55; Eyre-Milton (W2015) 3355 (predicted rate |1−√r|/|1+√r| = 0.994).
- 3-D Boolean spheres 64³ (p = 0.2), ε = −50+2i: COCG 144 projections (rotated operator);
  NOT reproduced since (issue 22: complex64 stalls at 2.9e-4 after 1000; the defaults now
  take willot2014 in complex128 there, 298 projections, benchmarks/bench_fft_metals.py).
- Totals, complex64, 3 loadings, tol 1e-5: 128³ hematite-like (10 %, ε = 8+3i in 2.4)
  22 s, 11 projections per loading; 128³ Al flakes (10 %, ε = −50+20i) 262 s, 163/163/114
  projections; peak RSS 481 MiB. 256³, one loading each: hematite 60 s (11 projections,
  incl. set-up), Al flakes 600 s (165 projections, 3.64 s each against 2.45 s for the bare
  FFT pair: ratio 1.49); peak RSS 1.76 GiB (4 complex64 vector fields of 384 MiB + the
  warm-start copy); three loadings take about 3x the time and +0.8 GiB for their seeds.
"""

from __future__ import annotations

import argparse
import resource
import sys
import time
import warnings

import numpy as np
import scipy.fft

from nmmm.homogenize import fft_permittivity
from nmmm.homogenize import geometries as G
from nmmm.homogenize.green import green_operator
from nmmm.homogenize.solvers import Problem, solve_cocg

WORKERS = 2


def peak_rss_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def bare_fft_time(shape, d, dtype, repeat=3) -> float:
    """Seconds for forward + inverse FFT of a d-component field, in place, best of ``repeat``."""
    a = np.ones((d,) + shape, dtype=dtype)
    axes = tuple(range(1, d + 1))
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        b = scipy.fft.fftn(a, axes=axes, workers=WORKERS, overwrite_x=True)
        a = scipy.fft.ifftn(b, axes=axes, workers=WORKERS, overwrite_x=True)
        best = min(best, time.perf_counter() - t)
    return best


def flakes(n: int, seed: int = 0) -> np.ndarray:
    """Metal platelets (discs of radius n/6, thickness 2 voxels) lying roughly flat, ~10 %."""
    rng = np.random.default_rng(seed)
    lab = np.zeros((n, n, n), np.uint8)
    x = np.arange(n)
    r = n / 6
    while lab.mean() < 0.10:
        c = rng.uniform(0, n, 3)
        dx = (x - c[0] + n / 2) % n - n / 2
        dy = (x - c[1] + n / 2) % n - n / 2
        disc = (dx[:, None] ** 2 + dy[None, :] ** 2) < r * r
        z0 = int(c[2])
        for dz in range(2):
            lab[:, :, (z0 + dz) % n] |= disc
    return lab


def iteration_ratio(lab, eps, dtype, n_iter=10, rounds=3, green="willot2015"):
    """(time per COCG iteration, bare FFT pair time, ratio) on ``lab``: medians of ``rounds``.

    The iteration time is the difference between runs of 2 + n_iter and 2 iterations (which
    removes set-up, right-hand side and flux), divided by n_iter; the bare pair is n_iter
    forward + inverse scipy.fft transforms of the same d-component field, in place, with the
    same workers — timed in alternation with the solves, on the solver's own work buffer (no
    extra field in memory).
    """
    import statistics

    d = lab.ndim
    op = green_operator(lab.shape, green)
    prob = Problem(lab.astype(np.uint8), 2, op, dtype, WORKERS)
    tab = np.array(eps, dtype=complex)
    e0 = np.eye(d)[0]
    solve_cocg(prob, tab, e0, tol=1e-30, maxiter=2, keep_x=False)  # warm up (JIT, FFT plans)
    axes = tuple(range(1, d + 1))
    its, ffts = [], []
    for _ in range(rounds):
        runs = {}
        for m in (2, 2 + n_iter):
            t = time.perf_counter()
            out = solve_cocg(prob, tab, e0, tol=1e-30, maxiter=m, keep_x=False)
            runs[m] = (time.perf_counter() - t, out.iterations)
            del out
        its.append((runs[2 + n_iter][0] - runs[2][0]) / (runs[2 + n_iter][1] - runs[2][1]))
        a = prob.q.reshape((d,) + lab.shape)
        t = time.perf_counter()
        for _ in range(n_iter):
            b = scipy.fft.fftn(a, axes=axes, workers=WORKERS, overwrite_x=True)
            a = scipy.fft.ifftn(b, axes=axes, workers=WORKERS, overwrite_x=True)
        ffts.append((time.perf_counter() - t) / n_iter)
        del a, b
    it, fft = statistics.median(its), statistics.median(ffts)
    return it, fft, it / fft


def peak_memory(n: int, maxiter: int = 5) -> dict:
    """Peak resident memory (VmHWM, MiB) of a fresh process that builds the flake cell at n³ and
    runs ``fft_permittivity`` on it (complex64, one loading, ``maxiter`` projections), as the
    totals below do; a subprocess, so that nothing else of this run counts."""
    import json
    import subprocess

    code = f"""
import json, sys, warnings
sys.path.insert(0, {str(__import__('pathlib').Path(__file__).resolve().parent)!r})
from bench_homogenize import flakes
from nmmm.errors import ConvergenceError
from nmmm.homogenize import fft_permittivity
def hwm():
    return [int(l.split()[1]) / 1024 for l in open('/proc/self/status') if l.startswith('VmHWM')][0]
out = {{'import': hwm()}}
lab = flakes({n}); out['geometry'] = hwm()
with warnings.catch_warnings():
    warnings.simplefilter('ignore')
    try:
        fft_permittivity(lab, {{0: 2.25, 1: -50 + 20j}}, dtype='complex64', directions=[0], maxiter={maxiter},
                         fallback=False, progress=False, max_minutes=float('inf'))
    except ConvergenceError:
        pass
out['solve'] = hwm()
print(json.dumps(out))
"""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def iteration_table(quick: bool):
    print("\n## Projections to relative residual 1e-6 against contrast (2-D Boolean discs, 128², p = 0.3)")
    lab2 = G.boolean_spheres(128, 0.3, 8, ndim=2, seed=1)
    solvers = ["cocg", "bicgstab", "gmres", "eyre_milton", "basic"]
    print(f"{'eps_metal':>12} {'green':>11} " + " ".join(f"{s:>11}" for s in solvers))
    for em in (-50 + 20j, -50 + 5j, -50 + 1j):
        for green in ("continuous", "willot2014", "willot2015"):
            row = []
            for s in solvers:
                cap = 3000 if s in ("eyre_milton", "basic") else 4000
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        r = fft_permittivity(lab2, {0: 2.25, 1: em}, green=green, solver=s, fallback=False,
                                             maxiter=cap, directions=[0])
                    row.append(f"{int(r.iterations[0]):>11d}")
                except Exception:
                    row.append(f"{'>' + str(cap):>11}")
            print(f"{str(em):>12} {green:>11} " + " ".join(row), flush=True)
    if quick:
        return
    print("\n## 3-D Boolean spheres 64³ (p = 0.2), ε = −50 + 2i in 2.25")
    lab3 = G.boolean_spheres(64, 0.2, 5, ndim=3, seed=1)
    for s in ("cocg", "eyre_milton"):
        t = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = fft_permittivity(lab3, {0: 2.25, 1: -50 + 2j}, solver=s, fallback=False, maxiter=5000,
                                 directions=[0], dtype="complex64")
        print(f"  {s:12s} {int(r.iterations[0]):5d} projections  {time.perf_counter() - t:7.1f} s  "
              f"eps_xx = {r.tensor[0, 0]:.4f}", flush=True)


def totals(n: int, directions=None):
    nload = 3 if directions is None else len(directions)
    print(f"\n## Totals at {n}³, complex64, {nload} loading(s), tol 1e-5", flush=True)
    t = time.perf_counter()
    hem = G.boolean_spheres(n, 0.10, max(2.0, n / 32), ndim=3, seed=2)
    fl = flakes(n)
    print(f"  geometry: {time.perf_counter() - t:.1f} s", flush=True)
    for name, lab, eps in (("hematite 10 % in epoxy", hem, {0: 2.4 + 0.001j, 1: 8.0 + 3.0j}),
                           ("Al flakes in resin", fl, {0: 2.25, 1: -50 + 20j})):
        per_iter, fft, ratio = iteration_ratio(lab, list(eps.values()), np.complex64, n_iter=4, rounds=2)
        t = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = fft_permittivity(lab, eps, dtype="complex64", progress=False, directions=directions)
        wall = time.perf_counter() - t
        print(f"  {name:24s} total {wall:7.1f} s, projections {r.iterations.tolist()}, "
              f"per iteration {per_iter * 1e3:.0f} ms vs bare FFT {fft * 1e3:.0f} ms: ratio {ratio:.2f}; "
              f"computed diag = {[complex(np.round(r.tensor[j, j], 3)) for j in r.directions]}", flush=True)
    print(f"  peak RSS so far: {peak_rss_mib():.0f} MiB", flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--big", action="store_true", help="also 256³")
    ap.add_argument("--quick", action="store_true", help="64³ only, short table")
    ap.add_argument("--no-table", action="store_true", help="skip the iterations-vs-contrast table")
    ap.add_argument("--no-ratio", action="store_true", help="skip the iteration/FFT ratio section")
    ap.add_argument("--memory", type=int, nargs="*", metavar="N",
                    help="only the peak memory (VmHWM) of a flake solve at each N³ (default 128 256), in subprocesses")
    args = ap.parse_args(argv)
    if args.memory is not None:
        for n in args.memory or [128, 256]:
            m = peak_memory(n)
            field = 3 * n**3 * 8 / 2**20
            print(f"  {n}³ complex64 flake solve: peak {m['solve']:.0f} MiB (after import {m['import']:.0f}, "
                  f"geometry {m['geometry']:.0f}; one vector field = {field:.0f} MiB)", flush=True)
        return 0
    print("# nmmm.homogenize benchmark (scipy.fft workers=2; numpy.fft is single-threaded and not used)")
    print("\n## Time per COCG iteration / bare FFT time of the same vector field")
    sizes = [(64, 64, 64)] if args.quick else [(512, 512), (64, 64, 64), (128, 128, 128)]
    for shape in ([] if args.no_ratio else sizes):
        lab = G.boolean_spheres(shape[0], 0.2, shape[0] / 16, ndim=len(shape), seed=0)
        for dt in (np.complex64, np.complex128):
            per_iter, fft, ratio = iteration_ratio(lab, [2.25, -50 + 20j], dt)
            print(f"  {str(shape):16s} {np.dtype(dt).name:10s} iteration {per_iter * 1e3:8.1f} ms   "
                  f"bare FFT {fft * 1e3:8.1f} ms   ratio {ratio:5.2f}", flush=True)
    if not args.no_table:
        iteration_table(args.quick)
    if not args.quick:
        totals(128)
    if args.big:
        totals(256, directions=[0])  # one loading: the other two cost about the same each
        print("  (one complex64 vector field at 256³ is 384 MiB; COCG holds 4 of them plus the "
              "warm-start copies)")
    print(f"\npeak RSS: {peak_rss_mib():.0f} MiB")


if __name__ == "__main__":
    sys.exit(main())
