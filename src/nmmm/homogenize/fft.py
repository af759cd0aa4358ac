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
from nmmm.homogenize.prediction import (PREDICT, PREDICT_FROM, first_prediction, flux_prediction,  # noqa: F401
                                        predicted_projections, slow_solve_monitor, solve_prediction)
from nmmm.homogenize.solvers import FALLBACKS, FLUX_TOL_MIN, FLUX_WINDOW, SOLVERS, Problem, pair_terms


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
        ``(n_wavelengths, d_loads)``. For ``metadata["method"] == "lanczos"``: the Lanczos step at
        which each wavelength converged (the run of a loading costs its slowest wavelength's:
        ``metadata["projections"]`` per loading).
    residual_history : list
        Relative residual histories ‖r‖/‖b‖ per wavelength and loading (nested lists).
    solver : ndarray of str
        Solver that produced each entry (``"cocg"`` unless a fallback was used; ``"lanczos"``
        for a spectrum solved by one Lanczos run per loading).
    green : str
        Green operator used.
    fractions : dict
        Volume fraction of each label.
    fields : ndarray or None
        With ``return_fields=True``: the local fields E, shape ``(d_loads, d, *grid)`` (or with a
        leading wavelength axis).
    switches : tuple of dict
        Every automatic choice or switch the solve made, in order: the Green operator chosen for
        ``green=None`` (``{"what": "green", "from": ..., "to": ..., "reason": ...}``) and each
        fallback after a failed solve (``"what": "green"`` or ``"solver"``, with
        ``"wavelength_index"``, ``"loading"``, and the failed attempt's ``"projections"``,
        ``"residual_reached"`` and ``"predicted_projections"``), complex64 promoted to complex128
        (``"what": "dtype"``), the spectrum method taken by ``method="auto"`` (``"what": "method"``),
        and, once, COCG's flux rule (``"what": "stop"``, ``"from": "residual"``, ``"to": "flux"``)
        when ``stop="auto"`` let a solve converge on the estimated error of its flux rather than on
        its residual: which solves did, their estimated errors (of ε_jj, and, where some of the
        column's off-diagonal terms could not be paired with another loading's solve, of those
        relative to |ε_jj|) and the residuals they reached are
        ``metadata["stop"]``, ``metadata["flux_error"]``, ``metadata["offdiagonal_error"]`` and
        ``metadata["residual_reached"]`` (one entry per wavelength and loading, like
        ``iterations``). Empty when nothing was switched.
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
    switches: tuple = ()

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


#: The operator of ``green=None`` ("auto") and its alternative for metal-dielectric 3-D cells.
AUTO_GREEN = "willot2015"
AUTO_GREEN_METAL_3D = "willot2014"


#: A metal phase is "low-loss" when Im ε < LOW_LOSS |ε| (−50 + 5i: 0.10; −44 + 13i: 0.28).
LOW_LOSS = 0.15

#: With ``green=None``, a COCG whose best residual is still above PROBE[1] after PROBE[0]
#: projections is stopped and the other Willot operator takes over (it would need > ~400).
PROBE = (150, 1e-2)

#: With ``green=None`` and ``dtype="complex64"``, a 3-D cell with a low-loss metal beside a
#: dielectric is solved in complex128 when ``tol`` is below this (reported in ``switches``):
#: complex64 COCG stalls there above 1e-5 (64³, ε = −50 + 1i in 2.25: Boolean spheres at
#: 1.07e-5, flakes at 6.3e-5 after 1001 projections), complex128 converges in 118-505
#: (benchmarks/bench_fft_metals.py).
COMPLEX64_METAL_TOL = 1e-4


#: Ways of solving a spectrum (``method=``): "auto" chooses between the other two.
METHODS = ("auto", "per_wavelength", "lanczos")

#: When a COCG solve has converged (``stop=``): "auto" adds the flux rule when no fields are asked.
STOPS = ("auto", "residual")

#: Registry of whole-spectrum methods: name -> ``f(compact_labels, counts, table, op, directions,
#: tol, maxiter, workers, stop_when_slow) -> (tensor, iterations, histories, projections)``.
#: "lanczos" is registered by :mod:`nmmm.homogenize.bergman_lanczos` (imported with the package),
#: which uses this module's input checks, so this module does not import it.
SPECTRUM_METHODS: dict = {}


