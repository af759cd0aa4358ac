"""The wavelengths of one FFT homogenization spread over a Dask cluster.

- :func:`fft_permittivity_spectrum` — :func:`~nmmm.homogenize.fft.fft_permittivity` over a
  spectrum on a Dask cluster (a ``LocalCluster`` of single-threaded worker processes by
  default, or a running scheduler ``tcp://HOST:8786``, as ``nmmm sweep`` does), one task per
  worker; the tasks' results are joined into one :class:`~nmmm.homogenize.fft.FFTHomogenization`.
- :func:`wavelength_work` — the relative work of each wavelength's solve, from ε alone.

How the work is cut. The loadings (E0 along each axis) are independent solves, and so are
the wavelengths but for the warm start a wavelength gives the next one. The (loading,
wavelength) solves are laid in one line, loading after loading, and cut into one piece per
task of equal *estimated* work (:func:`wavelength_work`): short wavelengths of a metal take
up to 3× the projections of long ones, so equal counts of wavelengths were unbalanced (64³
aluminium flakes, 16 λ, 2 workers: 49.4 s and 33.3 s). A cut inside a loading costs one cold
start (the solve after it starts from zero). When the whole spectrum is solved by one Lanczos
run per loading (two-phase cells, ``method="auto"``), a run lasts as long as its slowest
wavelength whatever its wavelengths, so cutting it over wavelengths repeats work: whole
loadings then go to the tasks in turn (3 loadings on 2 workers: 2 runs and 1).

Every task takes the automatic choices (Green operator, precision, spectrum method) of the
*whole* spectrum, so ε_eff(λ) has no jump at a boundary. The cell's labels travel once to each
worker (scattered), not once per task.

What it gives (benchmarks/bench_fft_metals.py ``--speedup N``): k workers divide the wall time
by about k when the machine has k free cores and the work splits evenly, less the cold starts
and the start of the cluster (a few seconds); with Lanczos runs, by at most the number of
loadings (the slowest run is the floor). On a cluster each worker needs the cell's memory
(d + 1 vector fields); a larger cluster than d (Lanczos) or than the wavelength count helps no
more.
"""

from __future__ import annotations

import time
import uuid
import warnings

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.homogenize.work_estimate import WARM_START_FRACTION  # projections warm / cold


def wavelength_work(table) -> np.ndarray:
    """Relative work (projections) of each wavelength's solve, from the permittivity table alone.

    Parameters
    ----------
    table : array_like, complex, shape (n_wavelengths, n_phases)

    Returns
    -------
    ndarray, shape (n_wavelengths,)
        For a metal-like phase (Re ε < 0) beside others, |ε| / Im ε of that phase (the largest
        over such phases): COCG's and Lanczos's projections on aluminium flakes in 2.25 (64³, 16 λ
        from 380 to 780 nm, ε from −20.8 + 4.0i to −64.6 + 44.9i) were proportional to it within
        a few per cent, 195 to 68; a lossless metal gets a large finite value. Otherwise the square
        root of the contrast max|ε| / min|ε| (conjugate gradients on a dielectric contrast). Only
        the ratios between wavelengths are meaningful.
    """
    t = np.atleast_2d(np.asarray(table, dtype=complex))
    mag = np.abs(t)
    contrast = np.sqrt(mag.max(axis=1) / np.maximum(mag.min(axis=1), 1e-300))
    metal = (t.real < 0) & (mag > 0)
    q = np.where(metal, mag / np.maximum(np.abs(t.imag), 1e-3 * mag), 0.0).max(axis=1)
    mixed = metal.any(axis=1) & (~metal).any(axis=1)
    return np.where(mixed, np.maximum(q, 1.0), np.maximum(contrast, 1.0))


