"""Every wavelength of a two-phase cell from one Lanczos run (Bergman's spectral representation).

- :func:`two_phase_spectrum` — the diagonal of ε_eff(λ) of a two-phase voxel cell at all
  wavelengths at once.

For two phases, ε = ε_a + Δ χ (χ the indicator of phase b, Δ = ε_b − ε_a), the Galerkin
equation Γ ε (E0 + x) = 0 on compatible fields is the *shifted* real symmetric system

    (M + s I) x = b,    M = Γ χ Γ,  s = ε_a / Δ,  b = −Γ χ E0,

with M and b real and independent of the wavelength: only the complex shift s(λ) changes.
Krylov spaces are shift-invariant, so one Lanczos run on (M, b) — real fields, one
projection per step — gives the Galerkin (COCG) solution at every shift, and the flux needs no
field: E0·⟨ε E⟩ = ε_a + Δ (f − bᵀx / N) with bᵀx = ‖b‖² [(T_k + s I)⁻¹]₁₁, T_k the Lanczos
tridiagonal (a continued fraction: the Gauss quadrature of Bergman's spectral measure of the
cell). The relative residual of shift s after k steps is Π_{j≤k} β_j / |d_j(s)| (d_j the
pivots of T_k + s I), so each wavelength stops at its own tolerance, and the run costs the
projections of the slowest wavelength — instead of the sum over wavelengths.

Limits: two phases; the diagonal only (off-diagonal terms would need the other loadings'
right-hand sides); finite-precision Lanczos loses orthogonality, which delays convergence
(as it does COCG) but keeps the quadrature accurate — checked against COCG in the tests.

References
----------
- Bergman, D. J. (1978). The dielectric constant of a composite material — a problem in
  classical physics. Phys. Rep. 43(9), 377-407. doi:10.1016/0370-1573(78)90009-1
- Milton, G. W. (2002). The Theory of Composites, ch. 18 (Stieltjes function, analytic method).
- Frommer, A. (2003). BiCGStab(ℓ) for families of shifted linear systems. Computing 70, 87-109
  (shift invariance of Krylov spaces); Golub, G. H., Meurant, G. (2010). Matrices, Moments and
  Quadrature with Applications. Princeton (Lanczos and Gauss quadrature).
"""

from __future__ import annotations

import numpy as np

from nmmm.errors import InvalidInputError


