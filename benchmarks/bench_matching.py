"""A 3- or 4-colourant match: nmmm.matching.match_recipe against plain scipy least-squares (issue 17, Speed).

The case: the shipped hematite tint at 8 µm over white with a third colourant (a black, n 1.9 + 0.6i,
60 nm), three free fractions (hematite 0.005–0.08, rutile 0.02–0.25, black 0–0.02); the target is the
adding–doubling spectrum at (0.021, 0.15, 0.006) — the recipe of tests/matching/test_match.py.
``--colourants 4`` adds gold nanospheres (40 nm, 0–0.002, true 0.0008; tests/matching/test_match_acceptance.py).

What is timed, per mode (colorimetric: ΔE00 residual + 0.1 × spectral residual under D65; spectral):

- nmmm: one :func:`nmmm.matching.match_recipe` call as a user makes it — Kubelka–Munk fits from two
  starts (cheap: the Mie optics of each colourant once, then KM algebra), the quasi-Newton finish on
  adding–doubling started from the KM Jacobian, the final spectrum, the standard errors (n more
  adding–doubling evaluations), the shares and the total's profile interval (8 more) and the
  metamerism indices.
- plain: ``scipy.optimize.least_squares`` (trf, default tolerances and step) on the same residual and
  the same forward model called directly with adding–doubling (the automatic quadrature rule at every
  call, as ``nmmm run`` computes; CIELAB by the same once-computed E308 weights as nmmm's residual),
  no KM start, from the middle of the same bounds, then one final spectrum. Its evaluation count moves with rounding (41–81 seen for the same case: the default
  finite-difference step is 1.5e-8).
- plain-stopped: the same, stopped at the same residual norm as nmmm (1e-5: ΔE00 or % RMS), as a
  user who knows when to stop would write it.

All use the same :class:`~nmmm.matching.RecipeModel` (per-component Mie optics computed once); model
evaluations are counted by solver (``ad``: adding–doubling, ~8 ms each here; ``km``: Kubelka–Munk,
~0.3 ms). All run in one process at the thread count given (NUMBA/OMP/OPENBLAS/MKL_NUM_THREADS set before
numpy is imported), alternately, after one warm-up run each; medians of ``--repeat`` runs.
ratio = rival / nmmm (> 1: nmmm faster or fewer evaluations). Nothing here is asserted on time.

Usage: ``python benchmarks/bench_matching.py [--repeat 5] [--threads 2] [--step-nm 20] [--mode both]
[--colourants 3|4] [--json]``
"""

from __future__ import annotations

import argparse
import os
import sys


