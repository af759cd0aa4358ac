"""Every nmmm kernel against the best a user could do instead, at equal thread counts, one table.

    python benchmarks/run_all.py                 # 1 and 2 threads, writes benchmarks/RESULTS.md
    python benchmarks/run_all.py --threads 1     # one thread count
    python benchmarks/run_all.py --only mie ema  # some cases

How it measures
---------------
- Each thread count runs in its own Python process started with NUMBA_NUM_THREADS,
  OMP_NUM_THREADS, OPENBLAS_NUM_THREADS and MKL_NUM_THREADS set to that count, so nmmm and
  the rival get the same number of cores (scipy.fft ``workers`` too).
- Every callable is called once first (Numba compilation, caches, FFT plans), then nmmm and
  its rivals are timed in alternation ``--repeat`` times (so load changes hit both); the
  table shows medians.
- Rivals are the fastest way the other library allows (vectorised calls: miepython's array
  call, colour's ``msds_to_XYZ``, pyElli's array-over-wavelength ``evaluate``, iadpython's
  array ``Sample``), or, where no library does the computation, the closed-form formula
  written in plain NumPy — the floor a user would write. Never a Python loop over points
  where the rival offers arrays, never nmmm against nmmm.
- ratio = rival time / nmmm time (> 1: nmmm faster). Each case checks that nmmm and the
  rival agree on the same inputs (the "agreement" column) before its time counts.
- exponent: the slope of log time against log work between the case at 1/4 of its size and
  at full size (1: linear).
- The machine's load average is printed with the table: on a shared machine times are
  noisy, ratios measured in the same process less so.

Cases whose rival is a floor rather than the same computation say so in the table
(``floor:``): the bare FFT pair of one FFT-solver iteration, the principal-root Bruggeman
formula (which returns the gain root, Im ε < 0, for metal fractions — not the same
function), the coat's Fresnel factors alone for the BRDF, nmmm's own fused BRDF kernel on the same
pixel pairs for the plate render's per-pixel path (issues 19/22 measure the path against its
kernel: the ratio is the share of the kernel's rate the whole image keeps, <= 1 by nature).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


# --------------------------------------------------------------------------------------
# cases: each returns (work description, work count, nmmm callable, [(rival, callable)], check)
# --------------------------------------------------------------------------------------

def case_mie(scale, threads):
    os.environ["MIEPYTHON_USE_JIT"] = "1"
    import miepython
    import numpy as np

    from nmmm.layers.mie_scattering import mie

    w = np.linspace(380.0, 780.0, 401)
    d = np.geomspace(20.0, 2000.0, int(200 * scale))
    nk = 2.6 + 0.4 * np.exp(-((w - 450.0) / 120.0) ** 2) + 1j * (0.02 + 0.9 / (1 + np.exp((w - 560.0) / 25.0)))
    W, D = np.meshgrid(w, d, indexing="ij")
    M = np.broadcast_to(nk[:, None], W.shape).ravel()

    def ours():
        return mie(nk[:, None], 1.55, d[None, :], w[:, None])

    def rival():
        return miepython.efficiencies(M, D.ravel(), W.ravel(), n_env=1.55)

    def check():
        r, q = ours(), rival()
        return f"Qext rel {np.max(np.abs(r.qext.ravel() - q[0]) / np.abs(q[0])):.0e}"

    return f"Mie 401 λ × {d.size} diameters", W.size, ours, [("miepython (numba, array call)", rival)], check


def case_mie_single(scale, threads):
    os.environ["MIEPYTHON_USE_JIT"] = "1"
    import miepython

    from nmmm.layers.mie_scattering import mie

    calls = 1000  # one call is a few µs: time a thousand to rise above the timer's resolution

    def ours():
        for _ in range(calls):
            r = mie(1.5 + 0.01j, 1.0, 500.0, 550.0)
        return r

    def rival():
        for _ in range(calls):
            q = miepython.efficiencies(1.5 + 0.01j, 500.0, 550.0, n_env=1.0)
        return q

    def check():
        return f"Qext rel {abs(float(ours().qext) - float(rival()[0])) / float(rival()[0]):.0e}"

    return f"Mie one sphere, {calls} separate calls (per-call cost)", 1, ours, \
        [("miepython (numba), same calls", rival)], check


def case_thinfilm(scale, threads):
    import elli
    import numpy as np

    from nmmm.layers import Stack

    nk = [2.4 + 0.01j, 1.46, 2.4 + 0.01j, 1.46, 0.8 + 6.0j, 1.46, 2.0 + 0.1j, 1.38, 2.4, 1.46]
    dd = [55.0, 90.0, 60.0, 95.0, 8.0, 100.0, 70.0, 110.0, 50.0, 85.0]
    wl = np.linspace(380.0, 780.0, 401)
    ang = np.linspace(0.0, 89.0, max(2, int(92 * scale)))
    stack = Stack(list(zip(nk, dd)), ambient=1.0, substrate=1.52)

    def mat(n):
        return elli.IsotropicMaterial(elli.ConstantRefractiveIndex(n=complex(n)))

    structure = elli.Structure(mat(1.0), [elli.Layer(mat(n), t) for n, t in zip(nk, dd)], mat(1.52))

    def ours():
        return stack.rt(wl, ang)

    def rival():  # pyElli vectorises over wavelength; one call per angle is its array API
        return [structure.evaluate(wl, float(a), solver=elli.Solver2x2) for a in ang]

    def check():
        r, o = ours(), rival()
        rs = np.array([x.jones_matrix_r[:, 1, 1] for x in o]).T
        return f"max|Δrs| {np.abs(rs - r.rs).max():.0e}"

    return f"thin film 10 layers × 401 λ × {ang.size} angles", wl.size * ang.size, ours, \
        [("pyElli Solver2x2 (array over λ)", rival)], check


def case_adding_doubling(scale, threads):
    import iadpython as iad
    import numpy as np

    from nmmm.layers import adding_doubling

    a = np.linspace(0.3, 0.999, int(400 * scale))

    def ours():
        return adding_doubling(a, 2.0, 0.6, n_slab=1.5, quad_pts=16, quadrature="prahl")

    def rival():
        return iad.Sample(a=a, b=2.0, g=0.6, n=1.5, n_above=1.5, n_below=1.5, quad_pts=16).rt()

    def check():
        return f"max|ΔR| {np.abs(ours().reflectance - rival()[0]).max():.0e}"

    return f"adding-doubling slab, {a.size} albedos, 16 points", a.size, ours, \
        [("iadpython (array Sample)", rival)], check


def case_colour(scale, threads):
    import colour
    import numpy as np

    from nmmm.colour import spectra_to_lab, weighting_factors

    w = np.arange(380, 781, 1.0)
    n = int(100_000 * scale)
    R = np.random.default_rng(0).random((n, w.size))
    shape = colour.SpectralShape(380, 780, 1)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
    ill = colour.SDS_ILLUMINANTS["D65"].copy().align(shape)
    xyz_w = colour.sd_to_XYZ(colour.sd_ones(shape), cmfs, ill, method="Integration") / 100
    xy_w = colour.XYZ_to_xy(xyz_w)
    Wt = np.ascontiguousarray(weighting_factors(w))  # (λ, 3), the same weights nmmm uses
    white = Wt.sum(0)

    def ours():
        return spectra_to_lab(w, R)

    def rival():
        return colour.XYZ_to_Lab(colour.msds_to_XYZ(R, cmfs, ill, method="Integration", shape=shape) / 100, xy_w)

    def floor():  # matrix product + the CIELAB formula in NumPy
        t = (R @ Wt) / white
        f = np.where(t > (6 / 29) ** 3, np.cbrt(t), t / (3 * (6 / 29) ** 2) + 4 / 29)
        return np.stack([116 * f[:, 1] - 16, 500 * (f[:, 0] - f[:, 1]), 200 * (f[:, 1] - f[:, 2])], -1)

    def check():
        a = ours()
        return f"max|ΔLab| colour {np.abs(a - rival()).max():.0e}, numpy {np.abs(a - floor()).max():.0e}"

    return f"CIELAB of {n} spectra × 401 λ", n, ours, \
        [("colour msds_to_XYZ + XYZ_to_Lab", rival), ("floor: R @ W + CIELAB in NumPy", floor)], check


def _ema_inputs(scale):
    import numpy as np

    import nmmm.materials as M

    w = np.arange(380.0, 781.0, 1.0)
    f = np.linspace(0.0, 1.0, int(1000 * scale))[None, :]
    return M.get("main/Au/Johnson").eps(w)[:, None], M.get("main/SiO2/Malitson").eps(w)[:, None], f


def case_maxwell_garnett(scale, threads):
    import numpy as np

    from nmmm.ema import maxwell_garnett

    ei, em, p = _ema_inputs(scale)

    def ours():
        return maxwell_garnett(ei, em, p)

    def rival():
        return em * ((1 + 2 * p) * ei + 2 * (1 - p) * em) / ((1 - p) * ei + (2 + p) * em)

    def check():
        return f"max rel {np.max(np.abs(ours() - rival()) / np.abs(rival())):.0e}"

    return f"Maxwell Garnett Au/SiO2 401 λ × {p.size} fractions", p.size * ei.size, ours, \
        [("eq. (2) in NumPy", rival)], check


def case_bruggeman(scale, threads):
    import numpy as np

    from nmmm.ema import bruggeman, bruggeman_residual

    e1, e2, p = _ema_inputs(scale)

    def ours():
        return bruggeman(e1, e2, p)

    def rival():  # what a user writes; for gold fractions it returns the gain root
        b = (3 * p - 1) * e1 + (2 - 3 * p) * e2
        return (b + np.sqrt(b * b + 8 * e1 * e2)) / 4

    def check():
        out, naive = ours(), rival()
        res = np.abs(bruggeman_residual(out, [e1, e2], [p, 1 - p])).max()
        return f"residual {res:.0e}; NumPy root has Im<0 at {np.mean(naive.imag < -1e-12):.0%} of points"

    return f"Bruggeman 2-phase Au/SiO2 401 λ × {p.size}", p.size * e1.size, ours, \
        [("floor: principal-root formula in NumPy", rival)], check


def case_looyenga(scale, threads):
    import numpy as np

    from nmmm.ema import looyenga

    e1, e2, p = _ema_inputs(scale)

    def ours():
        return looyenga(e1, e2, p)

    def rival():
        return (p * e1 ** (1 / 3) + (1 - p) * e2 ** (1 / 3)) ** 3

    def check():
        return f"max rel {np.max(np.abs(ours() - rival()) / np.abs(rival())):.0e}"

    return f"Looyenga Au/SiO2 401 λ × {p.size}", p.size * e1.size, ours, [("formula in NumPy", rival)], check


def case_boolean(scale, threads):
    import math

    import numpy as np
    from scipy import ndimage

    import nmmm.microstructure as M

    n = 128 if scale == 1 else 80  # 80³ ≈ 128³/4
    shape, r, frac = (n, n, n), 5, 0.30

    def ours():
        return M.boolean_spheres(shape, 1.0, r, fraction=frac, seed=1)

    def rival():  # Poisson seeds, then a Euclidean distance transform (scipy, non-periodic)
        rng = np.random.default_rng(1)
        theta = -math.log(1 - frac) / (4 / 3 * math.pi * r**3)
        k = rng.poisson(theta * n**3)
        seeds = np.ones(shape, bool)
        seeds[tuple(rng.integers(0, n, k) for _ in range(3))] = False
        return ndimage.distance_transform_edt(seeds) <= r

    def check():
        return f"fraction {ours().volume_fraction():.3f} vs {rival().mean():.3f} (target {frac})"

    return f"Boolean spheres {n}³ r=5 30 %", n**3, ours, [("scipy EDT of Poisson seeds", rival)], check


def case_fft_iteration(scale, threads):
    """One COCG iteration of the FFT solver against the bare FFT pair of its field (issue 22:
    iteration / pair <= 1.3; the table's ratio is pair / iteration, so >= 0.77).

    nmmm: ``solve_cocg`` on Boolean spheres (20 %, ε 2.25 | −50+20i), willot2015, complex64,
    ``Problem(..., workers=threads)`` (scipy.fft ``workers`` and the kernels' thread count),
    x formed (``keep_x=True``, the default). Per iteration: the direction + ε pass (p ← r + β p,
    q ← ε p, pᵀεp), the real-space divergence of q (the scalar Dᵀ q / h), 1 forward FFT of it in
    place, the inverse-Laplacian pass, 1 inverse FFT (the potential ψ), the x update
    (x ← x + α p) and the stencil update (r ← r − α D ψ / h, rᵀr, ‖r‖²).
    Timed as (run of 2 + k iterations − run of 2) / k, k = 8, which removes the set-up, the
    right-hand side (one Γ) and the flux. Rival: k forward + inverse ``scipy.fft.fftn``/``ifftn``
    pairs of a 3-component complex64 field, in place (``overwrite_x``), same ``workers``,
    divided by k — the FFTs of one iteration of the usual Galerkin scheme (Γ applied in Fourier
    space to the vector field); nmmm's iteration transforms one scalar field (2 FFTs against 6).
    The agreement column also gives the time of those 2 scalar FFTs alone (same ``workers``,
    medians of 5 runs of k pairs), so the iteration's cost over its own FFTs can be read off.
    """
    import numpy as np
    import scipy.fft

    from nmmm.homogenize import geometries as G
    from nmmm.homogenize.green import green_operator
    from nmmm.homogenize.solvers import Problem, solve_cocg

    n = 128 if scale == 1 else 80
    lab = G.boolean_spheres(n, 0.2, n / 16, ndim=3, seed=0).astype(np.uint8)
    prob = Problem(lab, 2, green_operator(lab.shape, "willot2015"), np.complex64, threads)
    tab = np.array([2.25, -50 + 20j])
    e0 = np.eye(3)[0]
    a = np.ones((3,) + lab.shape, np.complex64)
    k = 8

    def ours():  # k COCG iterations (set-up, right-hand side and flux subtracted below)
        return solve_cocg(prob, tab, e0, tol=1e-30, maxiter=2 + k)

    def base():
        return solve_cocg(prob, tab, e0, tol=1e-30, maxiter=2)

    def rival():  # k bare FFT pairs of the 3-component field, in place
        nonlocal a
        for _ in range(k):
            b = scipy.fft.fftn(a, axes=(1, 2, 3), workers=threads, overwrite_x=True)
            a = scipy.fft.ifftn(b, axes=(1, 2, 3), workers=threads, overwrite_x=True)

    def check():  # the same Γ both ways: the rank-one stencil form against the dense projection
        f = prob.field()
        f[...] = np.random.default_rng(0).normal(size=f.shape)
        g = scipy.fft.fftn(f.reshape((3,) + lab.shape).astype(complex), axes=(1, 2, 3))
        k_ = prob.op.symbol()
        s_ = np.sum(np.conj(k_) * g, axis=0) / np.maximum(np.sum(np.abs(k_) ** 2, axis=0), 1e-300)
        ref = scipy.fft.ifftn(k_ * s_, axes=(1, 2, 3)).reshape(3, -1)
        err = np.abs(prob.project_inplace(f) - ref).max() / np.abs(ref).max()
        s = np.ones(lab.shape, np.complex64)
        own = []
        for _ in range(5):  # the iteration's own FFTs: one scalar field forward and back, k times
            t0 = time.perf_counter()
            for _ in range(k):
                s = scipy.fft.ifftn(scipy.fft.fftn(s, workers=threads, overwrite_x=True), workers=threads,
                                    overwrite_x=True)
            own.append((time.perf_counter() - t0) / k)
        return (f"Γ vs dense k kᴴ/|k|²: {err:.1e}; iteration = (run(2+8) − run(2)) / 8; its own 2 scalar "
                f"FFTs {1e3 * float(np.median(own)):.3g} ms")

    return f"FFT solver: 1 COCG iteration (1 FFT + 1 inverse of a scalar), {n}³ complex64", n**3, (ours, base, k), \
        [("floor: bare FFT pair (scipy.fft)", rival)], check


def case_brdf(scale, threads):
    import numpy as np

    from nmmm.appearance.brdf import metallic_paint

    rng = np.random.default_rng(0)
    npair = int(200_000 * scale)
    w = np.linspace(380.0, 780.0, 81)

    def dirs():
        v = rng.normal(size=(npair, 3))
        v[:, 2] = np.abs(v[:, 2])
        return v / np.linalg.norm(v, axis=1, keepdims=True)

    wi, wo = dirs(), dirs()
    b = metallic_paint()
    b.prepare(w)
    n = np.full(w.size, 1.5)[None, :]

    def ours():
        return b(w, wi, wo, dtype=np.float32)

    def fresnel(mu):  # unpolarised Fresnel of air → n at cos θ = mu, (pairs, λ), float32
        mu = mu.astype(np.float32)[:, None]
        s2 = 1 - mu * mu
        ct = np.sqrt(1 - s2 / (n * n)).astype(np.float32)
        rs = (mu - n * ct) / (mu + n * ct)
        rp = (n * mu - ct) / (n * mu + ct)
        return 0.5 * (rs * rs + rp * rp)

    def rival():  # the coat's Fresnel factors alone, coat in and out, vectorised NumPy
        return fresnel(wi[:, 2]) * fresnel(wo[:, 2])

    def check():
        return "floor covers 2 of the BRDF's factors only"

    return f"metallic paint BRDF {npair} pairs × 81 λ", npair * w.size, ours, \
        [("floor: coat Fresnel in/out in NumPy", rival)], check


def case_render(scale, threads):
    sys.path.insert(0, str(HERE))
    from bench_render import per_pixel_pair

    res = (1024, 683) if scale == 1 else (512, 341)
    ours, rival, n = per_pixel_pair(res)  # the whole image / the fused BRDF kernel alone, same pixel pairs

    def check():
        return f"{n / 1e6:.1f} M evaluations per image; ratio = share of the kernel's rate the path keeps"

    return f"plate render per-pixel path {res[0]}×{res[1]} × 81 λ (metallic BRDF)", n, ours, \
        [("floor: nmmm's BRDF kernel alone, same pixel pairs (the issue's measure)", rival)], check


CASES = {
    "mie": case_mie, "mie1": case_mie_single, "thinfilm": case_thinfilm, "ad": case_adding_doubling,
    "colour": case_colour, "mg": case_maxwell_garnett, "bruggeman": case_bruggeman, "looyenga": case_looyenga,
    "boolean": case_boolean, "fft": case_fft_iteration, "brdf": case_brdf, "render": case_render,
}


# --------------------------------------------------------------------------------------
# worker: one process per thread count
# --------------------------------------------------------------------------------------

def _timings(ours, rivals, repeat):
    """Median seconds of nmmm and of each rival, timed in alternation (each repeat times all
    of them, so a change of machine load hits both), the order rotated by one each repeat so
    that each callable follows each other one equally often: a BLAS call leaves OpenBLAS's
    worker spinning for a while, which slowed whatever ran right after the NumPy floor (at 2
    threads nmmm's CIELAB took 58 ms alone, 104-116 ms right after ``R @ W``). For the FFT
    case ``ours`` is (run of 2 + k iterations, run of 2, k): per-iteration difference, rival
    divided by k."""
    import statistics

    fft = isinstance(ours, tuple)
    fns = [ours[0], ours[1]] if fft else [ours]
    fns += [f for _, f in rivals]
    for f in fns:
        f()  # compile, fill caches, plan FFTs
    ts = [[] for _ in fns]
    for r in range(repeat):
        for j in range(len(fns)):
            i = (j + r) % len(fns)
            t = time.perf_counter()
            fns[i]()
            ts[i].append(time.perf_counter() - t)
    med = [statistics.median(t) for t in ts]
    if fft:
        k = ours[2]
        return max(med[0] - med[1], 1e-9) / k, [m / k for m in med[2:]]
    return med[0], med[1:]


def worker(threads, names, repeat):
    import math

    rows = []
    for name in names:
        t0 = time.perf_counter()
        try:
            work, count, ours, rivals, check = CASES[name](1, threads)
            agree = check()
            t_ours, t_r = _timings(ours, rivals, repeat)
            t_riv = [(rn, t) for (rn, _), t in zip(rivals, t_r)]
            expo = None
            if name != "mie1":
                _, c4, o4, r4, _ = CASES[name](0.25, threads)
                t4, _ = _timings(o4, [], repeat)
                expo = math.log(t_ours / t4) / math.log(count / c4)
            rows.append(dict(name=name, work=work, nmmm=t_ours, rivals=t_riv, exponent=expo, agree=agree))
        except Exception as exc:  # a missing optional library: say so in the table
            rows.append(dict(name=name, work=name, error=f"{type(exc).__name__}: {exc}"[:160]))
        print(f"  [{threads} thread(s)] {name}: {time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
    return rows


def _fmt(t):
    return f"{t * 1e3:.3g} ms" if t < 1 else f"{t:.3g} s"


def table(results, load):
    lines = [f"Load average at start/end: {load[0]} / {load[1]} (2-core machine shared with other jobs).", "",
             "| kernel / work | threads | nmmm | rival (best a user could do instead) | rival time | ratio | "
             "exponent | agreement |", "|---|---|---|---|---|---|---|---|"]
    names = [r["name"] for r in results[min(results)]]
    for i, _ in enumerate(names):
        for th in sorted(results):
            r = results[th][i]
            if "error" in r:
                lines.append(f"| {r['work']} | {th} | – | not run: {r['error']} | | | | |")
                continue
            for j, (rn, rt) in enumerate(r["rivals"]):
                head = f"| {r['work']} | {th} | {_fmt(r['nmmm'])} |" if j == 0 else "| ″ | ″ | ″ |"
                expo = "" if r["exponent"] is None or j else f"{r['exponent']:.2f}"
                lines.append(f"{head} {rn} | {_fmt(rt)} | {rt / r['nmmm']:.2f} | {expo} | "
                             f"{r['agree'] if j == 0 else ''} |")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--only", nargs="+", choices=sorted(CASES), default=list(CASES))
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--out", default=str(HERE / "RESULTS.md"))
    ap.add_argument("--worker", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--json", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        Path(args.json).write_text(json.dumps(worker(args.worker, args.only, args.repeat)))
        return 0
    load0 = " ".join(f"{x:.1f}" for x in os.getloadavg())
    results = {}
    for th in args.threads:
        env = dict(os.environ, NUMBA_NUM_THREADS=str(th), OMP_NUM_THREADS=str(th),
                   OPENBLAS_NUM_THREADS=str(th), MKL_NUM_THREADS=str(th), MIEPYTHON_USE_JIT="1")
        with tempfile.TemporaryDirectory() as tmp:
            js = Path(tmp) / "rows.json"
            subprocess.run([sys.executable, __file__, "--worker", str(th), "--json", str(js),
                            "--repeat", str(args.repeat), "--only", *args.only], env=env, check=True)
            results[th] = json.loads(js.read_text())
    load1 = " ".join(f"{x:.1f}" for x in os.getloadavg())
    text = table(results, (load0, load1))
    print(text)
    if set(args.only) == set(CASES):
        stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
        Path(args.out).write_text(
            f"# nmmm against the best alternative, equal threads ({stamp})\n\n"
            "Written by `python benchmarks/run_all.py` (see its docstring for the method). "
            "ratio = rival time / nmmm time; medians of repeats; exponent = slope of log time "
            "against log work (1/4 size to full size).\n\n" + text + "\n")
        print(f"\nwritten to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
