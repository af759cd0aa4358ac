"""Thin-film transfer matrices: nmmm ``Stack.rt`` against ``tmm`` and pyElli's 2×2 solver.

The issue's case: a 10-layer stack (dielectrics, one thin absorbing metal layer, weakly
absorbing oxides) on glass, 401 wavelengths (380–780 nm) × 91 angles (0–89°), s and p.
All timings come from this one run on this machine; the script prints the ratios and the
largest differences of the amplitude coefficients against each reference (same inputs).

``tmm`` computes one (wavelength, angle, polarization) per Python call; timing all
2 × 401 × 91 = 72 982 calls takes about a minute here, so by default it is timed on every
``--tmm-stride``-th wavelength (all angles, both polarizations) and scaled by the number
of points (its cost is per point). ``--tmm-stride 1`` times the full grid.

pyElli evaluates one angle of incidence per ``Structure.evaluate`` call (vectorised over
wavelengths), so it is called once per angle, as a user would.

Run:  python benchmarks/bench_thinfilm.py [--repeat 5] [--tmm-stride 8]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from nmmm.layers import Stack

NK = [2.4 + 0.01j, 1.46, 2.4 + 0.01j, 1.46, 0.8 + 6.0j, 1.46, 2.0 + 0.1j, 1.38, 2.4, 1.46]
D_NM = [55.0, 90.0, 60.0, 95.0, 8.0, 100.0, 70.0, 110.0, 50.0, 85.0]
N_AMBIENT, N_SUBSTRATE = 1.0, 1.52


def best_of(fn, repeat):
    times = []
    out = None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return min(times), out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--tmm-stride", type=int, default=8)
    args = ap.parse_args(argv)

    wl = np.linspace(380.0, 780.0, 401)
    ang = np.linspace(0.0, 89.0, 91)
    stack = Stack(list(zip(NK, D_NM)), ambient=N_AMBIENT, substrate=N_SUBSTRATE)
    npts = wl.size * ang.size
    print(f"10-layer stack x {wl.size} wavelengths x {ang.size} angles = {npts} points, s and p")

    # nmmm: warm-up (Numba compile / cache load), then best of --repeat
    stack.rt(wl[:3], ang[:2], method="numba")
    stack.rt(wl[:3], ang[:2], method="numpy")
    t_nb, res = best_of(lambda: stack.rt(wl, ang, method="numba"), args.repeat)
    t_np, res_np = best_of(lambda: stack.rt(wl, ang, method="numpy"), args.repeat)
    print(f"nmmm Stack.rt (numba)     {t_nb * 1e3:9.1f} ms")
    print(f"nmmm Stack.rt (numpy)     {t_np * 1e3:9.1f} ms   max|r_numba - r_numpy| = "
          f"{max(np.abs(res.rs - res_np.rs).max(), np.abs(res.rp - res_np.rp).max()):.1e}")

    # pyElli Solver2x2, one call per angle
    import elli

    def mat(n):
        return elli.IsotropicMaterial(elli.ConstantRefractiveIndex(n=complex(n)))

    structure = elli.Structure(
        mat(N_AMBIENT), [elli.Layer(mat(n), d) for n, d in zip(NK, D_NM)], mat(N_SUBSTRATE)
    )

    def run_elli():
        return [structure.evaluate(wl, float(a), solver=elli.Solver2x2) for a in ang]

    run_elli()
    t_el, out = best_of(run_elli, max(1, args.repeat // 2))
    # pyElli's Jones matrix is [[rpp, rps], [rsp, rss]]; same rp sign convention as nmmm
    rs_el = np.array([o.jones_matrix_r[:, 1, 1] for o in out]).T
    rp_el = np.array([o.jones_matrix_r[:, 0, 0] for o in out]).T
    d_el = max(np.abs(rs_el - res.rs).max(), np.abs(rp_el - res.rp).max())
    print(f"pyElli Solver2x2          {t_el * 1e3:9.1f} ms   max|r_nmmm - r_pyElli| = {d_el:.1e}")

    # tmm coh_tmm, one call per point and polarization
    import tmm

    n_list = [N_AMBIENT] + NK + [N_SUBSTRATE]
    d_list = [np.inf] + D_NM + [np.inf]
    sub = wl[:: args.tmm_stride]
    t0 = time.perf_counter()
    dmax = 0.0
    for i, w in enumerate(sub):
        for j, a in enumerate(ang):
            for pol, r in (("s", res.rs), ("p", res.rp)):
                ref = tmm.coh_tmm(pol, n_list, d_list, np.radians(a), w)
                dmax = max(dmax, abs(ref["r"] - r[i * args.tmm_stride, j]))
    t_sub = time.perf_counter() - t0
    t_tmm = t_sub * npts / (sub.size * ang.size)
    note = "" if args.tmm_stride == 1 else f" (timed on {sub.size}x{ang.size} points, scaled)"
    print(f"tmm coh_tmm               {t_tmm * 1e3:9.1f} ms{note}   max|r_nmmm - r_tmm| = {dmax:.1e}")

    print()
    print(f"speed-up vs tmm:    numba {t_tmm / t_nb:7.1f}x   numpy {t_tmm / t_np:7.1f}x   (target >= 50x)")
    print(f"speed-up vs pyElli: numba {t_el / t_nb:7.1f}x   numpy {t_el / t_np:7.1f}x   (target >= 1x)")


if __name__ == "__main__":
    main()