def _args(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--step-nm", type=float, default=20.0)
    ap.add_argument("--mode", choices=["colorimetric", "spectral", "both"], default="both")
    ap.add_argument("--colourants", type=int, choices=[3, 4], default=3)
    ap.add_argument("--json", action="store_true", help="print the result as JSON")
    return ap.parse_args(argv)


TRUE = (0.021, 0.15, 0.006)
FREE = ["pigments.0.fraction=0.005:0.08", "pigments.1.fraction=0.02:0.25", "pigments.2.fraction=0:0.02"]
#: the 4-colourant case adds gold nanospheres (Johnson & Christy, 40 nm: a green-absorbing plasmon band)
TRUE4 = TRUE + (0.0008,)
FREE4 = FREE + ["pigments.3.fraction=0:0.002"]


def model_and_target(step_nm: float = 20.0, colourants: int = 3):
    """The 3- (or 4-) colourant RecipeModel and its adding–doubling target spectrum at :data:`TRUE`
    (:data:`TRUE4`)."""
    import numpy as np

    from nmmm.matching import RecipeModel
    from nmmm.recipes.schema import example_path, read_toml, set_key

    raw, _, _ = read_toml(example_path("hematite_tint"))
    raw = set_key(raw, "film.thickness_nm", 8000.0)
    raw = set_key(raw, "spectral.step_nm", float(step_nm))
    raw["compounds"]["black"] = {"n": 1.9, "k": 0.6}
    raw["pigments"].append({"compound": "black", "fraction": 0.004, "diameter_nm": 60})
    if colourants == 4:
        raw["compounds"]["gold"] = {"database": "main/Au/Johnson"}
        raw["pigments"].append({"compound": "gold", "fraction": 0.0005, "diameter_nm": 40})
    elif colourants != 3:
        raise ValueError("colourants: 3 or 4")
    m = RecipeModel(raw, FREE4 if colourants == 4 else FREE)
    return m, m.reflectance(np.array(TRUE4 if colourants == 4 else TRUE), "ad")


def run_nmmm(m, target, mode: str = "colorimetric") -> dict:
    """One nmmm match: wall time, model evaluations (all solvers), final ΔE00, fitted fractions."""
    import time

    from nmmm.matching import match_recipe

    m.evaluations = {}
    t0 = time.perf_counter()
    res = match_recipe(m, target, mode=mode)
    wall = time.perf_counter() - t0
    return dict(wall_s=wall, evaluations=sum(m.evaluations.values()), ad_evaluations=m.evaluations.get("ad", 0),
                by_solver=dict(m.evaluations), de00=res.de00, values=[float(v) for v in res.values.values()])


def run_plain(m, target, mode: str = "colorimetric", stop_norm: float | None = None) -> dict:
    """One plain scipy least_squares on the same residual and forward model (adding–doubling only);
    ``stop_norm``: stop once the residual norm is below it (as match_recipe does)."""
    import time

    import numpy as np
    from scipy.optimize import least_squares

    from nmmm.colour import delta_e2000, spectra_to_lab
    from nmmm.matching.metamerism import delta_e2000_residuals
    from nmmm.matching.recipe_match import _lab_function

    w = m.wavelength_nm
    lo = np.array([b.lo for b in m.bounds])
    hi = np.array([b.hi for b in m.bounds])
    lab_t = spectra_to_lab(w, target, "D65")
    lab_of = _lab_function(w, "D65", "2")  # the CIELAB weights once, as nmmm's residual has them

    def residuals(x):
        R = m.reflectance(x, "ad", None)
        if mode == "spectral":
            return (R - target) * 100 / np.sqrt(w.size)
        lab = lab_of(R)
        return np.concatenate([delta_e2000_residuals(lab_t, lab), 0.1 * (R - target) * 100 / np.sqrt(w.size)])

    class _Stop(Exception):
        pass

    def stopping(x):
        r = residuals(x)
        if stop_norm is not None and float(np.linalg.norm(r)) < stop_norm:
            raise _Stop(np.array(x, float))
        return r

    m.evaluations = {}
    t0 = time.perf_counter()
    try:
        r = least_squares(stopping, 0.5 * (lo + hi), bounds=(lo, hi), method="trf")
        x, status = r.x, int(r.status)
    except _Stop as stop:
        x, status = stop.args[0], 5
    R = m.reflectance(x, "ad", None)
    de = float(delta_e2000(lab_t, spectra_to_lab(w, np.clip(R, 0, None), "D65")))
    wall = time.perf_counter() - t0
    return dict(wall_s=wall, evaluations=sum(m.evaluations.values()), ad_evaluations=m.evaluations.get("ad", 0),
                by_solver=dict(m.evaluations), de00=de, values=[float(v) for v in x], status=status)


def benchmark(repeat: int = 5, step_nm: float = 20.0, mode: str = "colorimetric", colourants: int = 3) -> dict:
    """Warm-up, then nmmm and the plain fits alternately ``repeat`` times; medians and ratios."""
    import numpy as np

    m, target = model_and_target(step_nm, colourants)
    who = {"nmmm": lambda: run_nmmm(m, target, mode), "plain": lambda: run_plain(m, target, mode),
           "plain-stopped": lambda: run_plain(m, target, mode, stop_norm=1e-5)}
    for f in who.values():  # warm-up: Numba compilation, caches
        f()
    runs = {k: [] for k in who}
    for _ in range(repeat):
        for k, f in who.items():
            runs[k].append(f())
    qs = ("wall_s", "evaluations", "ad_evaluations", "de00")
    med = {k: {q: float(np.median([r[q] for r in v])) for q in qs} for k, v in runs.items()}
    ratio = {q: (med["plain"][q] / med["nmmm"][q] if med["nmmm"][q] > 0 else float("inf")) for q in qs}
    ratio_stopped = {q: (med["plain-stopped"][q] / med["nmmm"][q] if med["nmmm"][q] > 0 else float("inf")) for q in qs}
    return dict(case=f"{colourants}-colourant {mode} match, {m.wavelength_nm.size} wavelengths",
                true=list(TRUE4 if colourants == 4 else TRUE),
                repeat=repeat, threads=os.environ.get("NUMBA_NUM_THREADS"), median=med, ratio=ratio,
                ratio_stopped=ratio_stopped,
                last={k: v[-1] for k, v in runs.items()}, load_average=list(os.getloadavg()))


def main(argv=None):
    args = _args(argv)
    import warnings

    warnings.simplefilter("ignore")
    modes = ["colorimetric", "spectral"] if args.mode == "both" else [args.mode]
    outs = [benchmark(args.repeat, args.step_nm, mode, args.colourants) for mode in modes]
    if args.json:
        import json

        print(json.dumps(outs, indent=1))
        return
    for out in outs:
        _print(out, args)


def _print(out: dict, args) -> None:
    med = out["median"]
    print(f"{out['case']}, threads {out['threads']}, medians of {args.repeat} (load {out['load_average'][0]:.1f})")
    print(f"{'':26s}{'wall':>9s}{'AD evals':>10s}{'all evals':>11s}{'final dE00':>12s}")
    for k, label in (("nmmm", "nmmm match_recipe"), ("plain", "plain least_squares"),
                     ("plain-stopped", "plain, stopped at 1e-5")):
        m = med[k]
        print(f"{label:26s}{m['wall_s']:8.3f}s{m['ad_evaluations']:10.0f}{m['evaluations']:11.0f}{m['de00']:12.2e}")
    for key, label in (("ratio", "ratio plain / nmmm"), ("ratio_stopped", "ratio stopped / nmmm")):
        r = out[key]
        print(f"{label:26s}{r['wall_s']:9.2f}{r['ad_evaluations']:10.2f}{r['evaluations']:11.2f}")
    last = out["last"]
    print(f"nmmm evaluations by solver: {last['nmmm']['by_solver']}; fractions nmmm "
          f"{[round(v, 5) for v in last['nmmm']['values']]}, plain {[round(v, 5) for v in last['plain']['values']]}, "
          f"stopped {[round(v, 5) for v in last['plain-stopped']['values']]} (true {out['true']})")


if __name__ == "__main__":
    # the thread count before numpy / Numba are imported (only here: changing it in a process whose
    # Numba threads run already is refused)
    _n = str(_args(sys.argv[1:]).threads)
    for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[_var] = _n
    main()
