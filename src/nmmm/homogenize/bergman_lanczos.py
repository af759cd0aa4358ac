"""Every wavelength of a two-phase cell from one Lanczos run (Bergman's spectral representation).

- :func:`two_phase_spectrum` — ε_eff(λ) of a two-phase voxel cell at all wavelengths at once.
- :func:`lanczos_columns` — its core, used by :func:`nmmm.homogenize.fft.fft_permittivity`
  (``method="lanczos"``, or ``"auto"`` over a spectrum).

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

Off-diagonal terms come from the same run: the products of the Lanczos vectors with the other
axes' right-hand sides are taken along the way (see :func:`lanczos_columns`).

Limits: two phases; no local fields; finite-precision Lanczos loses orthogonality, which delays
convergence. With a low-loss metal it falls behind COCG (which, in exact arithmetic, builds the
same Krylov space) and the residual estimated from the pivots no longer bounds the error: 64³
flake deposit (p 0.10) in 2.25, willot2014, tol 1e-5 — at −50 + 1i 1284 steps against COCG's
498 and ε_xx 2.3e-3 away from COCG's (whose true residual is 9.7e-6); −50 + 5i 419 vs 291,
5.8e-6 apart; at −44 + 13i (aluminium-like) both take 181 and agree to 4e-11. So
``fft_permittivity(method="auto")`` does not choose it when a metal phase has Im ε < 0.15 |ε|.

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
                       maxiter: int = 5000, workers: int = 2, wavelength_nm=None, voxel_nm=None,
                       stop_when_slow: bool = True):
    """ε_eff at every wavelength of a two-phase cell from one Lanczos run per loading.

    Parameters
    ----------
    labels : int array (2-D or 3-D) or Microstructure
        Exactly two phase labels.
    eps : mapping label -> ε (scalars, or 1-D arrays over wavelength, or Materials)
    green : str
        Green operator (the real-space operator must be real: "willot2015", "willot2014",
        "continuous").
    directions : sequence of int, optional
        Loadings (default all): the tensor's columns computed, off-diagonal terms included.
    tol : float
        Relative residual per wavelength (the COCG one, ‖Γ ε E − 0‖ / ‖Γ ε E0‖).
    maxiter : int
        Lanczos steps (projections) per loading.
    voxel_nm : float or sequence, optional
        Voxel size per axis (only the ratios matter: anisotropic voxels).
    stop_when_slow : bool
        Stop a run early (ConvergenceError) when the slowest wavelength's residual, extrapolated
        (:func:`nmmm.homogenize.fft.predicted_projections`), would need more than
        ``PREDICT[1]`` × ``maxiter`` steps (:data:`nmmm.homogenize.fft.PREDICT`), checked from
        :func:`nmmm.homogenize.fft.first_prediction` steps on.

    Returns
    -------
    FFTHomogenization
        ``tensor`` with the computed columns (other columns NaN), ``iterations`` the Lanczos
        step at which each wavelength converged, ``solver`` "lanczos",
        ``metadata["projections"]`` the projections of each loading's run (the first loading's
        also counts the d − 1 right-hand sides of the other axes, used for off-diagonal terms).

    Examples
    --------
    A laminate across its layers: the harmonic mean, at every wavelength (exact).

    >>> lab = np.zeros((8, 4), dtype=int); lab[4:] = 1
    >>> r = two_phase_spectrum(lab, {0: 2.25, 1: np.array([-10 + 1j, 4 + 0j])}, directions=[0], workers=1)
    >>> np.round(r.tensor[:, 0, 0], 6).tolist()   # 2 ε_a ε_b / (ε_a + ε_b)
    [(5.785056+0.165814j), (2.88+0j)]
    """
    from nmmm.homogenize.fft import FFTHomogenization, _as_label_array, _compact_labels, _eps_table
    from nmmm.homogenize.green import green_operator

    arr, meta = _as_label_array(labels)
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
    voxel_nm = meta.get("voxel_nm") if voxel_nm is None else voxel_nm
    spacing = None
    if voxel_nm is not None:
        spacing = np.broadcast_to(np.asarray(voxel_nm, dtype=float), (d,))
        spacing = tuple(spacing / spacing.min())
    op = green_operator(arr.shape, green, spacing=spacing)
    tensor, iterations, histories, projections = lanczos_columns(compact, counts, table, op, dirs, tol, maxiter,
                                                                 workers, stop_when_slow)
    fractions = {int(v): float(cnt) / arr.size for v, cnt in zip(values, counts)}
    solver = np.full(iterations.shape, "lanczos", dtype=object)
    if scalar:
        tensor, iterations, solver, histories = tensor[0], iterations[0], solver[0], histories[0]
    return FFTHomogenization(tensor=tensor, iterations=iterations, residual_history=histories, solver=solver,
                             green=op.name, fractions=fractions, directions=dirs, shape=tuple(arr.shape),
                             dtype="complex128", metadata={"tol": tol, "projections": projections})


def lanczos_columns(compact, counts, table, op, dirs, tol, maxiter, workers=2, stop_when_slow=True):
    """The core of :func:`two_phase_spectrum` on checked input: compact labels (0/1), their
    counts, the ``(n_wavelengths, 2)`` permittivity table and a Green operator. Returns
    ``(tensor (nw, d, d), iterations (nw, len(dirs)), histories, projections per loading)``.

    Off-diagonal terms: E_i·⟨ε E⟩ for loading j is −Δ b_iᵀ x_j / N (i ≠ j), b_i = −Γ χ e_i, and
    b_iᵀ x_j = β0 Σ_k (b_iᵀ v_k) y_k with y = (T_m + s I)⁻¹ e_1; the products b_iᵀ v_k are taken
    along the run (d − 1 dot products per step, no extra projection)."""
    from scipy.linalg import solve_banded

    from nmmm.errors import ConvergenceError
    from nmmm.homogenize.fft import PREDICT, first_prediction, predicted_projections
    from nmmm.homogenize.kernels import threads
    from nmmm.homogenize.solvers import Problem

    shape = compact.shape
    n = compact.size
    d = compact.ndim
    ea, eb = table[:, 0], table[:, 1]
    delta = eb - ea
    homog = np.abs(delta) <= 1e-14 * np.maximum(np.abs(ea), 1e-300)
    s = np.where(homog, np.inf, ea / np.where(homog, 1.0, delta))
    f = float(counts[1]) / n
    prob = Problem(compact, 2, op, np.complex128, workers)
    chi = (prob.labels == 1).astype(np.float64)
    nw = table.shape[0]
    tensor = np.full((nw, d, d), np.nan + 0j)
    iterations = np.zeros((nw, len(dirs)), dtype=int)
    histories = [[] for _ in range(nw)]
    projections = []
    with threads(workers):
        rhs = []  # b_i = −Γ χ e_i for every axis (real fields)
        for i in range(d):
            w = prob.field()
            w[i] = chi
            rhs.append(-prob.project_inplace(w).real)
        for c, j in enumerate(dirs):
            b = rhs[j]
            others = [i for i in range(d) if i != j]
            beta0 = float(np.sqrt(np.sum(b * b)))
            if beta0 <= 1e-14 * np.sqrt(n):  # χ E0 is compatible-free: x = 0, ε_eff e_j = arithmetic mean
                tensor[:, :, j] = 0.0
                tensor[:, j, j] = ea + delta * f
                for i in others:  # b_i ⟂ x = 0
                    tensor[:, i, j] = 0.0
                projections.append(1 + (d - 1 if c == 0 else 0))
                continue
            v = b / beta0
            v_prev = np.zeros_like(v)
            alphas, betas = [], []
            cross = {i: [] for i in others}  # b_iᵀ v_k
            piv = None
            res = np.ones(nw)
            done_at = np.zeros(nw, dtype=int)
            done_at[homog] = 1
            beta_prev = 0.0
            k = 0
            hist = [[1.0] for _ in range(nw)]
            mv = np.empty_like(v)
            tmp = np.empty_like(v)
            flat = lambda f: f.reshape(-1)  # noqa: E731 - BLAS dot products on contiguous views, no temporaries
            while k < maxiter and not np.all(done_at > 0):
                for i in others:
                    cross[i].append(float(np.dot(flat(rhs[i]), flat(v))))
                w = prob.q  # the work buffer: no field allocated per step
                np.multiply(chi, v, out=w.real)
                w.imag[...] = 0.0
                np.copyto(mv, prob.project_inplace(w).real)
                a = float(np.dot(flat(v), flat(mv)))
                np.multiply(v, a, out=tmp)
                mv -= tmp
                np.multiply(v_prev, beta_prev, out=tmp)
                mv -= tmp
                beta = float(np.sqrt(np.dot(flat(mv), flat(mv))))
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
                open_ = np.flatnonzero(done_at == 0)
                if stop_when_slow and open_.size and k >= first_prediction(maxiter) and k % 25 == 0:
                    pred = max(predicted_projections(hist[i], tol) for i in open_)
                    if pred > PREDICT[1] * maxiter:
                        worst = int(open_[np.argmax(res[open_])])
                        when = (f"never at its recent rate (no decrease over the last {k // 2} steps)"
                                if not np.isfinite(pred) else f"after ~{pred:.0f} steps")
                        raise ConvergenceError(
                            f"Lanczos predicted slow for loading e{j}: {open_.size} wavelength(s) above tol={tol:g} "
                            f"after {k} steps (worst relative residual {res[worst]:.3g} at index {worst}) would "
                            f"reach it {when}, beyond maxiter={maxiter}; raise maxiter or loosen tol",
                            history={"lanczos": hist[worst]})
                np.divide(mv, beta, out=v_prev)  # the next v, in the old v_prev's memory
                v_prev, v = v, v_prev
                beta_prev = beta
            projections.append(k + 1 + (d - 1 if c == 0 else 0))  # the other axes' b_i: with the first
            if np.any(done_at == 0):
                bad = np.flatnonzero(done_at == 0)
                raise ConvergenceError(
                    f"Lanczos reached maxiter={maxiter} for loading e{j} with {bad.size} wavelength(s) above "
                    f"tol={tol:g} (worst relative residual {res[bad].max():.3g} at index {int(bad[np.argmax(res[bad])])}); "
                    "raise maxiter or use fft_permittivity", history={"lanczos": hist[int(bad[0])]})
            al, be = np.asarray(alphas), np.asarray(betas)
            cr = {i: np.asarray(cross[i]) for i in others}
            for i in range(nw):
                if homog[i]:
                    tensor[i, :, j] = 0.0
                    tensor[i, j, j] = ea[i]
                    continue
                m = done_at[i]
                # (1,1) element of (T_m + s I)^{-1}: backward continued fraction
                cf = 1.0 / (al[m - 1] + s[i])
                for t in range(m - 2, -1, -1):
                    cf = 1.0 / (al[t] + s[i] - be[t] ** 2 * cf)
                tensor[i, j, j] = ea[i] + delta[i] * (f - beta0 ** 2 * cf / n)
                if others:
                    band = np.zeros((3, m), dtype=complex)
                    band[0, 1:] = be[:m - 1]
                    band[1] = al[:m] + s[i]
                    band[2, :-1] = be[:m - 1]
                    e1 = np.zeros(m, dtype=complex)
                    e1[0] = 1.0
                    y = solve_banded((1, 1), band, e1)
                    for o in others:
                        tensor[i, o, j] = -delta[i] * beta0 * np.dot(cr[o][:m], y) / n
                iterations[i, c] = m
                histories[i].append(hist[i])
    return tensor, iterations, histories, projections


def _register():
    from nmmm.homogenize.fft import SPECTRUM_METHODS

    SPECTRUM_METHODS["lanczos"] = lanczos_columns


_register()

__all__ = ["two_phase_spectrum", "lanczos_columns"]
