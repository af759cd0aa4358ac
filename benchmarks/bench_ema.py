"""Benchmark: nmmm.ema against the same formulas written in plain NumPy, at one thread.

Work: gold (Johnson & Christy) in silica (Malitson), 401 wavelengths (380–780 nm) ×
1000 volume fractions, Maxwell Garnett, Bruggeman and Looyenga, each in one broadcast call;
the rival is the closed-form formula as a user would write it in NumPy (for two-phase
Bruggeman the principal-root formula, which gives the gain root Im ε < 0 at a third of
these points: a speed floor, not the same function). Times are medians of ``--repeat`` runs
after a warm-up call. nmmm's values are checked against pyElli's EMA classes (the library a
user would otherwise pick) on 10 of the fractions; pyElli is not timed, its API takes one
fraction per call. The n-phase root finder on the same two phases, and a three-phase mixture,
are timed too. For every kernel at 1 and 2 threads see benchmarks/run_all.py.

    python benchmarks/bench_ema.py
"""

from __future__ import annotations

import time

import numpy as np


def median_of(fn, repeat=7):
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out


def main():
    import elli

    import nmmm.materials as M
    from nmmm.ema import bruggeman, looyenga, maxwell_garnett

    w = np.arange(380.0, 781.0, 1.0)
    fractions = np.linspace(0.0, 1.0, 1000)
    ea, es = M.get("main/Au/Johnson").eps(w), M.get("main/SiO2/Malitson").eps(w)
    e1, e2, p = ea[:, None], es[:, None], fractions[None, :]
    host = elli.IsotropicMaterial(elli.TableEpsilon(lbda=w, epsilon=es))
    guest = elli.IsotropicMaterial(elli.TableEpsilon(lbda=w, epsilon=ea))

    def np_mg():
        return e2 * ((1 + 2 * p) * e1 + 2 * (1 - p) * e2) / ((1 - p) * e1 + (2 + p) * e2)

    def np_bruggeman():
        b = (3 * p - 1) * e1 + (2 - 3 * p) * e2
        return (b + np.sqrt(b * b + 8 * e1 * e2)) / 4

    def np_looyenga():
        return (p * e1 ** (1 / 3) + (1 - p) * e2 ** (1 / 3)) ** 3

    cases = [
        ("Maxwell Garnett", maxwell_garnett, np_mg, elli.MaxwellGarnettEMA),
        ("Bruggeman", bruggeman, np_bruggeman, elli.BruggemanEMA),
        ("Looyenga", looyenga, np_looyenga, elli.LooyengaEMA),
    ]
    print(f"work: {w.size} wavelengths x {fractions.size} fractions, gold in silica")
    print(f"{'method':18s} {'nmmm (ms)':>10s} {'NumPy (ms)':>11s} {'ratio':>6s} {'rel. diff vs pyElli':>20s}")
    sub = np.arange(0, fractions.size, 100)
    for name, ours, formula, theirs in cases:
        t_ours, out = median_of(lambda: ours(e1, e2, p))
        t_np, _ = median_of(formula)
        ref = np.stack([theirs(host, guest, float(fractions[k])).get_tensor(w)[:, 0, 0] for k in sub], axis=1)
        ok = np.isfinite(ref)
        diff = np.max(np.abs(out[:, sub][ok] - ref[ok]) / np.maximum(np.abs(ref[ok]), 1e-300))
        print(f"{name:18s} {t_ours * 1e3:10.2f} {t_np * 1e3:11.2f} {t_np / t_ours:6.2f} {diff:20.2e}")
    naive = np_bruggeman()
    print(f"(the NumPy Bruggeman formula has Im eps < 0 at {np.mean(naive.imag < -1e-12):.0%} of the points)")

    from nmmm.ema.bruggeman_rule import _bruggeman_general, _groups, _phases

    e, f = _phases([e1, e2], [p, 1 - p])
    t_gen, out_gen = median_of(lambda: _bruggeman_general(e, f, *_groups(2, None)), 3)
    t_fast, out_fast = median_of(lambda: bruggeman(e1, e2, p))
    print(f"Bruggeman two-phase: closed form {t_fast * 1e3:.1f} ms vs n-phase root finder {t_gen * 1e3:.1f} ms "
          f"({t_gen / t_fast:.0f}x; max rel. diff {np.max(np.abs(out_fast - out_gen) / np.abs(out_gen)):.1e})")

    # what pyElli cannot do in one call: three phases (gold, silica, air voids)
    f3 = np.stack(np.meshgrid(np.linspace(0, 0.5, 100), np.linspace(0, 0.5, 10), indexing="ij"), -1).reshape(-1, 2)
    t3, out3 = median_of(lambda: bruggeman([e1, np.ones(1), e2],
                                           [f3[None, :, 0], f3[None, :, 1], 1 - f3[None, :, 0] - f3[None, :, 1]]), 3)
    print(f"3-phase Bruggeman, {w.size} x {f3.shape[0]} in one call: {t3:.3f} s "
          f"(Im eps >= 0 everywhere: {bool(np.all(out3.imag >= 0))})")


if __name__ == "__main__":
    import os

    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    main()
