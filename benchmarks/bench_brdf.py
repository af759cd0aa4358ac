"""Paint BRDF speed: 10^6 direction pairs × 81 wavelengths, measured in one run.

What is timed
-------------
- nmmm's fused Numba kernel (``PaintBRDF.evaluate``, float32 output) for a
  solid, a metallic (Al flakes) and an interference (TiO2/mica) paint; the table set-up
  for a wavelength grid (``prepare``) is timed separately (once per paint and grid).
- the same equations as chunked NumPy array code (``method="numpy"``) — the baseline a
  user writing vectorised NumPy would get;
- a floor: the clear coat's unpolarised Fresnel factors alone (coat in and coat out, 2 of
  the BRDF's factors) written as vectorised NumPy over the same pairs and wavelengths. No
  library computes this paint BRDF, so this is a lower bound of the work any implementation
  does, not the same computation. (Earlier versions extrapolated tmm's per-call Fresnel;
  tmm has no array call, so that was a Python loop and is no longer reported.)

nmmm runs at the thread count of the process (``NUMBA_NUM_THREADS``); the NumPy code on
one. Equal-thread numbers for every kernel: benchmarks/run_all.py.

    python benchmarks/bench_brdf.py [n_pairs]
"""

from __future__ import annotations

import sys
import time

import numpy as np


def random_directions(n, rng):
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2])
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def main(n_pairs: int = 1_000_000):
    import numba

    from nmmm.appearance.brdf import interference_paint, metallic_paint, opaque_paint

    w = np.linspace(380.0, 780.0, 81)
    rng = np.random.default_rng(0)
    wi, wo = random_directions(n_pairs, rng), random_directions(n_pairs, rng)
    paints = [opaque_paint(0.5, name="solid"), metallic_paint(name="metallic (Al)"),
              interference_paint(name="interference (TiO2/mica)")]
    print(f"BRDF evaluation: {n_pairs:.0e} direction pairs x {w.size} wavelengths, {numba.get_num_threads()} threads")
    print(f"{'paint':28s} {'prepare s':>10s} {'numba s':>9s} {'numpy s':>9s} {'numpy/numba':>12s} {'Mevals/s':>9s}")
    results = {}
    for b in paints:
        t = time.perf_counter()
        b.prepare(w)
        t_prep = time.perf_counter() - t
        b(w, wi[:1000], wo[:1000], dtype=np.float32)  # compile / load the kernel
        t = time.perf_counter()
        f = b(w, wi, wo, dtype=np.float32)
        t_nb = time.perf_counter() - t
        m = min(n_pairs, 200_000)
        t = time.perf_counter()
        b(w, wi[:m], wo[:m], dtype=np.float32, method="numpy")
        t_np = (time.perf_counter() - t) * n_pairs / m
        results[b.name] = (t_prep, t_nb, t_np)
        print(f"{b.name:28s} {t_prep:10.2f} {t_nb:9.2f} {t_np:9.2f} {t_np / t_nb:12.1f} "
              f"{n_pairs * w.size / t_nb / 1e6:9.1f}")
        del f

    n = np.full(w.size, 1.5)[None, :]

    def fresnel(mu):  # unpolarised air -> coat Fresnel reflectance at cos(theta) = mu
        mu = mu[:, None]
        ct = np.sqrt(1 - (1 - mu * mu) / (n * n))
        rs = (mu - n * ct) / (mu + n * ct)
        rp = (n * mu - ct) / (n * mu + ct)
        return 0.5 * (rs * rs + rp * rp)

    m = min(n_pairs, 200_000)
    t = time.perf_counter()
    fresnel(np.abs(wi[:m, 2])) * fresnel(np.abs(wo[:m, 2]))
    t_fl = (time.perf_counter() - t) * n_pairs / m
    t_best = min(v[1] for v in results.values())
    print(f"\nfloor: coat Fresnel factors in and out alone, vectorised NumPy ({n_pairs:.0e} x {w.size}, timed on "
          f"{m} pairs): {t_fl:.2f} s; fastest whole nmmm BRDF {t_best:.2f} s (ratio {t_fl / t_best:.1f})")


def effect_coat(n_pairs: int = 1_000_000, repeats: int = 5):
    """Issue 18 Speed: an effect coat with pigments (Al flakes with rough faces and rims in a
    red-pigmented basecoat, CoatMedium) against today's metallic paint (Al flakes over a grey
    base), both through ``PaintBRDF.evaluate`` (float32), same pairs, same threads; medians of
    ``repeats``. Returns the medians (s) and their ratio; the target is ratio <= 2."""
    from dataclasses import replace

    from nmmm.appearance.brdf import CoatMedium, metallic_paint
    from nmmm.appearance.flakes import edge_scatter_fraction

    w = np.linspace(380.0, 780.0, 81)
    rng = np.random.default_rng(1)
    wi, wo = random_directions(n_pairs, rng), random_directions(n_pairs, rng)
    metallic = metallic_paint(name="metallic (Al)")
    mu_a = 2e-4 * np.exp(-((w - 480.0) / 60.0) ** 2) + 1e-6
    red = metallic.with_(flakes=replace(metallic.flakes, surface_roughness=0.05, edge_fraction=edge_scatter_fraction(20e3)),
                         medium=CoatMedium(w, mu_a, 3e-5, 0.5, 2e4), name="red metallic (pigmented coat)")
    out = {}
    for b in (metallic, red):
        t = time.perf_counter()
        b.prepare(w)
        t_prep = time.perf_counter() - t
        b(w, wi[:1000], wo[:1000], dtype=np.float32)
        times = []
        for _ in range(repeats):
            t = time.perf_counter()
            b(w, wi, wo, dtype=np.float32)
            times.append(time.perf_counter() - t)
        out[b.name] = (t_prep, float(np.median(times)))
    (p0, t0), (p1, t1) = out.values()
    print(f"\neffect coat with pigments vs metallic kernel ({n_pairs:.0e} pairs x {w.size} wavelengths, median of "
          f"{repeats}): metallic {t0:.2f} s (prepare {p0:.2f} s), pigmented effect coat {t1:.2f} s "
          f"(prepare {p1:.2f} s), ratio {t1 / t0:.2f} (target <= 2)")
    return {"metallic_s": t0, "effect_coat_s": t1, "ratio": t1 / t0, "prepare_s": p1}


if __name__ == "__main__":
    main(int(float(sys.argv[1])) if len(sys.argv) > 1 else 1_000_000)
    effect_coat(int(float(sys.argv[1])) if len(sys.argv) > 1 else 1_000_000)
