"""Paint BRDF speed: 10^6 direction pairs × 81 wavelengths, measured in one run.

What is timed
-------------
- nmmm's fused Numba kernel (``PaintBRDF.evaluate``, float32 output, 2 threads) for a
  solid, a metallic (Al flakes) and an interference (TiO2/mica) paint; the table set-up
  for a wavelength grid (``prepare``) is timed separately (once per paint and grid).
- the same equations as chunked NumPy array code (``method="numpy"``) — the baseline a
  user writing vectorised NumPy would get;
- ``tmm`` (Byrnes), the library a user would otherwise pick for the Fresnel factors: the
  unpolarised reflectance of the clear coat alone (one ``coh_tmm`` call per polarisation,
  angle and wavelength), timed on a subset and extrapolated linearly to the 2 × 10^6 × 81
  interface evaluations that one BRDF evaluation needs (coat in and coat out).

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

    numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
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

    import tmm

    k = 200
    ang = np.radians(rng.uniform(0, 89, k))
    wl = rng.choice(w, k)
    t = time.perf_counter()
    for a, lam in zip(ang, wl):
        0.5 * (tmm.coh_tmm("s", [1.0, 1.5], [np.inf, np.inf], a, lam)["R"]
               + tmm.coh_tmm("p", [1.0, 1.5], [np.inf, np.inf], a, lam)["R"])
    t_tmm = (time.perf_counter() - t) / k * (2 * n_pairs * w.size)
    t_best = min(v[1] for v in results.values())
    print(f"\ntmm, coat Fresnel factors only (2 x {n_pairs:.0e} x {w.size}), extrapolated from {k} calls: "
          f"{t_tmm:.0f} s -> the whole nmmm BRDF is {t_tmm / t_best:.0f}x faster than tmm's Fresnel alone")


if __name__ == "__main__":
    main(int(float(sys.argv[1])) if len(sys.argv) > 1 else 1_000_000)
