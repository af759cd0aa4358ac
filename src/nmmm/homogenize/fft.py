"""Effective permittivity tensor of a periodic voxel microstructure by FFT.

- :func:`fft_permittivity` — the public entry point: labels + {label: ε} (scalars or spectra)
  -> :class:`FFTHomogenization` with ``.tensor`` and ``.iterations``.
- :class:`FFTHomogenization` — the result: tensor, iteration counts, residual histories,
  optional local fields.

The quasi-static problem div(ε(x)(E0 + ∇φ)) = 0 with φ periodic is solved for the d unit
loadings E0 = e_j; the effective tensor is defined by ε_eff · E0 = ⟨ε E⟩. The default is the
Galerkin form solved by COCG (:mod:`nmmm.homogenize.solvers`) with Willot's rotated Green
operator (2015) (:mod:`nmmm.homogenize.green`); on failure BiCGStab then GMRES are tried, and if
every solver fails a :class:`nmmm.ConvergenceError` carrying the residual histories is
raised — never a silently wrong tensor.

Over a spectrum the FFT plans (scipy's cache), the buffers and the labels are set up once, and
the converged field of one wavelength seeds the next (``warm_start=True``).

Errors in ε_eff are first order in the voxel size for discontinuous ε; see
:func:`nmmm.homogenize.resolution.extrapolate_resolution`.

References
----------
- Moulinec, H., Suquet, P. (1998). Comput. Methods Appl. Mech. Eng. 157, 69-94.
- Vondřejc, J., Zeman, J., Marek, I. (2014). Comput. Math. Appl. 68(3), 156-173.
- Willot, F. (2015). C. R. Mécanique 343(3), 232-245.
- Azzimonti, D. F., Willot, F., Jeulin, D. (2013). Optical properties of deposit models for
  paints: full-fields FFT computations and representative volume element. J. Mod. Opt.
  60(7), 519-528. doi:10.1080/09500340.2013.791729
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
from tqdm.auto import tqdm

from nmmm.errors import ConvergenceError, InvalidInputError
from nmmm.homogenize.green import green_operator
from nmmm.homogenize.solvers import FALLBACKS, SOLVERS, Problem


@dataclass(frozen=True)
class FFTHomogenization:
    """Result of :func:`fft_permittivity`.

    Attributes
    ----------
    tensor : ndarray, complex
        Effective permittivity tensor, shape ``(d, d)``, or ``(n_wavelengths, d, d)`` when the
        permittivities were given as arrays over wavelength. Columns are ⟨ε E⟩ for E0 = e_j;
        only the loadings in ``directions`` are computed (other columns are NaN).
    iterations : ndarray of int
        Projections (applications of Γ, 2d FFTs each) per loading, shape ``(d_loads,)`` or
        ``(n_wavelengths, d_loads)``.
    residual_history : list
        Relative residual histories ‖r‖/‖b‖ per wavelength and loading (nested lists).
    solver : ndarray of str
        Solver that produced each entry (``"cocg"`` unless a fallback was used).
    green : str
        Green operator used.
    fractions : dict
        Volume fraction of each label.
    fields : ndarray or None
        With ``return_fields=True``: the local fields E, shape ``(d_loads, d, *grid)`` (or with a
        leading wavelength axis).
    """

    tensor: np.ndarray
    iterations: np.ndarray
    residual_history: list
    solver: np.ndarray
    green: str
    fractions: dict
    directions: tuple
    shape: tuple
    dtype: str
    fields: np.ndarray | None = None
    metadata: dict = field(default_factory=dict)

    @property
    def diagonal(self) -> np.ndarray:
        """The diagonal of the tensor, shape ``(..., d)``."""
        return np.diagonal(self.tensor, axis1=-2, axis2=-1)

    @property
    def mean(self) -> np.ndarray:
        """Trace / d: the orientation average of the tensor."""
        return np.mean(self.diagonal, axis=-1)


def _compact_labels(labels: np.ndarray):
    """Map arbitrary integer labels to 0..m−1 (uint8/int32); return (compact, values, counts)."""
    flat = labels.reshape(-1)
    lo, hi = int(flat.min()), int(flat.max())
    if lo >= 0 and hi < 1 << 16:
        counts = np.bincount(flat, minlength=hi + 1)
        values = np.flatnonzero(counts)
        lut = np.zeros(hi + 1, dtype=np.int32)
        lut[values] = np.arange(values.size)
        dtype = np.uint8 if values.size <= 255 else np.int32
        compact = lut.astype(dtype)[labels]
        return compact, values, counts[values]
    values, inverse, counts = np.unique(flat, return_inverse=True, return_counts=True)
    return inverse.reshape(labels.shape).astype(np.int32), values, counts


def _as_label_array(labels):
    """Accept an integer array or a Microstructure-like object (``.labels``)."""
    meta = {}
    if hasattr(labels, "labels") and not isinstance(labels, np.ndarray):
        ms = labels
        meta["voxel_nm"] = getattr(ms, "voxel_nm", None)
        meta["periodic"] = getattr(ms, "periodic", True)
        meta["phases"] = getattr(ms, "phases", None)
        labels = ms.labels
    arr = np.asarray(labels)
    if arr.dtype == bool:
        arr = arr.astype(np.uint8)
    if arr.dtype.kind not in "iu":
        if arr.dtype.kind == "f" and np.all(np.isfinite(arr)) and np.all(arr == np.round(arr)):
            arr = arr.astype(np.int64)
        else:
            raise InvalidInputError(
                f"labels must be an integer array (one phase label per voxel), got dtype {arr.dtype}"
            )
    if arr.ndim not in (2, 3):
        raise InvalidInputError(f"labels must be a 2-D or 3-D voxel grid, got {arr.ndim}-D shape {arr.shape}")
    if min(arr.shape) < 1:
        raise InvalidInputError(f"labels grid is empty: shape {arr.shape}")
    return arr, meta


def _eps_table(values, eps, wavelength_nm=None):
    """Build the (n_wavelengths, n_phases) permittivity table; scalar flag."""
    if hasattr(eps, "items"):
        lookup = dict(eps.items())
    elif isinstance(eps, (list, tuple, np.ndarray)) and np.ndim(eps) >= 1:
        lookup = dict(enumerate(eps))
    else:
        raise InvalidInputError(
            f"eps must map each label to its permittivity, e.g. {{0: 2.25, 1: -50 + 20j}} "
            f"(or be a sequence indexed by label), got {type(eps).__name__} {eps!r}"
        )
    missing = [int(v) for v in values if int(v) not in lookup]
    if missing:
        raise InvalidInputError(
            f"labels {missing} have no permittivity; give eps for every label present "
            f"(labels present: {[int(v) for v in values]}, eps given for: {sorted(lookup)})"
        )
    cols = []
    scalar = True
    for v in values:
        e = lookup[int(v)]
        if hasattr(e, "eps") and callable(e.eps):  # a Material
            if wavelength_nm is None:
                raise InvalidInputError(
                    f"label {int(v)} is a Material ({e!r}): pass wavelength_nm to evaluate it"
                )
            e = e.eps(wavelength_nm)
        a = np.asarray(e)
        if a.dtype.kind not in "biufc":
            raise InvalidInputError(f"permittivity of label {int(v)} is not numeric: {e!r}")
        a = a.astype(complex)
        if a.ndim > 1:
            raise InvalidInputError(
                f"permittivity of label {int(v)} must be a scalar or a 1-D array over wavelength, got shape {a.shape}"
            )
        if a.ndim == 1:
            if a.size == 0:
                raise InvalidInputError(f"permittivity of label {int(v)} is an empty array; give one value per wavelength")
            scalar = False
        if not np.all(np.isfinite(a)):
            raise InvalidInputError(f"permittivity of label {int(v)} contains NaN or infinity; give finite values")
        if np.any(a.imag < 0):
            raise InvalidInputError(
                f"permittivity of label {int(v)} has Im(ε) < 0 (min {a.imag.min():g}); nmmm uses "
                "exp(-iωt), so absorbing media have Im(ε) >= 0"
            )
        cols.append(a)
    try:
        table = np.stack(np.broadcast_arrays(*[np.atleast_1d(c) for c in cols]), axis=-1)
    except ValueError:
        shapes = [np.shape(c) for c in cols]
        raise InvalidInputError(f"permittivity arrays of the phases have different lengths: {shapes}") from None
    return table, scalar


def fft_permittivity(
    labels,
    eps,
    *,
    green: str = "willot2015",
    solver: str = "cocg",
    tol: float | None = None,
    maxiter: int = 5000,
    fallback: bool = True,
    dtype="complex128",
    directions=None,
    warm_start: bool = True,
    return_fields: bool = False,
    wavelength_nm=None,
    voxel_nm=None,
    check_periodic: bool = True,
    periodize: str | None = None,
    workers: int = 2,
    progress: bool | None = None,
) -> FFTHomogenization:
    """Effective permittivity tensor of a periodic voxel microstructure (FFT, quasi-static).

    Parameters
    ----------
    labels : int array (2-D or 3-D) or Microstructure
        Phase label of each voxel; the cell is taken as periodic.
    eps : mapping label -> ε (or a sequence indexed by label)
        Complex permittivity of each phase (Im ε ≥ 0): scalars, or 1-D arrays over wavelength
        (all of the same length), or Materials (then ``wavelength_nm`` is required).
    green : {"willot2015", "willot2014", "continuous"}
        Green operator (:data:`nmmm.homogenize.green.GREEN_OPERATORS`). The default, Willot's
        rotated scheme (2015), was the most accurate at a given resolution on the exact
        references (coated sphere, Keller duality) and, like the finite-difference one of
        Willot et al. (2014), needs few iterations for metal-dielectric contrasts (44-52
        projections against 156-2000 for the spectral one on a 2-D Boolean model with
        ε = −50 + {20, 5}i). Its known weakness: voxels touching only at a corner are
        connected (the checkerboard converges only as 1/N); use "willot2014" or
        "continuous" for such contact-dominated cells.
    solver : {"cocg", "bicgstab", "gmres", "eyre_milton", "basic"}
        Iterative solver (:data:`nmmm.homogenize.solvers.SOLVERS`).
    tol : float
        Relative residual ‖Γ ε E‖ / ‖Γ ε E0‖ (Krylov solvers) or relative step (fixed points);
        default 1e-6 (complex128) or 1e-5 (complex64).
    maxiter : int
        Maximum number of projections per loading.
    fallback : bool
        If the solver fails, try BiCGStab then GMRES before raising ConvergenceError.
    dtype : {"complex128", "complex64"}
        Precision of the fields (complex64 halves memory and FFT time).
    directions : sequence of int, optional
        Loadings to compute (default all d); other columns of the tensor are NaN.
    warm_start : bool
        Seed each wavelength with the previous wavelength's field.
    return_fields : bool
        Keep the local fields E (memory: d² complex fields per wavelength).
    wavelength_nm, voxel_nm : optional
        For Materials and for the quasi-static validity warning
        (:func:`nmmm.homogenize.validity.check_quasistatic`).
    check_periodic : bool
        Warn when opposite faces of the cell do not match as well as neighbouring slices do.
    periodize : {None, "mirror"}
        ``"mirror"`` doubles the cell by mirror images along every axis, which makes any
        cell periodic (the result is then that of the mirrored cell).
    workers : int
        Threads for scipy.fft and Numba.

    Returns
    -------
    FFTHomogenization

    Examples
    --------
    A laminate: arithmetic mean along the layers, harmonic mean across (exact).

    >>> import numpy as np
    >>> lab = np.zeros((8, 4), dtype=int); lab[4:] = 1
    >>> r = fft_permittivity(lab, {0: 2.25, 1: -10 + 1j})
    >>> complex(np.round(r.tensor[1, 1], 6))   # along the layers: (2.25 - 10 + 1i) / 2
    (-3.875+0.5j)
    """
    arr, meta = _as_label_array(labels)
    if voxel_nm is None:
        voxel_nm = meta.get("voxel_nm")
    if meta.get("periodic") is False and periodize is None:
        raise InvalidInputError(
            "the microstructure is not periodic but the FFT solver assumes a periodic cell; "
            "generate a periodic one, or pass periodize='mirror' to mirror it explicitly"
        )
    if periodize is not None:
        from nmmm.homogenize.validity import periodize_mirror

        if periodize != "mirror":
            raise InvalidInputError(f"periodize must be None or 'mirror', got {periodize!r}")
        arr = periodize_mirror(arr)
    elif check_periodic:
        from nmmm.homogenize.validity import check_periodicity

        check_periodicity(arr, warn=True)
    dt = np.dtype(dtype)
    if dt not in (np.complex64, np.complex128):
        raise InvalidInputError(f"dtype must be complex64 or complex128, got {dtype!r}")
    if tol is None:
        tol = 1e-6 if dt == np.complex128 else 1e-5
    if not (0 < tol < 1):
        raise InvalidInputError(f"tol must lie in (0, 1), got {tol}")
    if isinstance(maxiter, bool) or not isinstance(maxiter, (int, np.integer)) or maxiter < 1:
        raise InvalidInputError(f"maxiter must be a positive integer (projections per loading), got {maxiter!r}")
    key = str(solver).lower().replace("-", "_")
    if key not in SOLVERS:
        raise InvalidInputError(f"unknown solver {solver!r}; choose one of {sorted(SOLVERS)}")
    compact, values, counts = _compact_labels(arr)
    table, scalar = _eps_table(values, eps, wavelength_nm)
    if wavelength_nm is not None and voxel_nm is not None:
        from nmmm.homogenize.validity import check_quasistatic

        check_quasistatic(arr, voxel_nm, wavelength_nm, table, values, warn=True)
    d = arr.ndim
    dirs = tuple(range(d)) if directions is None else tuple(int(j) for j in directions)
    if not dirs or any(j < 0 or j >= d for j in dirs):
        raise InvalidInputError(f"directions must be axes in 0..{d - 1}, got {directions!r}")
    spacing = None
    if voxel_nm is not None:
        spacing = np.broadcast_to(np.asarray(voxel_nm, dtype=float), (d,))
        spacing = tuple(spacing / spacing.min())
    op = green_operator(arr.shape, green, spacing=spacing)
    problem = Problem(compact, values.size, op, dt, workers)
    nw = table.shape[0]
    tensor = np.full((nw, d, d), np.nan + 0j)
    iterations = np.zeros((nw, len(dirs)), dtype=int)
    solvers_used = np.empty((nw, len(dirs)), dtype=object)
    histories: list = []
    fields = np.zeros((nw, len(dirs), d) + arr.shape, dtype=dt) if return_fields else None
    previous = [None] * len(dirs)
    keep_x = warm_start or return_fields
    bar = tqdm(total=nw * len(dirs), desc="FFT homogenization", unit="solve",
               disable=(nw * len(dirs) < 4) if progress is None else not progress, leave=False)
    try:
        for w in range(nw):
            tab = table[w]
            hist_w = []
            for c, j in enumerate(dirs):
                e0 = np.zeros(d, dtype=complex)
                e0[j] = 1.0
                x0 = previous[c] if warm_start else None
                order = [key] + ([s for s in FALLBACKS if s != key] if fallback else [])
                attempts = []
                out = None
                for name in order:
                    out = SOLVERS[name](problem, tab, e0, x0=x0, tol=tol, maxiter=maxiter, keep_x=keep_x)
                    attempts.append(out)
                    if out.converged:
                        break
                    warnings.warn(f"{out.message}; trying the next solver", RuntimeWarning, stacklevel=2)
                if not out.converged:
                    hist = {a.solver: a.history for a in attempts}
                    where = f" at wavelength index {w}" if not scalar else ""
                    raise ConvergenceError(
                        f"FFT homogenization did not converge for loading e{j}{where} with eps = "
                        f"{np.round(tab, 4).tolist()}: " + "; ".join(a.message for a in attempts)
                        + ". Metal-like contrasts at sharp corners (e.g. a checkerboard) may have no "
                        "converging solution; try another Green operator, a larger maxiter, or a looser tol",
                        history=hist,
                    )
                tensor[w, :, j] = out.flux
                iterations[w, c] = sum(a.iterations for a in attempts)
                solvers_used[w, c] = out.solver
                hist_w.append(out.history)
                if warm_start:
                    previous[c] = out.x
                if return_fields:
                    fields[w, c] = (out.x + e0.astype(dt)[:, None]).reshape((d,) + arr.shape)
                bar.update(1)
            histories.append(hist_w)
    finally:
        bar.close()
    fractions = {int(v): float(cnt) / arr.size for v, cnt in zip(values, counts)}
    if scalar:
        tensor, iterations, solvers_used = tensor[0], iterations[0], solvers_used[0]
        histories = histories[0]
        fields = None if fields is None else fields[0]
    return FFTHomogenization(
        tensor=tensor,
        iterations=iterations,
        residual_history=histories,
        solver=solvers_used,
        green=op.name,
        fractions=fractions,
        directions=dirs,
        shape=tuple(arr.shape),
        dtype=dt.name,
        fields=fields,
        metadata={"tol": tol, "voxel_nm": voxel_nm},
    )


__all__ = ["fft_permittivity", "FFTHomogenization"]
