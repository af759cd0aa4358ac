"""Iterative solvers of the periodic quasi-static problem on a voxel grid.

The unknown is the fluctuation x = E − E0 of the electric field, a compatible field
(x = Γ x, zero mean). The Galerkin (projection) form of the Lippmann-Schwinger equation is

    Γ ε x = −Γ ε E0,                                    (Vondřejc, Zeman, Marek 2014)

whose operator A = Γ ε Γ is complex *symmetric* (Γ is a real symmetric projection in real
space, ε a complex diagonal), not Hermitian: it is solved by the conjugate orthogonal
conjugate gradient (COCG, van der Vorst & Melissen 1990), which is CG with the bilinear
form xᵀy. No reference medium is needed, which is what makes it robust for metals
(ε ≈ −50 + 20i beside 2.25). Each iteration applies Γ once (2d FFTs).

Registry :data:`SOLVERS` (each ``solve(problem, tab, e0, x0, tol, maxiter) -> SolveOutcome``):

- :func:`solve_cocg` — default.
- :func:`solve_bicgstab` — BiCGStab (van der Vorst 1992) on the same Galerkin system; fallback.
- :func:`solve_gmres` — restarted GMRES (scipy) on the same system; fallback (memory: restart+2
  vector fields; impractical at 256³ in complex128).
- :func:`solve_eyre_milton` — the Eyre-Milton accelerated fixed point with reference
  ε0 = sqrt(ε_a ε_b) of the two most contrasted phases; converges at the rate
  |1 − √r| / |1 + √r| (r the contrast): the simple reference.
- :func:`solve_basic` — the Moulinec-Suquet fixed point with the same reference; for
  comparisons only (it finds no contracting reference for many metal contrasts).

``iterations`` counts applications of Γ (projections) for every solver, so that counts
compare across methods.

References
----------
- Vondřejc, J., Zeman, J., Marek, I. (2014). An FFT-based Galerkin method for homogenization
  of periodic media. Comput. Math. Appl. 68(3), 156-173. doi:10.1016/j.camwa.2014.05.014
- Zeman, J., Vondřejc, J., Novák, J., Marek, I. (2010). Accelerating a FFT-based solver for
  numerical homogenization of periodic media by conjugate gradients. J. Comput. Phys. 229,
  8065-8071. doi:10.1016/j.jcp.2010.07.010
- van der Vorst, H. A., Melissen, J. B. M. (1990). A Petrov-Galerkin type method for solving
  Ax = b, where A is symmetric complex. IEEE Trans. Magn. 26(2), 706-708. doi:10.1109/20.106415
- van der Vorst, H. A. (1992). Bi-CGSTAB. SIAM J. Sci. Stat. Comput. 13(2), 631-644.
- Eyre, D. J., Milton, G. W. (1999). A fast numerical scheme for computing the response of
  composites using grid refinement. Eur. Phys. J. Appl. Phys. 6, 41-47. doi:10.1051/epjap:1999150
- Moulinec, H., Suquet, P. (1998). Comput. Methods Appl. Mech. Eng. 157, 69-94.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np
import scipy.fft

from nmmm.homogenize import kernels
from nmmm.homogenize.green import GreenOperator, stacked_factors


@dataclass
class SolveOutcome:
    """What one solve (one loading, one wavelength) returns."""

    x: np.ndarray | None  # fluctuation field (d, N) or None
    flux: np.ndarray  # <eps E>, complex128 (d,)
    iterations: int  # applications of the projection
    history: list = field(default_factory=list)  # relative residuals
    converged: bool = True
    solver: str = ""
    message: str = ""
    green: str = ""  # the Green operator of the problem solved (set by fft_permittivity)
    stop: str = ""  # what declared convergence: "residual", or "flux" (COCG's flux rule); "" if not converged
    flux_error: float = float("nan")  # COCG with flux_tol: the last estimated relative error of e0·<eps E>
    flux_estimates: list = field(default_factory=list)  # ... one per projection from the flux window on
    offdiagonal_error: float = float("nan")  # ... and of the other components of <eps E> (their path, / |e0·<eps E>|)
    r: np.ndarray | None = None  # COCG with keep_r: the final (recursive) residual b − A x, (d, N)


def _local_threads(solve):
    """Run ``solve(problem, ...)`` with ``problem.workers`` Numba threads and restore the caller's
    count afterwards (no process-wide side effect)."""

    @functools.wraps(solve)
    def wrapper(problem, *args, **kwargs):
        with kernels.threads(problem.workers):
            return solve(problem, *args, **kwargs)

    return wrapper


def _stencil_form(op: GreenOperator, dtype):
    """(kind, stencil symbols (2, 3, Nmax), 1/h (3,)) when Γ of ``op`` has the rank-one stencil form
    k_j = phase(q) D_j(q) / h_j (kernels :func:`~nmmm.homogenize.kernels.stencil_divergence`): kind 1
    for "willot2014" (D_j = e^{iq_j} − 1, phase 1), 2 for "willot2015" (D_j = (e^{iq_j} − 1)
    Π_{l≠j} (e^{iq_l} + 1), phase e^{−i Σ q / 2} / 8i); None otherwise (the d-FFT path is used).
    The factors are checked against the operator's own, so a change there cannot go unnoticed."""
    kinds = {"willot2014": 1, "willot2015": 2}
    if op.name not in kinds or op.ndim != 3:
        return None
    kind = kinds[op.name]
    ih = np.ones(3)
    for j, n in enumerate(op.shape):
        q = 2.0 * np.pi * np.arange(n) / n
        e = np.exp(1j * q)
        if kind == 1:
            d_a, d_b, phase = e - 1.0, np.ones(n), np.ones(n)
        else:
            d_a, d_b, phase = (e - 1.0) / 2j, (e + 1.0) / 2.0, np.exp(-0.5j * q)
        a_ref, b_ref = phase * d_a, phase * d_b
        if n > 1:
            ih[j] = (op.a[j][1] / a_ref[1]).real
        if not (np.allclose(op.a[j], a_ref * ih[j], rtol=1e-12, atol=1e-12)
                and np.allclose(op.b[j], b_ref, rtol=1e-12, atol=1e-12)):
            return None
    real = np.float32 if np.dtype(dtype) == np.complex64 else np.float64
    return kind, kernels.stencil_symbols(op.shape, real), ih.astype(real)