def _plan(work, n_dirs: int, k: int, whole_loadings: bool) -> list[list[tuple[int, int, tuple[int, ...]]]]:
    """Pieces (one per task) of the (loading, wavelength) solves: each a list of segments
    ``(lo, hi, loading positions)`` — wavelengths lo..hi−1 of those loadings, solved in one call.

    ``whole_loadings``: loadings are not split over wavelengths; they go to the pieces in turn
    (at most one piece per loading: a Lanczos run lasts as long as its slowest wavelength, so a
    loading cut in two would run twice as long in the piece that holds both of its runs).
    Otherwise the line of solves (loading after loading, each wavelength weighing ``work``, the
    first of a loading 1 / WARM_START_FRACTION) is cut into ``k`` pieces of equal weight."""
    nw = len(work)
    if whole_loadings:
        k = max(1, min(int(k), n_dirs))
        return [[(0, nw, tuple(range(i, n_dirs, k)))] for i in range(k)]
    weight = np.array(work, dtype=float)
    weight[0] /= WARM_START_FRACTION
    line = np.tile(weight, n_dirs)
    k = max(1, min(int(k), line.size))
    cum = np.concatenate([[0.0], np.cumsum(line)])
    # cut where the running work passes i/k of the total (nearest item boundary), at least one item each
    cuts = [0]
    for i in range(1, k):
        c = int(np.argmin(np.abs(cum - cum[-1] * i / k)))
        cuts.append(min(max(c, cuts[-1] + 1), line.size - (k - i)))
    cuts.append(line.size)
    pieces = []
    for a, b in zip(cuts[:-1], cuts[1:]):
        segs = []
        for c in range(a // nw, (b - 1) // nw + 1):
            lo, hi = max(a - c * nw, 0), min(b - c * nw, nw)
            if segs and segs[-1][:2] == (lo, hi):
                segs[-1] = (lo, hi, segs[-1][2] + (c,))
            else:
                segs.append((lo, hi, (c,)))
        pieces.append(segs)
    return pieces


def _solve_piece(labels, by_label, segments, wavelength_nm, dirs, kwargs):
    """One task: fft_permittivity on each segment (wavelengths lo..hi−1, its loadings; warm
    starts along the segment). Returns [(lo, hi, loadings, result, seconds, warnings)]."""
    from nmmm.homogenize.fft import fft_permittivity

    out = []
    for lo, hi, cs in segments:
        t = time.perf_counter()
        js = [dirs[c] for c in cs]
        w = None if wavelength_nm is None else np.asarray(wavelength_nm)[lo:hi]
        # a worker's warnings (periodicity, quasi-static validity, solver fallbacks) would stay in its
        # log: record them and let the caller warn
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                r = fft_permittivity(labels, {v: e[lo:hi] for v, e in by_label.items()}, wavelength_nm=w,
                                     directions=js, progress=False, **kwargs)
            except Exception as exc:  # travels to the caller with the chunk named
                if hasattr(exc, "add_note"):
                    exc.add_note(f"in the Dask task of wavelengths {lo}..{hi - 1}, loadings {js} "
                                 "(fft_permittivity_spectrum)")
                raise
        found = [(c.category, str(c.message)) for c in caught]
        out.append((lo, hi, tuple(js), r, time.perf_counter() - t, found))
    return out


def _lanczos_expected(values, table, kwargs) -> bool:
    """Whether fft_permittivity's ``method="auto"`` takes one Lanczos run per loading for the whole
    spectrum (the rule of :func:`~nmmm.homogenize.fft.fft_permittivity`); used only to plan the
    cut — the solves make the choice themselves."""
    from nmmm.homogenize.fft import auto_spectrum_method

    method = str(kwargs.get("method", "auto")).lower().replace("-", "_")
    if method != "auto":
        return method == "lanczos"
    solver = str(kwargs.get("solver", "cocg")).lower().replace("-", "_")
    try:
        return auto_spectrum_method(values.size, table, solver, kwargs.get("dtype", "complex128"),
                                    bool(kwargs.get("return_fields", False)))[0] == "lanczos"
    except Exception:  # an unusual dtype or shape: plan as per wavelength
        return False


def fft_permittivity_spectrum(labels, eps, *, wavelength_nm=None, scheduler: str | None = None,
                              n_workers: int = 2, client=None, n_chunks: int | None = None,
                              **kwargs):
    """:func:`~nmmm.homogenize.fft.fft_permittivity` over a spectrum, its (loading, wavelength)
    solves cut into one Dask task per worker of about equal estimated work.

    Parameters
    ----------
    labels, eps, wavelength_nm
        As for :func:`~nmmm.homogenize.fft.fft_permittivity`; ``eps`` must vary over wavelength
        (arrays of one length, or Materials with ``wavelength_nm``).
    scheduler : str, optional
        ``"tcp://HOST:8786"`` of a running Dask scheduler; None: a ``LocalCluster`` of
        ``n_workers`` single-threaded worker processes, closed afterwards (in a script, call under
        ``if __name__ == "__main__":``: the worker processes import the main module again).
    n_workers : int
        Workers of the local cluster.
    client : dask.distributed.Client, optional
        An existing client (overrides ``scheduler``).
    n_chunks : int, optional
        Tasks (default: the number of workers); each runs its pieces of loadings and wavelengths
        with warm starts along each piece (module docstring: how the cut is made).
    **kwargs
        Passed to :func:`~nmmm.homogenize.fft.fft_permittivity` (``workers`` defaults to 1
        thread per task here).

    Returns
    -------
    FFTHomogenization
        As from one call, with ``metadata["chunks"]``: per piece solved (first wavelength, last + 1,
        seconds), ``metadata["chunk_loadings"]``: the loadings (axes) of each piece, and
        ``metadata["tasks"]``: seconds of each task. The workers' warnings
        are warned here (each once); a worker's error is raised here with a note naming its
        wavelengths and loadings (its "wavelength index" counts within the piece). A failed task
        fails the call: nothing is kept for a restart.
    """
    from nmmm.homogenize.fft import FFTHomogenization, _as_label_array, _compact_labels, _eps_table

    for bad in ("return_fields",):
        if kwargs.get(bad):
            raise InvalidInputError(f"{bad}=True is not supported over a cluster (the fields stay on the workers); "
                                    "call fft_permittivity for the fields")
    if n_chunks is not None and (isinstance(n_chunks, bool) or not isinstance(n_chunks, (int, np.integer))
                                 or n_chunks < 1):
        raise InvalidInputError(f"n_chunks must be a positive whole number of tasks (or None: one per worker), "
                                f"got {n_chunks!r}")
    arr, _ = _as_label_array(labels)
    compact, values, _ = _compact_labels(arr)
    table, scalar = _eps_table(values, eps, wavelength_nm)
    if scalar:
        raise InvalidInputError("fft_permittivity_spectrum needs permittivities over wavelength (1-D arrays or "
                                "Materials with wavelength_nm); for one wavelength call fft_permittivity")
    nw = table.shape[0]
    d = arr.ndim
    directions = kwargs.pop("directions", None)
    dirs = tuple(range(d)) if directions is None else tuple(int(j) for j in directions)
    if not dirs or any(j < 0 or j >= d for j in dirs):
        raise InvalidInputError(f"directions must be axes in 0..{d - 1}, got {directions!r}")
    by_label = {int(v): table[:, i] for i, v in enumerate(values)}
    kwargs.setdefault("workers", 1)
    whole_loadings = _lanczos_expected(values, table, kwargs)
    kwargs["_decide_on"] = table
    from nmmm.cluster import dask_client

    with dask_client(client, scheduler, n_workers, caller="fft_permittivity_spectrum") as client:
        k = n_chunks or max(1, len(client.scheduler_info().get("workers", {})) or int(n_workers))
        pieces = _plan(wavelength_work(table), len(dirs), k, whole_loadings)
        # hash=False and a fresh key per call: a later call on the same cell must not meet the keys
        # of this one being released
        lab_f = client.scatter(labels if hasattr(labels, "labels") else arr, broadcast=True, hash=False)
        tag = uuid.uuid4().hex[:8]
        futs = [client.submit(_timed, _solve_piece, lab_f, by_label, segs, wavelength_nm, dirs, kwargs, pure=False,
                              key=f"nmmm-fft-piece-{i}-{tag}")
                for i, segs in enumerate(pieces)]
        done = client.gather(futs)
    task_seconds = [sec for sec, _ in done]
    parts = [p for _, ps in done for p in ps]  # task by task, piece by piece
    seen = set()
    for lo, hi, js, _, _, found in parts:
        for category, message in found:
            if (category, message) not in seen:  # each piece repeats the cell's own warnings: once
                seen.add((category, message))
                warnings.warn(f"{message} (first seen in the Dask task of wavelengths {lo}..{hi - 1}, loadings "
                              f"{list(js)})", category, stacklevel=2)
    tensor = np.full((nw, d, d), np.nan + 0j)
    iterations = np.zeros((nw, len(dirs)), dtype=int)
    solver = np.empty((nw, len(dirs)), dtype=object)
    green_used = np.empty((nw, len(dirs)), dtype=object)
    per_solve = {k: np.full((nw, len(dirs)), np.nan) for k in ("flux_error", "offdiagonal_error", "residual_reached")}
    per_solve["stop"] = np.empty((nw, len(dirs)), dtype=object)
    hist = [[None] * len(dirs) for _ in range(nw)]
    whole, per_wl, projections = [], [], {}
    for lo, hi, js, r, _, _ in parts:
        cols = [dirs.index(j) for j in js]
        for c, j in zip(cols, js):
            tensor[lo:hi, :, j] = r.tensor[:, :, j]
        iterations[lo:hi, cols] = r.iterations
        solver[lo:hi, cols] = r.solver
        green_used[lo:hi, cols] = r.metadata["green_used"]
        for k, a in per_solve.items():
            if k in r.metadata:
                a[lo:hi, cols] = r.metadata[k]
        for w in range(hi - lo):
            for i, c in enumerate(cols):
                hist[lo + w][c] = r.residual_history[w][i]
        for i, c in enumerate(cols):
            if "projections" in r.metadata:
                projections[c] = projections.get(c, 0) + r.metadata["projections"][i]
        for s in r.switches:
            s = dict(s)
            if "wavelength_index" in s:
                s["wavelength_index"] += lo
                per_wl.append(s)
            elif s not in whole:  # the whole-spectrum choices: once
                whole.append(s)
    per_wl.sort(key=lambda s: (s["wavelength_index"], dirs.index(s["loading"]) if s.get("loading") in dirs else 0))
    first = parts[0][3]
    meta = dict(first.metadata)
    meta["green_used"] = green_used
    meta.update({k: a for k, a in per_solve.items() if k in first.metadata})
    if projections:
        meta["projections"] = [projections[c] for c in sorted(projections)]
    meta["chunks"] = [(lo, hi, sec) for lo, hi, _, _, sec, _ in parts]
    meta["chunk_loadings"] = [js for _, _, js, _, _, _ in parts]
    meta["tasks"] = task_seconds
    return FFTHomogenization(
        tensor=tensor, iterations=iterations, residual_history=hist, solver=solver,
        green=first.green, fractions=first.fractions, directions=dirs, shape=first.shape,
        dtype=first.dtype, fields=None, metadata=meta, switches=tuple(whole + per_wl))


def _timed(fn, *args):
    t = time.perf_counter()
    out = fn(*args)
    return time.perf_counter() - t, out


__all__ = ["fft_permittivity_spectrum", "wavelength_work"]
