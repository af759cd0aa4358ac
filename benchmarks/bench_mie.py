"""Benchmark: nmmm.layers.mie_scattering against miepython's Numba path (the library a user would pick).

Case (issue 4): 401 wavelengths (380–780 nm) × 200 diameters (20 nm – 2 µm, log-spaced) of a
hematite-like absorbing sphere (dispersive n + ik) in a resin of index 1.55. Both libraries are
warmed up (JIT compiled) first; each timing is the median of ``--repeat`` runs, alternating
the two; the accuracy is the largest relative difference of Q_ext, Q_sca, Q_back, g between the
two on the full grid. nmmm runs at ``NUMBA_NUM_THREADS`` threads, miepython's array call on one
(it has no parallel path): set ``NUMBA_NUM_THREADS=1`` for equal threads, or see
benchmarks/run_all.py, which runs both thread counts.

Per-call cost (issue 22, ``--single``): one sphere (m = 1.5 + 0.01i in air, D = 500 nm, λ = 550 nm,
x ≈ 2.9) by 1000 separate calls of each library, timed in alternation, medians of ``--repeat``
runs; the nmmm call includes its input checks and the MieResult it returns, miepython's its
tuple of four floats. Both run on one thread (neither threads a single sphere).

Run:  python benchmarks/bench_mie.py            # the grid
      python benchmarks/bench_mie.py --single   # the per-call cost
"""

from __future__ import annotations

import argparse
import os
import time

os.environ["MIEPYTHON_USE_JIT"] = "1"  # miepython's numba path, selected at import

import numpy as np  # noqa: E402


def main(repeat: int = 3) -> dict:
    import miepython

    from nmmm.layers.mie_scattering import mie

    assert miepython.USE_JIT, "miepython's numba path is not active"
    w = np.linspace(380.0, 780.0, 401)
    d = np.geomspace(20.0, 2000.0, 200)
    # a hematite-like index: strongly absorbing in the blue, weakly in the red
    nk = 2.6 + 0.4 * np.exp(-((w - 450.0) / 120.0) ** 2) + 1j * (0.02 + 0.9 / (1 + np.exp((w - 560.0) / 25.0)))
    n_med = 1.55

    # warm-up (compilation) outside the timings
    mie(nk[:2, None], n_med, d[None, :2], w[:2, None])
    miepython.efficiencies(nk[0], d[0], w[0], n_env=n_med)

    W, D = np.meshgrid(w, d, indexing="ij")
    M = np.broadcast_to(nk[:, None], W.shape)
    ts_nmmm, ts_mp = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        r = mie(nk[:, None], n_med, d[None, :], w[:, None])
        ts_nmmm.append(time.perf_counter() - t0)
        # miepython takes m = n - ik; it conjugates any positive imaginary part itself
        t0 = time.perf_counter()
        qext, qsca, qback, g = miepython.efficiencies(M.ravel(), D.ravel(), W.ravel(), n_env=n_med)
        ts_mp.append(time.perf_counter() - t0)
    t_nmmm, t_mp = float(np.median(ts_nmmm)), float(np.median(ts_mp))

    ref = np.array([qext, qsca, qback, g]).reshape(4, *W.shape)
    ours = np.array([r.qext, r.qsca, r.qback, r.g])
    rel = np.abs(ours - ref) / np.maximum(np.abs(ref), 1e-300)
    out = {
        "n_particles": W.size,
        "t_nmmm_s": t_nmmm,
        "t_miepython_numba_s": t_mp,
        "speedup": t_mp / t_nmmm,
        "max_rel_diff": {k: float(v) for k, v in zip(("qext", "qsca", "qback", "g"), rel.reshape(4, -1).max(axis=1))},
    }
    print(f"Mie, {len(w)} wavelengths x {len(d)} diameters = {W.size} spheres")
    print(f"  nmmm.layers.mie_scattering   : {t_nmmm * 1e3:8.1f} ms")
    print(f"  miepython (numba) : {t_mp * 1e3:8.1f} ms")
    print(f"  speed-up          : {out['speedup']:.1f}x  (target >= 2x)")
    print("  max relative difference vs miepython: " + ", ".join(f"{k} {v:.1e}" for k, v in out["max_rel_diff"].items()))
    return out


def per_call(repeat: int = 51, calls: int = 1000) -> dict:
    """µs per call of ``mie`` and of ``miepython.efficiencies`` for one sphere (see the module notes)."""
    import miepython

    from nmmm.layers.mie_scattering import mie

    args = (1.5 + 0.01j, 1.0, 500.0, 550.0)

    def ours():
        for _ in range(calls):
            r = mie(*args)
        return r

    def rival():
        for _ in range(calls):
            q = miepython.efficiencies(args[0], args[2], args[3], n_env=args[1])
        return q

    rel = abs(float(ours().qext) - rival()[0]) / rival()[0]  # also the warm-up (compilation)
    ts_ours, ts_rival = [], []
    for _ in range(repeat):
        for f, ts in ((ours, ts_ours), (rival, ts_rival)):
            t0 = time.perf_counter()
            f()
            ts.append(time.perf_counter() - t0)
    t_ours, t_rival = (float(np.median(t)) / calls * 1e6 for t in (ts_ours, ts_rival))
    print(f"Mie, one sphere (x = {float(ours().size_parameter):.2f}), {calls} separate calls, medians of {repeat}, "
          f"load {os.getloadavg()[0]:.1f}")
    print(f"  nmmm mie()              : {t_ours:6.2f} µs per call")
    print(f"  miepython.efficiencies  : {t_rival:6.2f} µs per call")
    print(f"  ratio miepython / nmmm  : {t_rival / t_ours:.2f}   (Q_ext rel. difference {rel:.0e})")
    return {"us_per_call_nmmm": t_ours, "us_per_call_miepython": t_rival, "ratio": t_rival / t_ours}


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--single", action="store_true", help="the per-call cost of one sphere instead of the grid")
    a = p.parse_args()
    per_call(max(a.repeat, 21)) if a.single else main(a.repeat)