def two_phase_spectrum(labels, eps, *, green: str = "willot2015", directions=None, tol: float = 1e-6,
                       maxiter: int = 5000, workers: int = 2, wavelength_nm=None):
    """Diagonal of ε_eff at every wavelength of a two-phase cell from one Lanczos run per loading.

    Parameters
    ----------
    labels : int array (3-D) or Microstructure
        Exactly two phase labels.
    eps : mapping label -> ε (scalars, or 1-D arrays over wavelength, or Materials)
    green : str
        Green operator (the real-space operator must be real: "willot2015", "willot2014",
        "continuous").
    directions : sequence of int, optional
        Loadings (default all).
    tol : float
        Relative residual per wavelength (the COCG one, ‖Γ ε E − 0‖ / ‖Γ ε E0‖).
    maxiter : int
        Lanczos steps (projections) per loading.

    Returns
    -------
    FFTHomogenization
        ``tensor`` with the computed diagonal (off-diagonal NaN), ``iterations`` the Lanczos
        step at which each wavelength converged, ``solver`` "lanczos",
        ``metadata["projections"]`` the projections of each loading's run.
    """
    from nmmm.errors import ConvergenceError
    from nmmm.homogenize.fft import FFTHomogenization, _as_label_array, _compact_labels, _eps_table
    from nmmm.homogenize.green import green_operator
    from nmmm.homogenize.solvers import Problem
    from nmmm.homogenize.kernels import threads

    arr, _ = _as_label_array(labels)
    compact, values, counts = _compact_labels(arr)
    if values.size != 2:
        raise InvalidInputError(f"two_phase_spectrum needs exactly two phases, got labels {values.tolist()}; "
                                "use fft_permittivity for other cells")
    table, scalar = _eps_table(values, eps, wavelength_nm)
    d = arr.ndim
    dirs = tuple(range(d)) if directions is None else tuple(int(j) for j in directions)
    if not dirs or any(j < 0 or j >= d for j in dirs):
        raise InvalidInputError(f"directions must be axes in 0..{d - 1}, got {directions!r}")
    if not (0 < tol < 1):
        raise InvalidInputError(f"tol must lie in (0, 1) (relative residual per wavelength), got {tol}")
    if isinstance(maxiter, bool) or not isinstance(maxiter, (int, np.integer)) or maxiter < 1:
        raise InvalidInputError(f"maxiter must be a positive integer (Lanczos steps per loading), got {maxiter!r}")
    ea, eb = table[:, 0], table[:, 1]
    delta = eb - ea
    homog = np.abs(delta) <= 1e-14 * np.maximum(np.abs(ea), 1e-300)
    s = np.where(homog, np.inf, ea / np.where(homog, 1.0, delta))
    f = float(counts[1]) / arr.size
    op = green_operator(arr.shape, green)
    prob = Problem(compact, 2, op, np.complex128, workers)
    chi = (prob.labels == 1).astype(np.float64)
    nw = table.shape[0]
    tensor = np.full((nw, d, d), np.nan + 0j)
    iterations = np.zeros((nw, len(dirs)), dtype=int)
    histories = [[] for _ in range(nw)]
    projections = []
    with threads(workers):
        for c, j in enumerate(dirs):
            w = prob.field()
            w[j] = chi
            b = -prob.project_inplace(w).real
            beta0 = float(np.sqrt(np.sum(b * b)))
            if beta0 <= 1e-14 * np.sqrt(arr.size):  # χ E0 is compatible-free: ε_eff = arithmetic mean
                tensor[:, j, j] = ea + delta * f
                projections.append(1)
                continue
            v = b / beta0
            v_prev = np.zeros_like(v)
            alphas, betas = [], []
            piv = None
            res = np.ones(nw)
            done_at = np.zeros(nw, dtype=int)
            done_at[homog] = 1
            beta_prev = 0.0
            k = 0
            hist = [[1.0] for _ in range(nw)]
            while k < maxiter and not np.all(done_at > 0):
                w = prob.q  # the work buffer: no field allocated per step
                np.multiply(chi, v, out=w.real)
                w.imag[...] = 0.0
                mv = prob.project_inplace(w).real.copy()
                a = float(np.sum(v * mv))
                mv -= a * v
                mv -= beta_prev * v_prev
                beta = float(np.sqrt(np.sum(mv * mv)))
                k += 1
                alphas.append(a)
                betas.append(beta)
                sh = np.where(homog, 0.0, s)
                piv = a + sh if piv is None else a + sh - beta_prev ** 2 / piv
                res = res * beta / np.maximum(np.abs(piv), 1e-300)
                newly = (done_at == 0) & (res <= tol)
                done_at[newly] = k
                for i in np.flatnonzero(done_at == 0):
                    hist[i].append(float(res[i]))
                if beta <= 1e-14 * beta0:  # invariant subspace: exact at every shift
                    done_at[done_at == 0] = k
                    break
                v_prev, v = v, mv / beta
                beta_prev = beta
            projections.append(k + 1)
            if np.any(done_at == 0):
                bad = np.flatnonzero(done_at == 0)
                raise ConvergenceError(
                    f"Lanczos reached maxiter={maxiter} for loading e{j} with {bad.size} wavelength(s) above "
                    f"tol={tol:g} (worst relative residual {res[bad].max():.3g} at index {int(bad[np.argmax(res[bad])])}); "
                    "raise maxiter or use fft_permittivity", history={"lanczos": hist[int(bad[0])]})
            # (1,1) element of (T_k + s I)^{-1}, backward continued fraction, each wavelength on its own T
            for i in range(nw):
                if homog[i]:
                    tensor[i, j, j] = ea[i]
                    continue
                m = done_at[i]
                cf = 1.0 / (alphas[m - 1] + s[i])
                for t in range(m - 2, -1, -1):
                    cf = 1.0 / (alphas[t] + s[i] - betas[t] ** 2 * cf)
                btx = beta0 ** 2 * cf
                tensor[i, j, j] = ea[i] + delta[i] * (f - btx / arr.size)
                iterations[i, c] = m
                histories[i].append(hist[i])
    fractions = {int(v): float(cnt) / arr.size for v, cnt in zip(values, counts)}
    solver = np.full((nw, len(dirs)), "lanczos", dtype=object)
    if scalar:
        tensor, iterations, solver, histories = tensor[0], iterations[0], solver[0], histories[0]
    return FFTHomogenization(tensor=tensor, iterations=iterations, residual_history=histories, solver=solver,
                             green=op.name, fractions=fractions, directions=dirs, shape=tuple(arr.shape),
                             dtype="complex128", metadata={"tol": tol, "projections": projections})


__all__ = ["two_phase_spectrum"]