def metal_dielectric(table, low_loss: float | None = None) -> bool:
    """True when the phases mix Re ε < 0 (metal-like) with Re ε > 0 at some wavelength; with
    ``low_loss``, only when such a metal phase also has Im ε < low_loss · |ε|."""
    t = np.atleast_2d(np.asarray(table))
    re = t.real
    metal = re < 0
    if low_loss is not None:
        metal &= t.imag < low_loss * np.abs(t)
    return bool(np.any(metal.any(axis=-1) & (re.max(axis=-1) > 0)))


def auto_green(ndim: int, table) -> tuple[str, str]:
    """The Green operator of ``green=None`` for a cell of ``ndim`` dimensions and phase table
    ``(n_wavelengths, n_phases)``, and the reason (measured in benchmarks/bench_fft_metals.py).

    Willot's rotated operator (2015) is the most accurate at a given resolution on the exact
    references (it keeps the metal-core Hashin sphere within 3 % at 32³, the finite-difference
    one does not), but on 3-D cells with a low-loss metal (Boolean spheres, p = 0.2, in 2.25,
    complex64, tol 1e-5) its COCG needs 552 projections at −50 + 5i, stalls near 3e-4 at
    −50 + 2i (1111 projections in complex128) and stands at 0.07 after 300 projections at
    128³; the finite-difference operator of Willot et al. (2014) converges there in 300-450.
    At −44 + 13i (aluminium at 550 nm) and −50 + 20i the rotated operator converges in 184 and
    144. So: "willot2014" for 3-D cells with a metal phase of Im ε < :data:`LOW_LOSS` |ε| next
    to a dielectric at any wavelength, else "willot2015". The whole spectrum uses one operator,
    so that ε_eff(λ) has no jump between wavelengths; a COCG that is still slow after
    :data:`PROBE` switches to the other operator (reported).
    """
    if ndim == 3 and metal_dielectric(table, LOW_LOSS):
        return AUTO_GREEN_METAL_3D, (f"3-D cell with a low-loss metal (Re ε < 0, Im ε < {LOW_LOSS} |ε|) beside a "
                                     "dielectric: COCG with the rotated operator stalls there, the finite-difference "
                                     "one converges")
    return AUTO_GREEN, "default operator"



def auto_spectrum_method(n_phases: int, table, solver: str = "cocg", dtype="complex128",
                         return_fields: bool = False) -> tuple[str, str]:
    """What ``method="auto"`` of :func:`fft_permittivity` takes for the spectrum ``table``
    (wavelengths × phases), and why: one Lanczos run per loading for a two-phase cell over several
    wavelengths solved by COCG without local fields, when
    :func:`~nmmm.homogenize.work_estimate.choose_spectrum_method` estimates it cheaper; otherwise
    per-wavelength solves. Never with a low-loss metal: there finite-precision Lanczos (no
    reorthogonalisation) falls behind COCG and its estimated residual is no longer the true one
    (64³, willot2014, tol 1e-5: flakes −50 + 1i 1284 steps vs COCG 498 and ε_xx 2.3e-3 apart, COCG's
    true residual 9.7e-6; Boolean spheres −50 + 1i 540 vs 304, 6.4e-5 apart; flakes −50 + 5i 419 vs
    291, 5.8e-6 apart), while at −44 + 13i both take 181 and agree to 4e-11. Also used by
    :mod:`~nmmm.homogenize.spectral_batches` to plan its tasks."""
    from nmmm.homogenize.work_estimate import choose_spectrum_method

    if (n_phases != 2 or table.shape[0] < 2 or solver != "cocg" or return_fields
            or metal_dielectric(table, LOW_LOSS)):
        return "per_wavelength", ("one wavelength, another solver, local fields, more than two phases or a "
                                  "low-loss metal (Lanczos drifts there)")
    return choose_spectrum_method(table.shape[0], dtype)


