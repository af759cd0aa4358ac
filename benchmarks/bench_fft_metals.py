"""Convergence of the FFT solver's defaults on metal-dielectric cells (issue 22 item 4).

For each cell (Boolean spheres, hard-core spheres, metal platelets "flakes"), grid and metal
permittivity in a dielectric of ε = 2.25, the script runs ``fft_permittivity`` with its
defaults (``green=None``: automatic operator, COCG, fallbacks on), complex64 asked, tol 1e-5,
one loading (x), and prints one table row: operator used, every automatic switch (including
the promotion to complex128 that ``green=None`` makes for low-loss metals, where complex64
stalls above 1e-5), the rule the solve converged on (``stop="auto"``: the residual, or COCG's flux
rule with its estimated error of ε_xx and the bound on the column's off-diagonal terms) and the
relative residual reached, projections, wall time and ε_xx. ``--true-residual`` also forms the field the
solve stopped at (a second solve) and prints ‖b − A x‖ / ‖b‖; ``--reference`` solves to a residual of
1e-9 (complex128, same operator, no stall check) and prints ε_xx's relative error against it. With
``--compare`` it also runs COCG with each Willot operator fixed (no fallback) to show what the
automatic choice is choosing between.

Usage::

    python benchmarks/bench_fft_metals.py                       # 64³, all cells and metals
    python benchmarks/bench_fft_metals.py --grids 64 128        # also 128³ (≈ 1-3 min per row)
    python benchmarks/bench_fft_metals.py --grids 64 --maxiter 500 --true-residual --reference
    python benchmarks/bench_fft_metals.py --stop residual      # the residual rule only
    python benchmarks/bench_fft_metals.py --compare --cases boolean --eps=-50+2j
    python benchmarks/bench_fft_metals.py --spectrum 64         # aluminium (Rakić), 81 λ, warm starts
    python benchmarks/bench_fft_metals.py --spectrum 64 --scheduler local   # the same on 2 Dask workers
    python benchmarks/bench_fft_metals.py --speedup 64 --n-wavelengths 16   # 1 process vs 2 Dask workers
    python benchmarks/bench_fft_metals.py --spectrum 128 --lanczos --spectrum-loadings 0   # one Lanczos run
    python benchmarks/bench_fft_metals.py --spectrum 64 --spectrum-loadings 0 --method auto   # what the API chooses

Cells: Boolean spheres p = 0.2, radius 5 voxels at 64³ (scaled with the grid); hard-core (RSA)
spheres p = 0.2, same radius; flakes: discs of radius n/6, 2 voxels thick, lying flat, ~10 %.
The machine's cores are shared: times are wall times of this run, iteration counts are not
affected by the load.

What the default path does (issue 22): ``green=None`` takes willot2014 and complex128 for a 3-D cell
with a low-loss metal (reported); a COCG whose residual, extrapolated from the last half of its
history, would need more than 5 × maxiter projections is stopped from 0.6 × maxiter (at least 150)
projections on (``fft.PREDICT``; the 128³ rows below were measured with checks from 150 on) and COCG with the other Willot operator takes over (reported with the projections
run, the residual reached and the prediction); BiCGStab/GMRES are not tried after such a stop (they
measured worse there, below). Over several wavelengths a two-phase cell without a low-loss metal is
solved by one Lanczos run per loading when estimated cheaper (``method="auto"``, reported).
Without local fields (this script asks none) COCG also converges when the estimated relative error of
ε_xx is ≤ tol (``stop="auto"``, the flux rule of ``solvers.solve_cocg``: ε_xx as COCG's Gauss
quadrature of bᵀA⁻¹b, its error estimated by its path over the last 30 projections; reported).

Measured, session 9 (2026-12-05, load 1-2.4 on 2 cores, the 2-FFT iteration of 0a2798a; defaults, complex64 asked, tol 1e-5, x)
--------------------------------------------------------------------------------------------------------------------
81-λ aluminium (Rakić, 380-780 nm) on the 128³ flake cell, 3 loadings, complex64, tol 1e-5, what the
API chooses (``--spectrum 128 --method auto``, load 1.0-1.7): one Lanczos run per loading (83-216 steps),
160 s of solve, 2 min 41 s in all with the cell and the table (session 5: 12.4 min with the 4-FFT
iteration, load 4-10; target 30 min); ε_xx −0.2304+1.3806i at 380 nm, −1.7312+6.0517i at 580 nm.

``--grids 64 128 --maxiter 500 --reference`` (64³ also ``--true-residual``: equal to the residual
reached to 2 digits in every row). "error" is ε_xx's relative error against COCG run to a residual of
1e-9 (complex128, same operator); "session 5" the projections of the residual rule, below:

| cell | grid | ε metal | operator | converged on | residual reached | projections (session 5) | time (s) | error |
|---|---|---|---|---|---|---|---|---|
| boolean (0.20) | 64³ | −50+1i | willot2014 c128 | residual | 9.5e-6 | 304 (304) | 2.0 | 1.3e-7 |
| boolean (0.20) | 64³ | −50+2i | willot2014 c128 | residual | 9.9e-6 | 293 (293) | 1.6 | 3.0e-8 |
| boolean (0.20) | 64³ | −50+5i | willot2014 c128 | flux (est. 9e-6) | 1.4e-4 | 263 (276) | 1.6 | 3.1e-8 |
| boolean (0.20) | 64³ | −44+13i | willot2015 c64 | flux (est. 9e-6) | 1.3e-4 | 134 (181) | 0.6 | 2.7e-7 |
| hardcore (0.20) | 64³ | −50+1i | willot2014 c128 | flux (est. 1e-5) | 3.1e-4 | 114 (118) | 0.7 | 2.0e-8 |
| hardcore (0.20) | 64³ | −50+2i | willot2014 c128 | flux (est. 8e-6) | 1.7e-4 | 114 (117) | 0.7 | 1.1e-8 |
| hardcore (0.20) | 64³ | −50+5i | willot2014 c128 | flux (est. 9e-6) | 8.5e-5 | 107 (111) | 0.6 | 6.3e-9 |
| hardcore (0.20) | 64³ | −44+13i | willot2015 c64 | flux (est. 9e-6) | 1.1e-4 | 116 (154) | 0.5 | 1.7e-7 |
| flakes (0.10) | 64³ | −50+1i | willot2014 c128 | flux (est. 8e-6) | 1.9e-4 | 431 (498) | 2.3 | 6.3e-8 |
| flakes (0.10) | 64³ | −50+2i | willot2014 c128 | flux (est. 9e-6) | 5.3e-4 | 368 (431) | 2.0 | 2.0e-7 |
| flakes (0.10) | 64³ | −50+5i | willot2014 c128 | flux (est. 1e-5) | 7.7e-4 | 242 (291) | 1.4 | 3.0e-8 |
| flakes (0.10) | 64³ | −44+13i | willot2015 c64 | flux (est. 9e-6) | 3.1e-4 | 131 (199) | 0.5 | 4.2e-7 |
| boolean (0.20) | 128³ | −50+1i | willot2014 c128 | residual | 9.5e-6 | 266 | 14.4 | 1.2e-7 |
| boolean (0.20) | 128³ | −50+2i | willot2014 c128 | residual | 9.1e-6 | 254 | 12.7 | 1.2e-7 |
| boolean (0.20) | 128³ | −50+5i | willot2014 c128 | flux (est. 8e-6) | 1.6e-5 | 219 | 10.9 | 5.3e-9 |
| boolean (0.20) | 128³ | −44+13i | willot2015 c64 | flux (est. 9e-6) | 1.3e-4 | 135 | 4.5 | 2.8e-7 |
| hardcore (0.20) | 128³ | −50+1i, 2i, 5i | willot2014 c128 | residual | 8-9e-6 | 71 each | 3.9 | 1.3-1.7e-10 |
| hardcore (0.20) | 128³ | −44+13i | willot2015 c64 | flux (est. 1e-5) | 1.2e-4 | 107 | 3.6 | 5.5e-8 |
| flakes (0.10) | 128³ | −50+5i | willot2014 c128 | flux (est. 1e-5) | 2.0e-3 | 358 (1000: no) | 20.7 | 1.7e-7 |
| flakes (0.10) | 128³ | −50+2i | willot2014 c128 | maxiter 500: both operators to 500 (best 0.028, 0.036), ConvergenceError | - | 1000 | 61.8 | - |
| flakes (0.10) | 128³ | −50+2i | ``--maxiter 2000`` | flux (est. 1e-5) | 1.2e-3 | 816 (1346) | 47.9 | 1.1e-7 |
| flakes (0.10) | 128³ | −50+1i | willot2014 c128 | maxiter 500: both operators to 500 (best 0.26, 0.27), ConvergenceError | - | 1000 | 59.9 | - |
| flakes (0.10) | 128³ | −50+1i | ``--maxiter 2000`` | flux (est. 1e-5) | 1.8e-3 | 1497 (2256*) | 89.3 | 7.1e-7 |
| flakes (0.10) | 128³ | −44+13i | willot2015 c64 | flux (est. 9e-6) | 4.3e-4 | 140 (199) | 5.3 | 2.0e-7 |

(*: the residual rule's count from the replay below.) So item 4 holds for 22 of the 24 cases (≤ 500
projections, ε_xx within 4.2e-7 of the reference, 0.04 tol); 128³ flakes at −50 + 2i and −50 + 1i
still need 816 and 1497 projections (ε_xx then 1.1e-7 and 7.1e-7 off; the near-singular
system above: the flux converges from a residual of 1e-3, not earlier). There the flux's estimate
extrapolates to ~930 and ~2050 at 300 projections (the residual's: 1431 and 5221), inside 5 ×
maxiter, so the solve runs to maxiter (500), the other operator too, and the ConvergenceError names
maxiter ≈ 1.2 × that prediction; with the residual alone −50 + 1i was stopped at 300 on each operator
(600 projections), −50 + 2i ran to 1000 as here. (128³ flakes at −50 + 1i with the residual rule and
its stall check: stopped at 325, "stalled" — the residual sits at 0.5 over 25-325 projections while
the flux's estimate falls; the stall check now also asks the estimate.)

How the flux rule was chosen (``/tmp`` replays of COCG histories run to residual 1e-9, the 24 cases
above on the old 4-FFT iteration, same operators; counts there differ from the table's by rounding,
e.g. 128³ flakes −50 + 1i 1456 vs 1497): true relative error of ε_xx at the projection where
each estimate first says ≤ tol, for tol = 1e-3, 3e-4, ..., 1e-6 (162 stops), as a multiple of tol — the
plain delayed difference |X_k − X_{k−d}| / |X_k| (Strakoš & Tichý 2002) against the path
Σ_{last d} |ΔX| / |X_k| (X: the Gauss quadrature in complex128, the iterate's flux in complex64):

| d | 10 | 20 | 30 | 50 | 100 |
|---|---|---|---|---|---|
| difference: worst (stops above tol) | 41.7 (44) | 11.4 (15) | 10.9 (11) | 6.8 (9) | 7.6 (6) |
| path: worst (stops above tol) | 1.09 (1) | 0.19 (0) | 0.14 (0) | 0.21 (0) | 0.22 (0) |

The difference fails on the 128³ flakes at −50 + 1i, where ε_xx circles its limit (a10 stopped at
855 with a true error of 4.2e-4, a100 at 1067 with 7.6e-5; the path waits until 1456). Plateaus
followed by jumps: the residual has them (128³ flakes −50 + 1i: 0.5 over 25-325 projections, then
0.1 at 840, 0.01 at 1240); the quadrature creeps down, non-monotonically but without a 30-projection
plateau that the path misses (worst 0.14 tol above); the flux of the iterate (error linear in the
residual) oscillates with the residual. On a wider replay (16³-48³ spheres and
flakes, 64²-128² discs, both operators, 10 ε from −50 + 0.5i to 12 + 1i: 298 histories, 7 tol) the
path with d = 20 stopped twice at 1.04 tol (flakes at −50 + 0.5i, willot2015), with d = 30 never above
0.46 tol (1156 stops): FLUX_WINDOW = 30. The quadrature vs the iterate's flux at a residual of 1e-5:
error 2e-11 vs 1e-7 (128³ flakes, −50 + 5i); at −50 + 2i the quadrature is within 1e-5 from 685
projections on, the iterate's flux from 1144. In complex64 the quadrature is biased (5e-5 at 64³,
1.3e-3 at 128³ from the first step), hence the iterate's flux there.

Measured, session 5 (2026-12-04, load 4-7 on 2 cores, defaults, complex64 asked, tol 1e-5, x, maxiter 500)
-----------------------------------------------------------------------------------------------
``python bench_fft_metals.py --grids 64 --maxiter 500`` — every case converges within 500, no
early stop fired (switches: willot2015→willot2014 and complex64→complex128 for the three low-loss
metals, chosen before the solve):

| cell | grid | ε metal | operator | projections | time (s) |
|---|---|---|---|---|---|
| boolean (0.20) | 64³ | −50+1i | willot2014 c128 | 304 | 10.5 |
| boolean (0.20) | 64³ | −50+2i | willot2014 c128 | 293 | 6.5 |
| boolean (0.20) | 64³ | −50+5i | willot2014 c128 | 276 | 7.1 |
| boolean (0.20) | 64³ | −44+13i | willot2015 c64 | 181 | 3.8 |
| hardcore (0.20) | 64³ | −50+1i | willot2014 c128 | 118 | 3.9 |
| hardcore (0.20) | 64³ | −50+2i | willot2014 c128 | 117 | 3.4 |
| hardcore (0.20) | 64³ | −50+5i | willot2014 c128 | 111 | 3.1 |
| hardcore (0.20) | 64³ | −44+13i | willot2015 c64 | 154 | 2.0 |
| flakes (0.10) | 64³ | −50+1i | willot2014 c128 | 498 | 7.1 |
| flakes (0.10) | 64³ | −50+2i | willot2014 c128 | 431 | 9.2 |
| flakes (0.10) | 64³ | −50+5i | willot2014 c128 | 291 | 9.1 |
| flakes (0.10) | 64³ | −44+13i | willot2015 c64 | 199 | 4.3 |

128³ flakes (``--grids 128 --cases flakes --maxiter 500``):

| cell | grid | ε metal | what happened (maxiter 500) | projections | time (s) |
|---|---|---|---|---|---|
| flakes (0.10) | 128³ | −44+13i | willot2015 c64, converged | 199 | 54 |
| flakes (0.10) | 128³ | −50+5i | willot2014 c128 to 500 (best 5.2e-5), then COCG/willot2015 to 500 (7.3e-5): ConvergenceError | 1000 | 360 |
| flakes (0.10) | 128³ | −50+2i | willot2014 c128 to 500 (best 0.028), then COCG/willot2015 to 500 (0.036): ConvergenceError | 1000 | 348 |
| flakes (0.10) | 128³ | −50+1i | predicted slow at 150 on each operator (residual not below 1: ∞): ConvergenceError | 300 | 106 |

So at 128³ the flakes at −50+1..5i are not within 500 (the near-resonant cell, above); the
early stop saves 700 of the 1000 projections at −50+1i and, before this session, BiCGStab and
GMRES would each have added 500 more. At −50+2i the extrapolation at 150-500 stayed under 5 ×
maxiter, so both operators ran to maxiter; COCG/willot2014 left alone (maxiter 2000): converged in 1346
projections (551 s; best residual 0.65 at 150, 0.028 at 500, 3e-4 at 1000), fewer than the 1505 of the
Lanczos run above; its prediction said 2115 at 150, 1627 at 300, 1345 at 500 — so the
ConvergenceError now names maxiter ≈ 1.2 × the prediction (1614 here).

What the switches were measured against (64³ flakes, −50+1i, complex128, 600 projections each,
``SOLVERS`` directly): COCG/willot2014 converges in 495; BiCGStab/willot2014 best residual 0.11;
GMRES(30)/willot2014 0.027 (201 s); COCG/willot2015 0.13. Lanczos (two_phase_spectrum,
no reorthogonalisation) with the same operator: 1284 steps to its estimated 1e-5 and ε_xx 2.3e-3
away from COCG's (whose true residual, from the formed field, is 9.7e-6) — so ``method="auto"``
keeps COCG for low-loss metals; at −44+13i the two agree to 4e-11 in 181 projections each.
The prediction errs long on near-resonant cells (superlinear convergence): 16³ Boolean −50+2i, tol
1e-8, converges in 531 while the extrapolation said 2308 at 150 and 1018 at 300 — hence the margin 5.
The flux converges much faster than the residual: Lanczos on 64³ flakes −50+1i / −50+2i gives
ε_xx within 1.3e-5 / 2.6e-5 of its tol-1e-7 value at a residual of 1e-2, 4.3e-7 at 1e-3.

81-λ aluminium (Rakić) on the 64³ flake cell, x, complex64, tol 1e-5 (``--spectrum 64
--spectrum-loadings 0 --method auto`` / ``per_wavelength``): one Lanczos run 211 projections,
21.6 s (chosen by ``method="auto"``); per-wavelength COCG with warm starts 9336 projections
(64-227 per wavelength), 251 s; ε_xx equal to 4 decimals at 380, 580 and 780 nm.

Measured, session 4 (2026-12-02, load 10-12 on 2 cores, defaults, complex64 asked, tol 1e-5, x)
------------------------------------------------------------------------------------------
| cell | grid | ε metal | operator | projections | time |
|---|---|---|---|---|---|
| flakes (0.10) | 128³ | −44+13i | willot2015 c64 | 200 | 178 s |
| flakes (0.10) | 128³ | −50+5i | willot2014 c128 (switch) | 562 | 898 s |
| flakes (0.10) | 128³ | −50+2i, −50+1i | willot2014 c128 | not finished (> 20 min, killed) | |
Review Q, the same 128³ cell, one real Lanczos run on Γ χ Γ (willot2015, x; its per-shift residual is
COCG's at every ε, two_phase_spectrum): to 1e-5 −44+13i 199, −50+5i 600, −50+2i 1505; −50+1i at
8.7e-4 after 1900 (≈ 3000 at its rate); Al (Rakić) 380 nm 216, 580 nm 180. Projections grow as
1/|Im s|, s = ε_h/(ε_m − ε_h) (|Im s| 1.3e-2, 4.1e-3, 1.6e-3, 8.2e-4): a near-singular system.
(Session 5: "its per-shift residual is COCG's" holds in exact arithmetic only — at 64³ with a
low-loss metal Lanczos took 1.4-2.6× COCG's projections and drifted from it, see above, so
these Lanczos counts overstate COCG's.)
Its Bergman measure of e_x has 27 % of its weight at μ ∈ [0.02, 0.05), largest nodes near 0.03
(ε_res ≈ −73; overlapping discs are wider than one), where −50 + 1..5i put μ_res = 0.043.
Why the 128³ flakes are hard: the flakes here keep 2 voxels of thickness at every grid, so at
128³ (r = 21) they are twice as flat as at 64³. For two phases, Γ ε Γ = ε_h Γ + (ε_m − ε_h) Γ χ Γ
has its eigenvalues on the segment ε_h + (ε_m − ε_h) μ, μ ∈ [0, 1] the spectrum of the real
symmetric Γ χ Γ; it comes within ε_h Im ε_m / |ε_m − ε_h| ≈ 0.04 (−50 + 1i) of zero where
μ ≈ ε_h / (ε_h − ε_m), i.e. at the in-plane plasmon of discs of depolarisation factor
L ≈ π t / 4D ≈ 0.04 (resonance at ε_m ≈ ε_h (1 − 1/L) ≈ −58). A low-loss metal near that
resonance makes any Krylov solver slow (the problem is near-singular, not badly scaled):
no operator or precision switch removes it (the loss or the flake shape does). Real aluminium in the visible (Rakić,
Im ε / |ε| ≥ 0.19) is on the default fast path (willot2015, complex64).

81-λ aluminium (Rakić, 380-780 nm) on the 128³ flake cell, tol 1e-5 (``--spectrum 128 --lanczos``):
two_phase_spectrum, one Lanczos run per loading, took x 216 projections (460 s), y 217 (174 s), and
z 162 (109 s) at load 4-10, 12.4 min in all. COCG with warm starts needs about 124 projections per
wavelength at 128³ (5 wavelengths measured, 0.44 s each), i.e. ≈ 74 min per loading (extrapolated).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings

import numpy as np

from nmmm.errors import ConvergenceError
from nmmm.homogenize import fft_permittivity
from nmmm.homogenize import geometries as G

from bench_homogenize import flakes  # the same flake deposit the homogenize benchmark times (run from benchmarks/)

METALS = (-50 + 1j, -50 + 2j, -50 + 5j, -44 + 13j)
HOST = 2.25


def cell(case: str, n: int) -> np.ndarray:
    radius = 5.0 * n / 64
    if case == "boolean":
        return G.boolean_spheres(n, 0.2, radius, ndim=3, seed=1)
    if case == "hardcore":
        from nmmm.microstructure import hardcore_spheres

        return np.asarray(hardcore_spheres((n, n, n), 1.0, radius, 0.2, seed=1).labels, dtype=np.uint8)
    if case == "flakes":
        return flakes(n)
    raise SystemExit(f"unknown case {case!r}; choose boolean, hardcore, flakes")


def run(lab, eps, **kw):
    t = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            r = fft_permittivity(lab, eps, dtype="complex64", tol=1e-5, directions=[0], progress=False, **kw)
        except ConvergenceError as e:
            its = sum(len(h) - 1 for h in e.history.values())
            return None, its, time.perf_counter() - t, describe_error(e)
    return r, int(np.sum(r.iterations)), time.perf_counter() - t, ""


def describe_stop(r) -> str:
    """How the solve converged: 'residual', or 'flux (est. e, off-diag. o)' for COCG's flux rule, and
    the relative residual reached (the recurrence's; ``true_residual`` forms the field)."""
    stop = str(np.atleast_1d(r.metadata.get("stop", ["residual"]))[0])
    res = float(np.atleast_1d(r.metadata.get("residual_reached", [r.residual_history[-1]]))[0])
    if stop == "flux":
        est = float(np.atleast_1d(r.metadata["flux_error"])[0])
        off = float(np.atleast_1d(r.metadata["offdiagonal_error"])[0])
        return f"flux (est. {est:.1g}, off-diag. {off:.1g}) | {res:.1e}"
    return f"residual | {res:.1e}"


def true_residual(lab, eps, r, tol=1e-5) -> float:
    """‖b − A x‖ / ‖b‖ of the field the default solve stops at, formed: the same COCG (operator,
    precision, flux rule) rerun with the field kept (fft_permittivity forms no field without
    return_fields)."""
    from nmmm.homogenize.fft import _compact_labels
    from nmmm.homogenize.green import green_operator
    from nmmm.homogenize.solvers import FLUX_TOL_MIN, Problem, _norm, solve_cocg

    compact, values, _ = _compact_labels(lab)
    green = str(np.atleast_1d(r.metadata["green_used"])[0])
    prob = Problem(compact, values.size, green_operator(lab.shape, green), np.dtype(r.dtype), 2)
    tab = prob.tab([eps[int(v)] for v in values])
    e0 = np.zeros(lab.ndim)
    e0[0] = 1.0
    flux_tol = tol if tol >= FLUX_TOL_MIN[prob.dtype] else None  # as fft_permittivity gives it
    out = solve_cocg(prob, tab, e0, tol=tol, maxiter=int(np.sum(r.iterations)) + 5, keep_x=True, flux_tol=flux_tol,
                     stall_window=None)
    b = prob.rhs(tab, e0)
    return _norm(b - prob.apply(out.x, tab)) / _norm(b)


def reference_exx(lab, eps, r) -> complex:
    """ε_xx of COCG to a relative residual of 1e-9 (residual rule, no stall check: 128³ flakes at
    −50 + 1i keep a residual of 0.5 over 25-325 projections) with the operator of the default solve,
    in complex128."""
    from nmmm.homogenize.fft import _compact_labels
    from nmmm.homogenize.green import green_operator
    from nmmm.homogenize.solvers import Problem, solve_cocg

    compact, values, _ = _compact_labels(lab)
    green = str(np.atleast_1d(r.metadata["green_used"])[0])
    prob = Problem(compact, values.size, green_operator(lab.shape, green), np.complex128, 2)
    e0 = np.zeros(lab.ndim)
    e0[0] = 1.0
    out = solve_cocg(prob, prob.tab([eps[int(v)] for v in values]), e0, tol=1e-9, maxiter=20000, keep_x=False,
                     stall_window=None)
    if not out.converged:
        raise RuntimeError(f"reference solve: {out.message}")
    return complex(out.flux[0])


def describe_switches(r) -> str:
    """Each automatic switch: from→to, and for a solve stopped early the projections it ran, the
    residual it reached and the projections its extrapolation predicted."""
    out = []
    for s in r.switches:
        where = f" @λ{s['wavelength_index']}" if "wavelength_index" in s else ""
        extra = ""
        if "residual_reached" in s:
            pred = s["predicted_projections"]
            extra = (f" (stopped at {s['projections']}: residual {s['residual_reached']:.2g}, predicted "
                     f"{'∞' if not np.isfinite(pred) else f'{pred:.0f}'})")
        out.append(f"{s['from']}→{s['to']}{where}{extra}")
    return "; ".join(out) or "-"


def describe_error(e) -> str:
    """The attempts of a ConvergenceError: solver@operator: projections, best residual."""
    parts = [f"{k}: {len(h) - 1} proj, best {min(h):.2g}" for k, h in e.history.items()]
    return "no convergence — " + "; ".join(parts)


def table(cases, grids, metals, compare: bool, maxiter: int, stop: str = "auto", check_residual: bool = False,
          reference: bool = False):
    print(f"\n| cell | grid | ε metal | operator | switches | stop={stop}: converged on | residual reached | "
          f"projections | ≤ 500 | time (s) | ε_xx |" + (" true residual |" if check_residual else "")
          + (" error vs ref (tol 1e-9) |" if reference else ""))
    print("|---|---|---|---|---|---|---|---|---|---|---|" + ("---|" if check_residual else "") + ("---|" if reference else ""))
    for n in grids:
        for case in cases:
            lab = cell(case, n)
            frac = float(lab.mean())
            for em in metals:
                eps = {0: HOST, 1: em}
                variants = [("default", {})]
                if compare:
                    variants += [(g, {"green": g, "fallback": False}) for g in ("willot2015", "willot2014")]
                for label, kw in variants:
                    r, its, wall, msg = run(lab, eps, maxiter=maxiter, stop=stop, **kw)
                    if r is None:
                        print(f"| {case} ({frac:.2f}) | {n}³ | {em} | {label} | {msg} | - | - | {its} (all attempts) | no | "
                              f"{wall:.1f} | - |", flush=True)
                        continue
                    op = r.green if label == "default" else label
                    op += " c64" if r.dtype == "complex64" else " c128"
                    extra = ""
                    if check_residual:
                        extra += f" {true_residual(lab, eps, r):.1e} |"
                    if reference:
                        ref = reference_exx(lab, eps, r)
                        extra += f" {abs(r.tensor[0, 0] - ref) / abs(ref):.1e} |"
                    print(f"| {case} ({frac:.2f}) | {n}³ | {em} | {op} | {describe_switches(r)} | {describe_stop(r)} | "
                          f"{its} | {'yes' if its <= 500 else 'no'} | {wall:.1f} | {complex(np.round(r.tensor[0, 0], 6))} |"
                          + extra, flush=True)


def spectrum(n: int, directions, scheduler=None, nwl: int = 81, workers: int = 2, lanczos: bool = False,
             method: str = "per_wavelength"):
    from nmmm.homogenize import fft_permittivity_spectrum, two_phase_spectrum

    w, eps_al = aluminium(nwl)
    lab = flakes(n)
    where = "one process" if not scheduler else ("LocalCluster" if scheduler == "local" else scheduler)
    if lanczos:
        where = "one Lanczos run per loading (two_phase_spectrum, complex128 fields)"
    print(f"\n## Aluminium (Rakić) flakes {n}³ ({lab.mean():.3f}), {nwl} wavelengths 380-780 nm, "
          f"complex64, tol 1e-5, warm starts, loadings {directions}, {where}")
    kw = dict(dtype="complex64", tol=1e-5, directions=directions, max_minutes=float("inf"))
    if not lanczos and not scheduler:
        kw["method"] = method
        where += f", method={method}"
    t = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if lanczos:
            r = two_phase_spectrum(lab, {0: HOST, 1: eps_al}, tol=1e-5, directions=directions)
        elif scheduler:
            r = fft_permittivity_spectrum(lab, {0: HOST, 1: eps_al}, n_workers=workers,
                                          scheduler=None if scheduler == "local" else scheduler, **kw)
        else:
            r = fft_permittivity(lab, {0: HOST, 1: eps_al}, progress=False, **kw)
    wall = time.perf_counter() - t
    its = np.asarray(r.iterations)
    if lanczos or r.metadata.get("method") == "lanczos":  # the run costs its slowest wavelength per loading
        its = np.asarray(r.metadata["projections"])
        print(f"  Lanczos steps at which the wavelengths converged: min {np.min(r.iterations)}, "
              f"max {np.max(r.iterations)}")
    print(f"  total {wall:.1f} s, operator {r.green}, switches: {describe_switches(r)}")
    print(f"  projections per solve: min {its.min()}, median {int(np.median(its))}, max {its.max()}, "
          f"total {its.sum()}; {wall / its.sum() * 1e3:.1f} ms per projection")
    for k in sorted({0, nwl // 2, nwl - 1}):
        print(f"  λ = {w[k]:.0f} nm: ε_Al = {complex(np.round(eps_al[k], 2))}, ε_xx = "
              f"{complex(np.round(r.tensor[k, 0, 0], 4))}")


def aluminium(nwl: int):
    import nmmm.materials as M

    w = np.linspace(380.0, 780.0, nwl)
    return w, M.get("main/Al/Rakic").eps(w)


def speedup(n: int, nwl: int, directions, workers: int):
    """The same Al-flake spectrum (nwl wavelengths, warm starts) in one process with 1 and with
    ``workers`` threads, and on a LocalCluster of ``workers`` single-threaded processes (the
    Dask time includes starting and closing the cluster)."""
    from nmmm.homogenize import fft_permittivity_spectrum

    w, eps_al = aluminium(nwl)
    lab = flakes(n)
    eps = {0: HOST, 1: eps_al}
    kw = dict(dtype="complex64", tol=1e-5, directions=directions, max_minutes=float("inf"))
    print(f"\n## Al flakes {n}³, {nwl} wavelengths, loadings {directions}: one process vs {workers} Dask workers")
    rows = []
    for label, fn in ((f"1 process, 1 thread", lambda: fft_permittivity(lab, eps, workers=1, progress=False, **kw)),
                      (f"1 process, {workers} threads",
                       lambda: fft_permittivity(lab, eps, workers=workers, progress=False, **kw)),
                      (f"LocalCluster {workers} × 1 thread",
                       lambda: fft_permittivity_spectrum(lab, eps, n_workers=workers, **kw))):
        t = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = fn()
        wall = time.perf_counter() - t
        its = np.asarray(r.iterations)
        rows.append((label, wall, int(its.sum())))
        extra = ""
        if "chunks" in r.metadata:
            extra = "; chunks " + ", ".join(f"{a}-{b - 1}: {sec:.1f} s" for a, b, sec in r.metadata["chunks"])
        print(f"  {label:28s} {wall:7.1f} s, projections {its.sum()} (per λ median {int(np.median(its.sum(axis=-1)))})"
              f"{extra}", flush=True)
    base = rows[0][1]
    for label, wall, its in rows[1:]:
        print(f"  speed-up {label} vs 1 process 1 thread: {base / wall:.2f}; vs {rows[1][0]}: {rows[1][1] / wall:.2f}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--grids", type=int, nargs="+", default=[64])
    ap.add_argument("--cases", nargs="+", default=["boolean", "hardcore", "flakes"])
    ap.add_argument("--eps", type=lambda t: [complex(x) for x in t.split(",")], default=list(METALS),
                    help="metal permittivities, comma-separated, e.g. --eps=-50+2j,-44+13j (the '=' keeps argparse "
                         "from reading -50+2j as an option)")
    ap.add_argument("--compare", action="store_true", help="also each Willot operator alone (no fallback)")
    ap.add_argument("--maxiter", type=int, default=2000)
    ap.add_argument("--spectrum", type=int, metavar="N", help="run the 81-λ aluminium flake spectrum at N³")
    ap.add_argument("--spectrum-loadings", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--n-wavelengths", type=int, default=81)
    ap.add_argument("--scheduler", help="'local' (LocalCluster) or tcp://HOST:8786: spread --spectrum over Dask")
    ap.add_argument("--dask-workers", type=int, default=2)
    ap.add_argument("--lanczos", action="store_true", help="--spectrum by two_phase_spectrum (one run per loading)")
    ap.add_argument("--method", default="per_wavelength", choices=["auto", "per_wavelength", "lanczos"],
                    help="--spectrum: fft_permittivity's method= (default per_wavelength, the warm-started solves)")
    ap.add_argument("--speedup", type=int, metavar="N", help="1 process vs --dask-workers Dask workers at N³")
    ap.add_argument("--stop", default="auto", choices=["auto", "residual"],
                    help="fft_permittivity's stop= (auto: COCG's flux rule without fields; residual: the residual only)")
    ap.add_argument("--true-residual", action="store_true",
                    help="also form the field the solve stopped at (a second solve) and print its true residual")
    ap.add_argument("--reference", action="store_true",
                    help="also solve to residual 1e-9 (complex128) and print ε_xx's relative error against it")
    args = ap.parse_args(argv)
    print(f"# FFT homogenization of metal-dielectric cells (load average {os.getloadavg()[0]:.1f}, "
          f"2 workers)")
    if args.speedup:
        speedup(args.speedup, args.n_wavelengths, args.spectrum_loadings, args.dask_workers)
    elif args.spectrum:
        spectrum(args.spectrum, args.spectrum_loadings, args.scheduler, args.n_wavelengths, args.dask_workers,
                 args.lanczos, args.method)
    else:
        table(args.cases, args.grids, args.eps, args.compare, args.maxiter, args.stop, args.true_residual, args.reference)


if __name__ == "__main__":
    sys.exit(main())
