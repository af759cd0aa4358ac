"""A 3-colourant match: nmmm.matching.match_recipe against a plain scipy least-squares (issue 17, Speed).

The case: the shipped hematite tint at 8 µm over white with a third colourant (a black, n 1.9 + 0.6i,
60 nm), three free fractions (hematite 0.005–0.08, rutile 0.02–0.25, black 0–0.02); the target is the
adding–doubling spectrum at (0.021, 0.15, 0.006) — the recipe of tests/matching/test_match.py.

- nmmm: :func:`nmmm.matching.match_recipe`, colorimetric and spectral modes (colorimetric: ΔE00 residual + 0.1 × spectral residual
  under D65; Kubelka–Munk stage from two starts, then adding–doubling with the quadrature pinned),
  followed by its final spectrum and standard errors, all counted.
- rival: the plain way, ``scipy.optimize.least_squares`` (trf, default tolerances and step) on the
  same residual (per mode), the same forward model called directly with adding–doubling (the automatic
  quadrature rule at every call, as ``nmmm run`` computes), no KM start, from the middle of the same
  bounds.

Both use the same :class:`~nmmm.matching.RecipeModel` (per-component Mie optics computed once, so the
forward model is the adding–doubling film model); model evaluations are counted by solver. Both run
in one process at the thread count given (NUMBA/OMP/OPENBLAS/MKL_NUM_THREADS set before numpy is
imported), alternately, after one warm-up run each; the table shows medians of ``--repeat`` runs.
ratio = rival / nmmm (> 1: nmmm faster or fewer evaluations). Nothing here is asserted on time.

Usage: ``python benchmarks/bench_matching.py [--repeat 5] [--threads 2] [--step-nm 20] [--mode both] [--json]``
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
    ap.add_argument("--json", action="store_true", help="print the result as JSON")
    return ap.parse_args(argv)


TRUE = (0.021, 0.15, 0.006)
FREE = ["pigments.0.fraction=0.005:0.08", "pigments.1.fraction=0.02:0.25", "pigments.2.fraction=0:0.02"]


def model_and_target(step_nm: float = 20.0):
    """The 3-colourant RecipeModel and its adding–doubling target spectrum at :data:`TRUE`."""
    import numpy as np

    from nmmm.matching import RecipeModel
    from nmmm.recipes.schema import example_path, read_toml, set_key

    raw, _, _ = read_toml(example_path("hematite_tint"))
    raw = set_key(raw, "film.thickness_nm", 8000.0)
    raw = set_key(raw, "spectral.step_nm", float(step_nm))
    raw["compounds"]["black"] = {"n": 1.9, "k": 0.6}
    raw["pigments"].append({"compound": "black", "fraction": 0.004, "diameter_nm": 60})
    m = RecipeModel(raw, FREE)
    return m, m.reflectance(np.array(TRUE), "ad")


def run_nmmm(m, target, mode: str = "colorimetric") -> dict:
    """One nmmm match: wall time, model evaluations (all solvers), final ΔE00, fitted fractions."""
    import time

    from nmmm.matching import match_recipe

    m.evaluations = {}
    t0 = time.perf_counter()
    res = match_recipe(m, target, mode=mode)
    wall = time.perf_counter() - t0
    return dict(wall_s=wall, evaluations=sum(m.evaluations.values()), by_solver=dict(m.evaluations),
                de00=res.de00, values=[float(v) for v in res.values.values()])


def run_plain(m, target, mode: str = "colorimetric") -> dict:
    """One plain scipy least_squares on the same residual and forward model (adding–doubling only)."""
    import time

    import numpy as np
    from scipy.optimize import least_squares

    from nmmm.colour import delta_e2000, spectra_to_lab
    from nmmm.matching.metamerism import delta_e2000_residuals

    w = m.wavelength_nm
    lo = np.array([b.lo for b in m.bounds])
    hi = np.array([b.hi for b in m.bounds])
    lab_t = spectra_to_lab(w, target, "D65")

    def residuals(x):
        R = m.reflectance(x, "ad", None)
        if mode == "spectral":
            return (R - target) * 100 / np.sqrt(w.size)
        lab = spectra_to_lab(w, np.clip(R, 0, None), "D65")
        return np.concatenate([delta_e2000_residuals(lab_t, lab), 0.1 * (R - target) * 100 / np.sqrt(w.size)])

    m.evaluations = {}
    t0 = time.perf_counter()
    r = least_squares(residuals, 0.5 * (lo + hi), bounds=(lo, hi), method="trf")
    R = m.reflectance(r.x, "ad", None)
    de = float(delta_e2000(lab_t, spectra_to_lab(w, np.clip(R, 0, None), "D65")))
    wall = time.perf_counter() - t0
    return dict(wall_s=wall, evaluations=sum(m.evaluations.values()), by_solver=dict(m.evaluations), de00=de,
                values=[float(v) for v in r.x], status=int(r.status))


def benchmark(repeat: int = 5, step_nm: float = 20.0, mode: str = "colorimetric") -> dict:
    """Warm-up, then nmmm and the plain fit alternately ``repeat`` times; medians and ratios."""
    import numpy as np

    m, target = model_and_target(step_nm)
    run_nmmm(m, target, mode), run_plain(m, target, mode)  # warm-up: Numba compilation, caches
    runs = {"nmmm": [], "plain": []}
    for _ in range(repeat):
        runs["nmmm"].append(run_nmmm(m, target, mode))
        runs["plain"].append(run_plain(m, target, mode))
    med = {k: {q: float(np.median([r[q] for r in v])) for q in ("wall_s", "evaluations", "de00")}
           for k, v in runs.items()}
    ratio = {q: (med["plain"][q] / med["nmmm"][q] if med["nmmm"][q] > 0 else float("inf"))
             for q in ("wall_s", "evaluations", "de00")}
    return dict(case=f"3-colourant {mode} match, {m.wavelength_nm.size} wavelengths", true=list(TRUE),
                repeat=repeat, threads=os.environ.get("NUMBA_NUM_THREADS"), median=med, ratio=ratio,
                last={k: v[-1] for k, v in runs.items()}, load_average=list(os.getloadavg()))


def main(argv=None):
    args = _args(argv)
    import warnings

    warnings.simplefilter("ignore")
    modes = ["colorimetric", "spectral"] if args.mode == "both" else [args.mode]
    outs = [benchmark(args.repeat, args.step_nm, mode) for mode in modes]
    if args.json:
        import json

        print(json.dumps(outs, indent=1))
        return
    for out in outs:
        _print(out, args)


def _print(out: dict, args) -> None:
    med, ratio = out["median"], out["ratio"]
    print(f"{out['case']}, threads {out['threads']}, medians of {args.repeat} (load {out['load_average'][0]:.1f})")
    print(f"{'':24s}{'wall':>10s}{'model evals':>14s}{'final dE00':>14s}")
    for k, label in (("nmmm", "nmmm match_recipe"), ("plain", "plain least_squares")):
        print(f"{label:24s}{med[k]['wall_s']:9.2f}s{med[k]['evaluations']:14.0f}{med[k]['de00']:14.2e}")
    print(f"{'ratio plain / nmmm':24s}{ratio['wall_s']:10.2f}{ratio['evaluations']:14.2f}{ratio['de00']:14.3g}")
    print(f"nmmm evaluations by solver: {out['last']['nmmm']['by_solver']}; fractions "
          f"nmmm {[round(v, 5) for v in out['last']['nmmm']['values']]}, plain "
          f"{[round(v, 5) for v in out['last']['plain']['values']]} (true {list(TRUE)})")


if __name__ == "__main__":
    # the thread count before numpy / Numba are imported (only here: changing it in a process whose
    # Numba threads run already is refused)
    _n = str(_args(sys.argv[1:]).threads)
    for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[_var] = _n
    main()