def fft_permittivity(
    labels,
    eps,
    *,
    green: str | None = None,
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
    max_memory_gb: float | None = None,
    max_minutes: float | None = None,
    work_advice: str | None = None,
    method: str = "auto",
    stop: str = "auto",
    _decide_on=None,
) -> FFTHomogenization:
    """Effective permittivity tensor of a periodic voxel microstructure (FFT, quasi-static).

    Parameters
    ----------
    labels : int array (2-D or 3-D) or Microstructure
        Phase label of each voxel; the cell is taken as periodic.
    eps : mapping label -> ε (or a sequence indexed by label)
        Complex permittivity of each phase (Im ε ≥ 0): scalars, or 1-D arrays over wavelength
        (all of the same length), or Materials (then ``wavelength_nm`` is required).
    green : {None, "willot2015", "willot2014", "continuous"}
        Green operator (:data:`nmmm.homogenize.green.GREEN_OPERATORS`). ``None`` (default)
        chooses automatically (:func:`auto_green`): Willot's rotated scheme (2015), except for
        3-D cells with a metal-dielectric contrast, which get the finite-difference operator of
        Willot et al. (2014) (the rotated one's COCG stalls there); the choice is reported in
        ``result.switches``, and if COCG fails, the other of the two operators is tried before
        the other solvers. Willot's rotated scheme (2015) was the most accurate at a given resolution on the exact
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
        default 1e-6 (complex128) or 1e-5 (complex64). With COCG and no local fields asked
        (``stop="auto"``), a solve also converges when the estimated relative error of the
        computed diagonal entry ε_jj is ≤ ``tol`` (see ``stop``).
    maxiter : int
        Maximum number of projections per loading.
    fallback : bool
        If the solver fails (or stalls), try — with ``green=None`` — COCG with the other of the
        two Willot operators, then BiCGStab and GMRES, before raising ConvergenceError; every
        switch is reported in ``result.switches``.
    dtype : {"complex128", "complex64"}
        Precision of the fields (complex64 halves memory and FFT time). With ``green=None``,
        complex64 on a 3-D cell with a low-loss metal and ``tol`` < :data:`COMPLEX64_METAL_TOL`
        is solved in complex128 instead (complex64 stalls there), reported in ``switches``.
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
    max_memory_gb, max_minutes : float, optional
        Limits of the work estimated before the solve starts
        (:func:`nmmm.homogenize.work_estimate.check_fft_work`; defaults half the physical memory
        and 30 minutes): beyond them the call is refused with the estimate. ``float('inf')``
        lifts a limit. A solve estimated above a minute shows a progress bar.
    work_advice : str, optional
        What the refusal beyond those limits tells the caller's user to change, in the caller's
        terms (a recipe's keys); default: this function's arguments and the CLI options.
    method : {"auto", "per_wavelength", "lanczos"}
        How a spectrum is solved (:data:`METHODS`). ``"per_wavelength"``: one ``solver`` solve per
        wavelength and loading, warm-started. ``"lanczos"``: a two-phase cell at every wavelength
        from one Lanczos run per loading (:func:`nmmm.homogenize.bergman_lanczos.lanczos_columns`,
        Bergman's spectral representation; real float64 fields, no local fields). ``"auto"``
        (default) takes "lanczos" for a two-phase cell over several wavelengths with the default
        solver, no ``return_fields`` and no low-loss metal (Im ε < :data:`LOW_LOSS` |ε|, where
        finite-precision Lanczos falls behind COCG and drifts from it: see the source) when its
        estimated time is lower
        (:func:`nmmm.homogenize.work_estimate.choose_spectrum_method`), reported in
        ``result.switches`` and ``metadata["method"]`` (why: ``metadata["method_reason"]``); a
        Lanczos run that "auto" chose and that does not converge within ``maxiter`` hands over to
        per-wavelength solves (reported).
    stop : {"auto", "residual"}
        When a COCG solve has converged. ``"residual"``: relative residual ≤ ``tol``. ``"auto"``
        (default): the same with ``return_fields=True``; without local fields, also when the
        estimated relative error of ε_jj (j the loading) is ≤ ``tol`` — the flux rule of
        :func:`~nmmm.homogenize.solvers.solve_cocg`: ε_jj as COCG's Gauss quadrature of bᵀA⁻¹b
        (complex128; complex64: the flux of the iterate), its error estimated by its path over the
        last :data:`~nmmm.homogenize.solvers.FLUX_WINDOW` (30) projections. ε_eff converges much
        faster than the residual: on the 24 metal cases of benchmarks/bench_fft_metals.py (64³,
        128³; tol 1e-3 to 1e-6) the rule never stopped with a true error above 0.15 ``tol`` (0.46
        on a wider replay, see FLUX_WINDOW), and 128³ flakes at −50 + 5i, 2i, 1i (tol 1e-5) stop
        after 358, 816 and 1497 projections instead of 572, 1346 and 2256 (residuals 1e-3 to 2e-3
        reached; ε_xx 1.7e-7, 1.1e-7 and 7.1e-7 off). Off-diagonal terms: the iterate's flux alone
        is off by an error linear in the residual (up to 2.2e-4 of |ε_jj| at such stops), so with
        several loadings ε_ij = ε_ji is taken from both loadings' solves, T_ij(x_j) − x_iᵀ r_j / N
        (error quadratic; ≤ 0.015 tol on 24³-48³ spheres and flakes at −50 + 1, 2i and −44 + 13i,
        where the residual rule's are 0.1-0.6 tol); the field of every loading but the last is
        then kept (one field per loading; not where those fields would pass ``max_memory_gb``: then no
        pairing, as with one loading).
        With one loading (``directions=[j]``) the column's off-diagonal terms stay the iterate's
        flux: ``metadata["offdiagonal_error"]`` is their path over the window (11-840× above their
        true error on the 64³-128³ cells); ``stop="residual"`` there when they must be within
        ``tol``. Not below :data:`~nmmm.homogenize.solvers.FLUX_TOL_MIN` (1e-5 in complex64,
        1e-10 in complex128: the estimate's rounding floor). Reported in ``switches`` and
        ``metadata`` (see :class:`FFTHomogenization`).

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
    mkey = str(method).lower().replace("-", "_")
    if mkey not in METHODS:
        raise InvalidInputError(f"unknown method {method!r}; choose one of {list(METHODS)}")
    if stop not in STOPS:
        raise InvalidInputError(f"unknown stop {stop!r}; choose one of {list(STOPS)}")
    # COCG's flux rule: ε_jj's estimated error (no local fields asked, so none is less converged)
    flux_rule = stop == "auto" and not return_fields
    compact, values, counts = _compact_labels(arr)
    table, scalar = _eps_table(values, eps, wavelength_nm)
    if mkey == "lanczos":
        if values.size != 2:
            raise InvalidInputError(f"method='lanczos' needs a two-phase cell, got labels {values.tolist()}; "
                                    "use method='per_wavelength'")
        if return_fields:
            raise InvalidInputError("method='lanczos' gives no local fields; use method='per_wavelength' with "
                                    "return_fields=True")
        if key != "cocg":
            raise InvalidInputError(f"method='lanczos' is its own solver; solver={solver!r} needs "
                                    "method='per_wavelength'")
    # the automatic choices look at the whole spectrum; a chunk of it (spectral_batches) passes the
    # whole table in ``_decide_on`` so that every chunk takes the same operator and precision
    decide = table if _decide_on is None else np.asarray(_decide_on)
    promoted = None
    if (green is None and dt == np.complex64 and tol < COMPLEX64_METAL_TOL and arr.ndim == 3
            and metal_dielectric(decide, LOW_LOSS)):
        dt = np.dtype(np.complex128)
        promoted = {"what": "dtype", "from": "complex64", "to": "complex128",
                    "reason": f"3-D cell with a low-loss metal: complex64 COCG stalls above tol={tol:g} there "
                              f"(measured floors 1e-5 to 6e-5); complex128 converges"}
    if wavelength_nm is not None and voxel_nm is not None:
        from nmmm.homogenize.validity import check_quasistatic

        check_quasistatic(arr, voxel_nm, wavelength_nm, table, values, warn=True)
    d = arr.ndim
    dirs = tuple(range(d)) if directions is None else tuple(int(j) for j in directions)
    if not dirs or any(j < 0 or j >= d for j in dirs):
        raise InvalidInputError(f"directions must be axes in 0..{d - 1}, got {directions!r}")
    from nmmm.homogenize.work_estimate import check_fft_work

    method_switch = None
    method_reason = f"method={method!r} asked"
    if mkey == "auto":
        # on the whole spectrum (``decide``), so that every chunk of spectral_batches takes the same method
        mkey, why = auto_spectrum_method(values.size, decide, key, dt, return_fields)
        method_reason = "auto: " + why
        if mkey == "lanczos":
            method_switch = {"what": "method", "from": "per_wavelength", "to": "lanczos", "reason": why}
    # the flux rule's off-diagonal pairing keeps the field of every loading but the last (solvers.pair_terms);
    # where those fields would pass the memory limit, no pairing (the off-diagonal terms' path bound is reported)
    kept = len(dirs) - 1 if (stop == "auto" and not return_fields and key == "cocg" and mkey != "lanczos"
                             and tol >= FLUX_TOL_MIN[dt]) else 0
    work_args = dict(n_wavelengths=table.shape[0], n_loadings=len(dirs), dtype=dt, metal=metal_dielectric(table),
                     max_memory_gb=max_memory_gb, max_minutes=max_minutes, advice=work_advice, method=mkey)
    try:
        work = check_fft_work(arr.shape, kept_fields=kept, **work_args)
    except InvalidInputError:
        if not kept:
            raise
        work = check_fft_work(arr.shape, **work_args)  # refused here too: the error names the limit
        kept = 0
    spacing = None
    if voxel_nm is not None:
        spacing = np.broadcast_to(np.asarray(voxel_nm, dtype=float), (d,))
        spacing = tuple(spacing / spacing.min())
    switches: list = []
    auto = green is None
    if auto:
        green, reason = auto_green(arr.ndim, decide)
        if green != AUTO_GREEN:
            switches.append({"what": "green", "from": AUTO_GREEN, "to": green, "reason": reason})
        if promoted is not None:
            switches.append(promoted)
    op = green_operator(arr.shape, green, spacing=spacing)
    fractions = {int(v): float(cnt) / arr.size for v, cnt in zip(values, counts)}
    if mkey == "lanczos":
        lanczos_columns = SPECTRUM_METHODS["lanczos"]
        if method_switch is not None:
            switches.append(method_switch)
        try:
            tensor, iterations, histories, projections = lanczos_columns(compact, counts, table, op, dirs, tol,
                                                                         maxiter, workers, stop_when_slow=fallback)
        except ConvergenceError as exc:
            if method_switch is None:  # method="lanczos" asked: no other method is tried
                raise
            # auto: finite-precision Lanczos takes a few % more steps than COCG (24³ spheres at −50 + 8i:
            # 349 vs 301), so a maxiter that per-wavelength COCG meets may stop it; those solves decide
            mkey = "per_wavelength"
            method_reason += f"; the Lanczos run did not converge, per-wavelength solves took over: {exc}"
            switches.append({"what": "method", "from": "lanczos", "to": "per_wavelength", "reason": str(exc)})
            warnings.warn(f"{exc}; solving per wavelength", RuntimeWarning, stacklevel=2)
    if mkey == "lanczos":
        if promoted in switches:  # Lanczos runs on real float64 fields whatever dtype was asked
            switches.remove(promoted)
        solvers_used = np.full(iterations.shape, "lanczos", dtype=object)
        greens_used = np.full(iterations.shape, op.name, dtype=object)
        if scalar:
            tensor, iterations, solvers_used, greens_used = tensor[0], iterations[0], solvers_used[0], greens_used[0]
            histories = histories[0]
        return FFTHomogenization(
            tensor=tensor, iterations=iterations, residual_history=histories, solver=solvers_used, green=op.name,
            fractions=fractions, directions=dirs, shape=tuple(arr.shape), dtype="complex128",
            metadata={"tol": tol, "voxel_nm": voxel_nm, "green_used": greens_used, "method": "lanczos",
                      "method_reason": method_reason, "projections": projections},
            switches=tuple(switches))
    problem = Problem(compact, values.size, op, dt, workers)
    alternative = None  # (Problem with the other Willot operator), built on first need
    nw = table.shape[0]
    tensor = np.full((nw, d, d), np.nan + 0j)
    iterations = np.zeros((nw, len(dirs)), dtype=int)
    solvers_used = np.empty((nw, len(dirs)), dtype=object)
    greens_used = np.empty((nw, len(dirs)), dtype=object)
    histories: list = []
    stops = np.empty((nw, len(dirs)), dtype=object)
    flux_errors = np.full((nw, len(dirs)), np.nan)
    off_errors = np.full((nw, len(dirs)), np.nan)
    paired = np.empty((nw, len(dirs)), dtype=object)  # the loadings each solve's off-diagonal terms were paired with
    for idx in np.ndindex(paired.shape):
        paired[idx] = set()
    residuals = np.full((nw, len(dirs)), np.nan)
    fields = np.zeros((nw, len(dirs), d) + arr.shape, dtype=dt) if return_fields else None
    previous = [None] * len(dirs)
    # off-diagonal terms of flux-rule solves from two loadings' fields (solvers.pair_terms): each loading's field is
    # kept until the later loadings' residuals have met it
    pairs = flux_rule and key == "cocg" and len(dirs) > 1 and tol >= FLUX_TOL_MIN[dt] and kept > 0
    keep_x = return_fields or (warm_start and nw > 1)  # a single wavelength seeds nothing
    bar = tqdm(total=nw * len(dirs), desc="FFT homogenization", unit="solve",
               disable=(nw * len(dirs) < 4 and work["seconds"] < 60) if progress is None else not progress,
               leave=False)
    try:
        for w in range(nw):
            tab = table[w]
            hist_w = []
            finals = []  # (column, x, Problem) of this wavelength's COCG solves, for pair_terms
            for c, j in enumerate(dirs):
                e0 = np.zeros(d, dtype=complex)
                e0[j] = 1.0
                x0 = previous[c] if warm_start else None
                order = [(key, problem)]
                if fallback:
                    if auto and key == "cocg" and d == 3 and op.name in (AUTO_GREEN, AUTO_GREEN_METAL_3D):
                        if alternative is None:
                            other = AUTO_GREEN_METAL_3D if op.name == AUTO_GREEN else AUTO_GREEN
                            alternative = Problem(compact, values.size, green_operator(arr.shape, other, spacing=spacing),
                                                  dt, workers)
                        order.append(("cocg", alternative))
                    order += [(s, problem) for s in FALLBACKS if s != key]
                attempts = []
                out = None
                i = -1
                while i + 1 < len(order):
                    i += 1
                    name, prob = order[i]
                    x_start = x0 if prob is problem else None
                    extra = {}
                    if i == 0 and op.name == AUTO_GREEN and len(order) > 1 and order[1][1] is not problem:
                        extra["probe"] = PROBE  # auto mode: leave a slow operator early
                    if fallback and name == "cocg":  # default path: stop a solve predicted beyond maxiter
                        extra["monitor"] = slow_solve_monitor(tol, maxiter)
                    if flux_rule and name == "cocg" and tol >= FLUX_TOL_MIN[prob.dtype]:
                        extra["flux_tol"] = tol
                        extra["keep_r"] = pairs
                    # pairs: every loading's field but the last one's is met by a later residual
                    keep = keep_x or (pairs and c < len(dirs) - 1)
                    out = SOLVERS[name](prob, tab, e0, x0=x_start, tol=tol, maxiter=maxiter, keep_x=keep, **extra)
                    out.green = prob.op.name
                    attempts.append(out)
                    if out.converged:
                        break
                    out.x = out.r = None  # a failed attempt's fields: only its history and message are used
                    if fallback and name == "cocg" and (
                            out.message.startswith("predicted slow")
                            or (out.message.startswith("COCG reached maxiter") and out.iterations > PREDICT[0]
                                and np.isfinite(solve_prediction(out, tol)))):
                        # converging too slowly (a near-singular, near-resonant system), not a breakdown:
                        # BiCGStab and GMRES measured worse there (64³ flakes, −50 + 1i, willot2014: best
                        # residual 0.11 and 0.027 after 600 projections where COCG converged in 495);
                        # only COCG with the other operator is still tried
                        order[i + 1:] = [(nm, pb) for nm, pb in order[i + 1:] if nm == "cocg"]
                    if i + 1 < len(order):
                        nxt_name, nxt = order[i + 1]
                        what = "green" if nxt is not prob else "solver"
                        switches.append({"what": what, "wavelength_index": w, "loading": j,
                                         "from": f"{name}/{prob.op.name}", "to": f"{nxt_name}/{nxt.op.name}",
                                         "reason": out.message, "projections": int(out.iterations),
                                         "residual_reached": float(min(out.history)),
                                         "predicted_projections": float(solve_prediction(out, tol))})
                    warnings.warn(f"{out.message}; trying the next solver", RuntimeWarning, stacklevel=2)
                if not out.converged:
                    hist = {(a.solver if a.green == op.name else f"{a.solver}@{a.green}"): a.history for a in attempts}
                    where = f" at wavelength index {w}" if not scalar else ""
                    slow = [solve_prediction(a, tol) for a in attempts
                            if a.message.startswith(("predicted slow", "COCG reached maxiter")) and a.iterations > PREDICT[0]]
                    hint = ("Metal-like contrasts at sharp corners (e.g. a checkerboard) may have no "
                            "converging solution; try another Green operator, a larger maxiter, or a looser tol")
                    if slow and np.isfinite(min(slow)):
                        hint = (f"A low-loss metal near a plasmon resonance of the cell makes the system near-singular "
                                f"(no solver or operator converges fast); maxiter ≈ {1.2 * min(slow):.0f} would "
                                "likely do (extrapolated from the residual history, or from the flux's estimated error "
                                "where that is sooner; it errs long early in a solve), or a looser tol")
                    raise ConvergenceError(
                        f"FFT homogenization did not converge for loading e{j}{where} with eps = "
                        f"{np.round(tab, 4).tolist()}: " + "; ".join(a.message for a in attempts) + ". " + hint,
                        history=hist,
                    )
                tensor[w, :, j] = out.flux
                stops[w, c] = out.stop or "residual"
                if pairs and out.solver == "cocg":
                    for i in pair_terms(tensor[w], finals, j, out, prob):
                        paired[w, c].add(i)
                        paired[w, dirs.index(i)].add(j)
                residuals[w, c] = out.history[-1]
                if out.stop == "flux":
                    flux_errors[w, c], off_errors[w, c] = out.flux_error, out.offdiagonal_error
                iterations[w, c] = sum(a.iterations for a in attempts)
                solvers_used[w, c] = out.solver
                greens_used[w, c] = out.green
                hist_w.append(out.history)
                if warm_start and out.green == op.name:
                    previous[c] = out.x
                if return_fields:
                    fields[w, c] = (out.x + e0.astype(dt)[:, None]).reshape((d,) + arr.shape)
                bar.update(1)
            histories.append(hist_w)
    finally:
        bar.close()
    for idx in np.ndindex(paired.shape):  # every off-diagonal term of the column from pairs: no linear error left
        if len(paired[idx]) == d - 1:
            off_errors[idx] = np.nan
    if np.any(stops == "flux"):  # once for the call, like the choices before it; the numbers per solve: metadata
        switches.append({"what": "stop", "from": "residual", "to": "flux",
                         "reason": f"no local fields asked: a COCG solve also converges when the estimated relative "
                                   f"error of eps_jj (its path over the last {FLUX_WINDOW} projections) is <= "
                                   f"tol={tol:g}; off-diagonal terms from two loadings' solves (x_i^T r_j), or, without "
                                   "the other loading, the iterate's flux (error linear in the residual reached: "
                                   "stop='residual' keeps them within tol); per solve: metadata['stop'], "
                                   "['flux_error'], ['offdiagonal_error'], ['residual_reached']"})
    if scalar:
        tensor, iterations, solvers_used, greens_used = tensor[0], iterations[0], solvers_used[0], greens_used[0]
        stops, flux_errors, off_errors, residuals = stops[0], flux_errors[0], off_errors[0], residuals[0]
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
        metadata={"tol": tol, "voxel_nm": voxel_nm, "green_used": greens_used, "method": "per_wavelength",
                  "method_reason": method_reason, "stop": stops, "flux_error": flux_errors,
                  "offdiagonal_error": off_errors, "residual_reached": residuals},
        switches=tuple(switches),
    )


__all__ = ["fft_permittivity", "FFTHomogenization", "auto_green", "metal_dielectric", "LOW_LOSS", "PROBE",
           "COMPLEX64_METAL_TOL", "METHODS", "SPECTRUM_METHODS", "auto_spectrum_method", "PREDICT", "PREDICT_FROM", "first_prediction", "predicted_projections",
           "slow_solve_monitor", "flux_prediction", "solve_prediction", "STOPS"]