class Problem:
    """A voxel grid, its compact labels and a Green operator, with preallocated buffers.

    The FFTs use :func:`scipy.fft.fftn` in place (``overwrite_x``) with ``workers``
    threads; the element-wise work runs in the Numba kernels of
    :mod:`nmmm.homogenize.kernels`.
    """

    def __init__(self, labels: np.ndarray, nphase: int, op: GreenOperator, dtype=np.complex128, workers: int = 2):
        self.shape = tuple(labels.shape)
        self.d = labels.ndim
        self.n = labels.size
        self.labels = np.ascontiguousarray(labels.reshape(-1))
        self.nphase = int(nphase)
        self.counts = np.bincount(self.labels, minlength=self.nphase).astype(float)
        self.op = op
        self.dtype = np.dtype(dtype)
        self.workers = int(workers)
        a, b, ny, shape3 = stacked_factors(op, self.dtype)
        self._a, self._b, self._ny, self._shape3 = a, b, ny, shape3
        self._has_ny = bool(ny.any())
        self._axes = tuple(range(1, self.d + 1))
        self.q = np.zeros((self.d, self.n), dtype=self.dtype)  # work buffer
        self.projections = 0  # Numba threads: set per solve by ``_local_threads`` and restored
        self.stencil = _stencil_form(op, self.dtype) if self.d == 3 and not self._has_ny else None
        self.psi = np.zeros(self.shape, dtype=self.dtype) if self.stencil is not None else None

    # -- operators ----------------------------------------------------------------------
    def field(self) -> np.ndarray:
        return np.zeros((self.d, self.n), dtype=self.dtype)

    def potential(self, F: np.ndarray) -> np.ndarray:
        """The scalar potential ψ of Γ F (Γ F = D ψ / h, :mod:`~nmmm.homogenize.kernels`), for a
        :attr:`stencil` operator: ψ = Δ⁻¹ Dᵀ F / h with Δ = Σ_j D_jᵀ D_j / h_j². The divergence is
        taken in real space, so one forward and one inverse FFT of a scalar field replace the d
        forward FFTs of F and the inverse one of the spectral form ψ̂ = kᴴ F̂ / |k|² (the same
        operator: the symbol of Dᵀ is conj(D)). The potential formulation of FFT-accelerated
        finite elements: Ladecký et al. (2023), Appl. Math. Comput. 446, 127835 (arXiv:2203.02962). F is not changed."""
        kind, sq, ih = self.stencil
        kernels.stencil_divergence(F.reshape((self.d,) + self.shape), self.psi, kind, ih)
        S = scipy.fft.fftn(self.psi, workers=self.workers, overwrite_x=True)
        kernels.inverse_laplacian(S, sq, kind, ih)
        psi = scipy.fft.ifftn(S, workers=self.workers, overwrite_x=True)
        if psi is not self.psi and not np.shares_memory(psi, self.psi):
            self.psi[...] = psi
        self.projections += 1
        return self.psi

    def project_inplace(self, F: np.ndarray, mode: int = 0) -> np.ndarray:
        """F ← Γ F (mode 0) or (I − 2Γ) F (mode 1), F a (d, N) real-space field; in place."""
        if mode == 0 and self.stencil is not None:
            kind, _, ih = self.stencil
            psi = self.potential(F)
            kernels.stencil_gradient(psi, F.reshape((self.d,) + self.shape), kind, ih)
            return F
        G = F.reshape((self.d,) + self.shape)
        Gh = scipy.fft.fftn(G, axes=self._axes, workers=self.workers, overwrite_x=True)
        kernels.project(Gh.reshape((self.d,) + self._shape3), self._a, self._b, self._ny, self._has_ny, mode)
        G2 = scipy.fft.ifftn(Gh, axes=self._axes, workers=self.workers, overwrite_x=True)
        self.projections += 1
        out = G2.reshape(self.d, self.n)
        if out is not F and not np.shares_memory(out, F):
            F[...] = out
        return F

    def tab(self, tab) -> np.ndarray:
        return np.ascontiguousarray(np.asarray(tab, dtype=self.dtype))

    def apply(self, x: np.ndarray, tab: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """out ← Γ ε x (the Galerkin operator on a compatible x)."""
        out = self.field() if out is None else out
        kernels.eps_times(out, x, self.labels, tab, np.zeros(self.d, dtype=self.dtype))
        return self.project_inplace(out)

    def rhs(self, tab: np.ndarray, e0: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """b = −Γ ε E0."""
        out = self.field() if out is None else out
        zero = self.q if out is not self.q else self.field()
        zero[...] = 0
        kernels.eps_times(out, zero, self.labels, tab, np.asarray(e0, dtype=self.dtype))
        self.project_inplace(out)
        out *= -1
        return out

    def flux(self, x, tab, e0) -> np.ndarray:
        return kernels.mean_flux(x, self.labels, tab, np.asarray(e0, dtype=complex), self.counts)


def _norm(v) -> float:
    v = v.reshape(-1)
    return float(np.sqrt(np.vdot(v, v).real))


def _bad(z) -> bool:
    return not np.isfinite(z) or z == 0


def _krylov_start(problem: Problem, tab, e0, keep_x: bool, name: str):
    """Common start of the Krylov solvers on Γ ε x = −Γ ε E0.

    Returns ``(tab, start, b, nb, x, done)``: the phase table in the field's precision, the
    projection count before the solve, the right-hand side b and its norm, a zero field x, and
    ``done`` — the finished outcome (E = E0) when b vanishes (a homogeneous medium), else None.
    """
    tab = problem.tab(tab)
    start = problem.projections
    b = problem.rhs(tab, e0)
    nb = _norm(b)
    x = problem.field()
    scale = float(np.max(np.abs(tab))) * np.sqrt(problem.n)
    done = None
    if nb <= 1e-14 * scale:
        done = SolveOutcome(x if keep_x else None, problem.flux(x, tab, e0), 0, [0.0], True, name)
    return tab, start, b, nb, x, done


# -- COCG -------------------------------------------------------------------------------------
#: COCG stops as stalled when its best residual has not halved in this many projections (a
#: finite-precision plateau, e.g. complex64 on a metal cell): the fallbacks then take over early.
STALL_WINDOW = 300

#: The window of COCG's flux rule (``flux_tol``): the estimated relative error of e0·⟨ε E⟩ is the
#: path length of its value over the last FLUX_WINDOW projections, Σ |X_k − X_{k−1}| / |X_k|.
#: Replayed on 298 complex128 COCG histories run to residual 1e-9..1e-11 (16³-48³ Boolean spheres
#: and flakes, 64² and 128² discs, both Willot operators, 10 ε from −50 + 0.5i to 12 + 1i in 2.25;
#: the 18 complex128 metal cases of benchmarks/bench_fft_metals.py at 64³ and 128³), stopping at 7
#: tol from 1e-3 to 1e-6: with 30 no stop had a true error above 0.46 tol (1156 stops before the
#: residual rule's; the worst, flakes at −50 + 0.5i with willot2015; the bench's cases, its 6
#: complex64 ones included, ≤ 0.15 tol); with 20, two were 1.04 tol off, and the plain difference
#: |X_k − X_{k−d}| was up to 42 tol off (near a resonance X circles its limit: 128³ flakes at
#: −50 + 1i, tol 1e-5, d = 10; still 7.6 tol with d = 100).
FLUX_WINDOW = 30

#: The smallest ``flux_tol`` fft_permittivity gives the flux rule, per precision: below it the
#: estimate sits on rounding noise (and its extrapolation would keep a hopeless solve going).
#: complex64's own floor: 24³ Boolean spheres at −50 + 2i (willot2014) are 1e-5 off the complex128
#: value even at residual 7e-6, and with flux_tol 1e-6 the rule stopped 2.6-17 tol off (at 1e-5 and
#: above, it stayed within 0.3 tol on the 64³-128³ cells at −44 + 13i); in complex128 the quadrature
#: and the iterate's flux agree to 1e-11 at residual 1e-9.
FLUX_TOL_MIN = {np.dtype(np.complex64): 1e-5, np.dtype(np.complex128): 1e-10}


@_local_threads
def solve_cocg(problem: Problem, tab, e0, x0=None, tol=1e-6, maxiter=5000, keep_x=True,
               stall_window: int | None = STALL_WINDOW, probe: tuple | None = None, monitor=None,
               flux_tol: float | None = None, flux_window: int = FLUX_WINDOW, keep_r: bool = False) -> SolveOutcome:
    """Conjugate orthogonal conjugate gradient on Γ ε x = −Γ ε E0 (van der Vorst & Melissen 1990).

    Converges when the relative residual is ≤ ``tol`` or, with ``flux_tol``, when the estimated
    relative error of the flux in the loading direction, X = e0·⟨ε E⟩, is ≤ ``flux_tol`` (the flux
    rule, ``stop="flux"`` in the outcome). X is the effective permittivity's bilinear form
    e0·ε_eff·e0 = e0·⟨ε⟩·e0 − bᵀA⁻¹b / N (b = −Γ ε E0, A = Γ ε Γ), and COCG's iterates give it as a
    Gauss quadrature, X_k = X_0 − Σ_{j<k} α_j ρ_j / N (ρ_j = r_jᵀ r_j), whose error is quadratic
    in the error of x (Strakoš & Tichý 2002; 2011 for non-Hermitian forms): it converges well
    before the residual (128³ flakes, −50 + 2i: true relative error below 1e-5 from 685 projections on,
    residual 1e-5 at 1338). The error of X_{k−d} is the sum of the later terms; it is estimated by the path length
    of X over the last ``flux_window`` projections (:data:`FLUX_WINDOW`), which, unlike |X_k − X_{k−d}|,
    does not vanish when X circles its limit. In complex64 the quadrature carries a bias of 5e-5 to
    1e-3 (measured, 64³-128³), so there X is the flux of the iterate, Σ α_j ⟨ε p_j⟩, instead; that
    one also is returned by a solve stopped on the residual (and for the other components of ⟨ε E⟩
    always: their error stays linear in the residual; ``keep_r`` returns the residual field, with
    which fft_permittivity makes them quadratic from two loadings' solves). With a seed, X_0 is the
    seed's flux and its residual's term x_sᵀ r_0 / N is subtracted (the same quadrature for A y = r_0).

    Stops early ("stalled") when the best relative residual has not halved over the last
    ``stall_window`` projections (None: never; with the flux rule, nor the flux's estimated error:
    128³ flakes at −50 + 1i keep a residual of 0.5 over 25-325 projections while the estimate falls,
    and converge on the flux at ~1500), and, with ``probe = (n, r)``, when the best
    residual is still above r after n projections (a convergence too slow to wait for). ``monitor``:
    a callable on the residual history after each projection (with the flux rule also given the
    flux estimates, ``monitor(history, (flux_window, estimates, flux_tol))``); a returned message
    stops the solve (unconverged, with that message) — fft_permittivity's prediction of a solve
    beyond maxiter.

    References: Strakoš, Z., Tichý, P. (2002). On error estimation in the conjugate gradient method
    and why it works in finite precision computations. Electron. Trans. Numer. Anal. 13, 56-80.
    Strakoš, Z., Tichý, P. (2011). On efficient numerical approximation of the bilinear form
    c*A⁻¹b. SIAM J. Sci. Comput. 33(2), 565-587."""
    tab, start, r, nb, x, done = _krylov_start(problem, tab, e0, keep_x, "cocg")
    if done is not None:  # homogeneous medium: E = E0
        done.stop = "residual"
        done.r = r if keep_r else None
        return done
    e0c = np.asarray(e0, dtype=complex)
    seeded = False
    if x0 is not None:
        # seed with γ x0, γ minimising ‖b − γ A x0‖ (never a worse start than x = 0)
        Ax = problem.apply(x0, tab, out=problem.q)  # q is free here: no extra field
        axv = Ax.reshape(-1)
        den = float(np.vdot(axv, axv).real)
        if den > 0:
            gamma = np.vdot(axv, r.reshape(-1)) / den
            x[...] = x0
            x *= gamma
            Ax *= gamma
            r -= Ax
            seeded = True
        del Ax, axv
    p = problem.field()
    q = problem.q
    rv = r.reshape(-1)
    rho = complex(np.dot(rv, rv))
    history = [_norm(r) / nb]
    beta = 0.0j
    ctype = problem.dtype.type
    converged = history[-1] <= tol
    stop = "residual" if converged else ""
    message = ""
    it = 0
    stencil = problem.stencil  # Willot operators: q = Γ ε p enters the update through its potential
    # without keep_x and a seed, x is never formed: ⟨ε x⟩ = Σ α_k ⟨ε p_k⟩ from the direction pass
    # (x = Σ α_k p_k), which saves a field read and write per iteration (x's pages stay untouched)
    lazy = stencil is not None and not keep_x and x0 is None
    sums = np.zeros(problem.d, np.complex128)
    flux_x = np.zeros(problem.d, np.complex128)  # Σ α_k Σ_voxels ε p_k (every path: the sums come free)
    rule = flux_tol is not None
    if rule:
        window = max(1, int(flux_window))
        seed_flux = problem.flux(x if seeded else None, tab, e0)  # ⟨ε (E0 + x_s)⟩
        quadrature = problem.dtype == np.complex128  # complex64: the iterate's flux (see above)
        # X_0 and the running quadrature sum Σ α ρ (with a seed: x_sᵀ r_0 first)
        x_start = complex(e0c @ seed_flux)
        gauss = complex(np.dot(x.reshape(-1), rv)) if seeded else 0j
        values = [x_start]
        path = []  # |X_k − X_{k−1}|
        others = np.abs(e0c) == 0  # the other components of ⟨ε E⟩ (off-diagonal terms for a unit loading)
        off_path = []  # max |Δ⟨ε E⟩_i| over those
        estimates: list = []
        flux_error = off_error = float("nan")
    while not converged and it < maxiter:
        pq = kernels.direction_and_eps(p, q, r, ctype(beta), problem.labels, tab, True, sums)
        if stencil is not None:
            psi = problem.potential(q)
        else:
            problem.project_inplace(q)
        it += 1
        if _bad(pq) or _bad(rho):
            message = "COCG breakdown (pᵀAp or rᵀr vanished)"
            break
        alpha = rho / pq
        a_used = complex(ctype(alpha))
        flux_x += a_used * sums
        if stencil is not None:
            rho_new, nr = kernels.cocg_update_stencil(x, r, p, psi, ctype(alpha), stencil[0], stencil[2], not lazy)
        else:
            rho_new, nr = kernels.cocg_update(x, r, p, q, ctype(alpha))
        res = float(np.sqrt(nr)) / nb
        history.append(res)
        if not np.isfinite(res) or res > 1e8:
            message = "COCG diverged"
            break
        if res <= tol:
            converged = True
            stop = "residual"
            break
        if rule:
            if quadrature:
                gauss += a_used * rho
                values.append(x_start - gauss / problem.n)
            else:
                values.append(x_start + complex(e0c @ flux_x) / problem.n)
            path.append(abs(values[-1] - values[-2]))
            off_path.append(float(np.max(np.abs(a_used * sums[others]), initial=0.0)) / problem.n)
            if it >= window:
                size = abs(values[-1])
                flux_error = float(sum(path[-window:]) / size) if size > 0 else float("inf")
                estimates.append(flux_error)
                if flux_error <= flux_tol:
                    converged = True
                    stop = "flux"
                    off_error = float(sum(off_path[-window:]) / size) if others.any() else float("nan")
                    message = (f"COCG converged on the flux: estimated relative error of e0·<eps E> "
                               f"{flux_error:.2g} <= {flux_tol:g} (its path over the last {window} projections, "
                               f"{'Gauss quadrature' if quadrature else 'flux of the iterate'}); relative "
                               f"residual {res:.3g} (tol={tol:g}); the other components of <eps E> (off-diagonal "
                               f"terms, error linear in the residual): path {off_error:.2g} of |e0·<eps E>|")
                    break
        if monitor is not None:
            message = (monitor(history, (window, estimates, flux_tol)) if rule else monitor(history)) or ""
            if message:
                break
        if probe is not None and it == probe[0] and min(history) > probe[1]:
            message = (f"COCG slow: best relative residual {min(history):.3g} > {probe[1]:g} after "
                       f"{probe[0]} projections (tol={tol:g})")
            break
        if stall_window and it > stall_window and it % 25 == 0:
            stalled = min(history[-stall_window:]) > 0.5 * min(history[:-stall_window])
            if stalled and rule:  # ... and so has the flux's estimated error (near a resonance it falls first)
                stalled = (len(estimates) > stall_window
                           and min(estimates[-stall_window:]) > 0.5 * min(estimates[:-stall_window]))
            if stalled:
                message = (f"COCG stalled: best relative residual {min(history):.3g} did not halve in the last "
                           f"{stall_window} projections" + (" (nor the flux's estimated error)" if rule else "")
                           + f" (tol={tol:g})")
                break
        beta = rho_new / rho
        rho = rho_new
    if not converged and not message:
        message = f"COCG reached maxiter={maxiter} with relative residual {history[-1]:.3g} > tol={tol:g}"
        if rule and np.isfinite(flux_error):
            message += f" (the flux's estimated relative error {flux_error:.2g} > {flux_tol:g})"
    if lazy:
        flux = problem.flux(None, tab, e0) + flux_x / problem.n
    else:
        flux = problem.flux(x, tab, e0)
    out = SolveOutcome(x if keep_x else None, flux, problem.projections - start, history, converged, "cocg", message,
                       stop=stop, r=r if keep_r else None)
    if rule:
        out.flux_error, out.flux_estimates, out.offdiagonal_error = flux_error, estimates, off_error
        if stop == "flux" and quadrature:
            # the loading direction's component is the quadrature (the estimate is about it)
            j = int(np.argmax(np.abs(e0c)))
            if np.count_nonzero(e0c) == 1 and e0c[j] == 1:
                out.flux = flux.copy()
                out.flux[j] = values[-1]
    return out


# -- BiCGStab ---------------------------------------------------------------------------------
@_local_threads
def solve_bicgstab(problem: Problem, tab, e0, x0=None, tol=1e-6, maxiter=5000, keep_x=True) -> SolveOutcome:
    """BiCGStab (van der Vorst 1992) on the Galerkin system; two projections per iteration."""
    tab, start, b, nb, x, done = _krylov_start(problem, tab, e0, keep_x, "bicgstab")
    if done is not None:
        return done
    r = b
    if x0 is not None:
        x[...] = x0
        r = r - problem.apply(x, tab)
    rhat = r.copy()
    rho = alpha = omega = 1.0 + 0j
    v = problem.field()
    p = problem.field()
    history = [_norm(r) / nb]
    converged = history[-1] <= tol
    message = ""
    while not converged and problem.projections - start < maxiter:
        rho_new = np.vdot(rhat, r)
        if _bad(rho_new) or _bad(omega):
            message = "BiCGStab breakdown"
            break
        beta = (rho_new / rho) * (alpha / omega)
        p = r + beta * (p - omega * v)
        v = problem.apply(p, tab, out=v)
        den = np.vdot(rhat, v)
        if _bad(den):
            message = "BiCGStab breakdown"
            break
        alpha = rho_new / den
        s = r - alpha * v
        ns = _norm(s) / nb
        if ns <= tol:
            x += alpha * p
            history.append(ns)
            converged = True
            break
        t = problem.apply(s, tab)
        tt = np.vdot(t, t)
        omega = np.vdot(t, s) / tt if tt != 0 else 0.0
        x += alpha * p + omega * s
        r = s - omega * t
        rho = rho_new
        res = _norm(r) / nb
        history.append(res)
        if not np.isfinite(res) or res > 1e8:
            message = "BiCGStab diverged"
            break
        converged = res <= tol
    if not converged and not message:
        message = f"BiCGStab reached maxiter={maxiter} projections with relative residual {history[-1]:.3g}"
    return SolveOutcome(x if keep_x else None, problem.flux(x, tab, e0), problem.projections - start, history,
                        converged, "bicgstab", message)


# -- GMRES ------------------------------------------------------------------------------------
@_local_threads
def solve_gmres(problem: Problem, tab, e0, x0=None, tol=1e-6, maxiter=5000, keep_x=True, restart=30) -> SolveOutcome:
    """Restarted GMRES (:func:`scipy.sparse.linalg.gmres`) on the Galerkin system."""
    from scipy.sparse.linalg import LinearOperator, gmres

    tab, start, b, nb, x, done = _krylov_start(problem, tab, e0, keep_x, "gmres")
    if done is not None:
        return done
    shape = (problem.d, problem.n)
    size = problem.d * problem.n

    def mv(v):
        return problem.apply(np.asarray(v, dtype=problem.dtype).reshape(shape), tab).reshape(-1).copy()

    A = LinearOperator((size, size), matvec=mv, dtype=problem.dtype)
    history: list = []
    restart = max(1, min(int(restart), int(maxiter)))
    xs, info = gmres(A, b.reshape(-1), x0=None if x0 is None else x0.reshape(-1), rtol=tol, atol=0.0,
                     restart=restart, maxiter=max(1, maxiter // restart), callback=history.append,
                     callback_type="pr_norm")
    x = np.asarray(xs, dtype=problem.dtype).reshape(shape)
    res = _norm(b - problem.apply(x, tab)) / nb
    history.append(res)
    converged = res <= tol * 1.5
    message = "" if converged else f"GMRES stopped (info={info}) with relative residual {res:.3g}"
    return SolveOutcome(x if keep_x else None, problem.flux(x, tab, e0), problem.projections - start, history,
                        converged, "gmres", message)


# -- fixed-point schemes with a reference medium ------------------------------------------------
def reference_eyre_milton(tab) -> complex:
    """ε0 = sqrt(ε_a ε_b) for the two phases of largest contrast |log(ε_a/ε_b)| (Eyre & Milton 1999).

    The branch with Re(ε0) > 0 is taken, or, for metal-dielectric contrasts, the root that
    minimises the contraction factor max |(ε − ε0)/(ε + ε0)|.
    """
    tab = np.asarray(tab, dtype=complex)
    best, pair = -1.0, (tab[0], tab[0])
    for i in range(tab.size):
        for j in range(i + 1, tab.size):
            c = abs(np.log(tab[i] / tab[j]))
            if c > best:
                best, pair = c, (tab[i], tab[j])
    root = np.sqrt(pair[0] * pair[1])
    cands = [root, -root]
    rates = [np.max(np.abs((tab - c) / (tab + c))) if np.all(tab + c != 0) else np.inf for c in cands]
    return complex(cands[int(np.argmin(rates))])


@_local_threads
def solve_eyre_milton(problem: Problem, tab, e0, x0=None, tol=1e-6, maxiter=20000, keep_x=True, eps0=None) -> SolveOutcome:
    """Eyre-Milton scheme u ← (I − 2Γ)(ε − ε0)(ε + ε0)⁻¹ u + 2 ε0 E0, E = (ε + ε0)⁻¹ u.

    Stops when ‖u_{k+1} − u_k‖ / ‖u_{k+1}‖ ≤ tol.
    """
    tab = np.asarray(tab, dtype=complex)
    eps0 = reference_eyre_milton(tab) if eps0 is None else complex(eps0)
    ztab = problem.tab((tab - eps0) / (tab + eps0))
    start = problem.projections
    e0 = np.asarray(e0, dtype=complex)
    u = problem.field()
    zero = np.zeros(problem.d, dtype=problem.dtype)
    kernels.eps_times(u, problem.field() if x0 is None else x0.astype(problem.dtype),
                      problem.labels, problem.tab(tab + eps0), e0.astype(problem.dtype))
    w = problem.field()
    shift = (2 * eps0 * e0).astype(problem.dtype)[:, None]
    history: list = []
    converged = False
    it = 0
    while it < maxiter:
        kernels.eps_times(w, u, problem.labels, ztab, zero)
        problem.project_inplace(w, mode=1)
        w += shift
        it += 1
        du = _norm(w - u) / max(_norm(w), 1e-300)
        u, w = w, u
        history.append(du)
        if not np.isfinite(du):
            break
        if du <= tol:
            converged = True
            break
    etab = problem.tab(tab / (tab + eps0))
    flux = kernels.mean_flux(u, problem.labels, etab, np.zeros(problem.d, complex), problem.counts)
    x = None
    if keep_x:
        x = problem.field()
        kernels.eps_times(x, u, problem.labels, problem.tab(1.0 / (tab + eps0)), zero)
        x -= e0.astype(problem.dtype)[:, None]
    msg = "" if converged else f"Eyre-Milton: no convergence in {maxiter} iterations (last step {history[-1]:.3g})"
    return SolveOutcome(x, flux, problem.projections - start, history, converged, "eyre_milton", msg)


@_local_threads
def solve_basic(problem: Problem, tab, e0, x0=None, tol=1e-6, maxiter=20000, keep_x=True, eps0=None) -> SolveOutcome:
    """Moulinec-Suquet fixed point E ← E0 − Γ (ε − ε0)/ε0 E, ε0 = (ε_a + ε_b)/2 by default."""
    tab = np.asarray(tab, dtype=complex)
    if eps0 is None:
        i, j = np.argmin(np.abs(tab)), np.argmax(np.abs(tab))
        eps0 = (tab[i] + tab[j]) / 2
    ttab = problem.tab((tab - eps0) / eps0)
    start = problem.projections
    e0 = np.asarray(e0, dtype=problem.dtype)
    x = problem.field() if x0 is None else x0.astype(problem.dtype).copy()
    w = problem.field()
    history: list = []
    converged = False
    it = 0
    while it < maxiter:
        kernels.eps_times(w, x, problem.labels, ttab, e0)
        problem.project_inplace(w)
        w *= -1
        it += 1
        du = _norm(w - x) / max(_norm(w + e0[:, None]), 1e-300)
        x, w = w, x
        history.append(du)
        if not np.isfinite(du) or du > 1e8:
            break
        if du <= tol:
            converged = True
            break
    flux = problem.flux(x, problem.tab(tab), e0)
    msg = "" if converged else f"basic scheme: no convergence in {maxiter} iterations (last step {history[-1]:.3g})"
    return SolveOutcome(x if keep_x else None, flux, problem.projections - start, history, converged, "basic", msg)


# -- off-diagonal terms from two loadings' solves --------------------------------------------
def _bilinear(a: np.ndarray, b: np.ndarray) -> complex:
    """aᵀb (no conjugate) summed in complex128, a slice of 2^20 values at a time."""
    a, b = a.reshape(-1), b.reshape(-1)
    step = 1 << 20
    return sum((complex(np.dot(a[k:k + step], b[k:k + step])) for k in range(0, a.size, step)), 0j)


def pair_terms(t: np.ndarray, finals: list, j: int, out, prob) -> list:
    """The off-diagonal terms between loading ``j`` (just solved: ``out``, with its field and residual)
    and the loadings solved before it at this wavelength (``finals``: (loading, field, Problem)):
    ε_ij = ε_ji = T_ij(x_j) − x_iᵀ r_j / N in ``t`` (d, d), with T_ij(x_j)
    the iterate's flux (column j, row i), r_j = b_j − A x_j. This is the bilinear form b_iᵀA⁻¹b_j with
    loading i's solve as the dual one (Strakoš & Tichý 2011): its error is e_iᵀ A e_j, quadratic like the
    diagonal's, where T_ij alone is off by b_iᵀA⁻¹r_j, linear in the residual (64³ flakes at −50 + 2i, tol
    1e-5: 2.2e-4 of |ε_jj|). Pairs across operators or solvers (a fallback) keep T. Returns the loadings
    paired with j."""
    paired = []
    if out.r is not None:
        for i, x_i, prob_i in finals:
            if prob_i is prob and x_i is not None:
                s = t[i, j] - _bilinear(x_i, out.r) / prob.n
                t[i, j] = t[j, i] = s
                paired.append(i)
    finals.append((j, out.x, prob))
    out.r = None  # not needed any more
    return paired


#: Registry of solvers: name -> function(problem, tab, e0, x0, tol, maxiter, keep_x).
SOLVERS = {
    "cocg": solve_cocg,
    "bicgstab": solve_bicgstab,
    "gmres": solve_gmres,
    "eyre_milton": solve_eyre_milton,
    "basic": solve_basic,
}

#: Fallback order after the default solver fails.
FALLBACKS = ("bicgstab", "gmres")

__all__ = [
    "Problem",
    "SolveOutcome",
    "SOLVERS",
    "FALLBACKS",
    "STALL_WINDOW",
    "FLUX_WINDOW",
    "FLUX_TOL_MIN",
    "solve_cocg",
    "solve_bicgstab",
    "solve_gmres",
    "solve_eyre_milton",
    "solve_basic",
    "reference_eyre_milton",
    "pair_terms",
]
