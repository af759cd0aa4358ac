"""Benchmark: nmmm.ema against pyElli's EMA classes on the same work, measured in one run.

Work: gold (Johnson & Christy) in silica (Malitson), 401 wavelengths (380–780 nm) ×
1000 volume fractions, Maxwell Garnett, Bruggeman and Looyenga. Two-phase Bruggeman uses
nmmm's closed-form quadratic path; the n-phase root finder on the same two phases is timed
too, for comparison. nmmm does each in one
broadcast call; pyElli takes one scalar fraction per call (its MixtureMaterial API), so it
loops over the fractions. Results are checked to agree before timing is reported.

    python benchmarks/bench_ema.py
"""

from __future__ import annotations

import time

import numpy as np


def best_of(fn, repeat=3):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def main():
    import elli

    import nmmm.materials as M
    from nmmm.ema import bruggeman, looyenga, maxwell_garnett

    w = np.arange(380.0, 781.0, 1.0)
    fractions = np.linspace(0.0, 1.0, 1000)
    ea, es = M.get("main/Au/Johnson").eps(w), M.get("main/SiO2/Malitson").eps(w)
    host = elli.IsotropicMaterial(elli.TableEpsilon(lbda=w, epsilon=es))
    guest = elli.IsotropicMaterial(elli.TableEpsilon(lbda=w, epsilon=ea))

    cases = [
        ("Maxwell Garnett", maxwell_garnett, elli.MaxwellGarnettEMA),
        ("Bruggeman", bruggeman, elli.BruggemanEMA),
        ("Looyenga", looyenga, elli.LooyengaEMA),
    ]
    print(f"work: {w.size} wavelengths x {fractions.size} fractions, gold in silica")
    print(f"{'method':18s} {'nmmm (s)':>10s} {'pyElli (s)':>11s} {'speed-up':>9s} {'max rel. diff':>14s}")
    for name, ours, theirs in cases:
        t_ours, out = best_of(lambda: ours(ea[:, None], es[:, None], fractions[None, :]))

        def run_pyelli():
            cols = [theirs(host, guest, float(f)).get_tensor(w)[:, 0, 0] for f in fractions]
            return np.stack(cols, axis=1)

        t_ref, ref = best_of(run_pyelli, repeat=1)
        ok = np.isfinite(ref)
        diff = np.max(np.abs(out[ok] - ref[ok]) / np.maximum(np.abs(ref[ok]), 1e-300))
        print(f"{name:18s} {t_ours:10.4f} {t_ref:11.3f} {t_ref / t_ours:8.0f}x {diff:14.2e}")

    from nmmm.ema.bruggeman_rule import _bruggeman_general, _groups, _phases

    e2, f2 = _phases([ea[:, None], es[:, None]], [fractions[None, :], 1 - fractions[None, :]])
    t_gen, out_gen = best_of(lambda: _bruggeman_general(e2, f2, *_groups(2, None)))
    t_fast, out_fast = best_of(lambda: bruggeman(ea[:, None], es[:, None], fractions[None, :]))
    print(f"Bruggeman two-phase: closed form {t_fast:.4f} s vs n-phase root finder {t_gen:.4f} s "
          f"({t_gen / t_fast:.0f}x; max rel. diff {np.max(np.abs(out_fast - out_gen) / np.abs(out_gen)):.1e})")

    # what pyElli cannot do in one call: three phases (gold, silica, air voids)
    f3 = np.stack(np.meshgrid(np.linspace(0, 0.5, 100), np.linspace(0, 0.5, 10), indexing="ij"), -1).reshape(-1, 2)
    t3, out3 = best_of(lambda: bruggeman([ea[:, None], np.ones(1), es[:, None]],
                                         [f3[None, :, 0], f3[None, :, 1], 1 - f3[None, :, 0] - f3[None, :, 1]]))
    print(f"3-phase Bruggeman, {w.size} x {f3.shape[0]} in one call: {t3:.3f} s "
          f"(Im eps >= 0 everywhere: {bool(np.all(out3.imag >= 0))})")


if __name__ == "__main__":
    main()
