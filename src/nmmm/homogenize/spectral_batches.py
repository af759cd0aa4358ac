"""The wavelengths of one FFT homogenization spread over a Dask cluster.

- :func:`fft_permittivity_spectrum` — :func:`~nmmm.homogenize.fft.fft_permittivity` over a
  spectrum, the wavelengths cut into contiguous chunks, one task per chunk on a Dask cluster
  (a ``LocalCluster`` of single-threaded worker processes by default, or a running scheduler
  ``tcp://HOST:8786``, as ``nmmm sweep`` does); each task keeps the warm starts along its
  chunk; the chunks' results are joined into one :class:`~nmmm.homogenize.fft.FFTHomogenization`.

Every chunk takes the automatic choices (Green operator, precision) of the *whole* spectrum, so
ε_eff(λ) has no jump at a chunk boundary; a chunk starts cold, so it pays the first
wavelength's projections once (the price of the split: n_chunks − 1 cold starts). The cell's
labels travel once to each worker (scattered), not once per task.

What it gives (benchmarks/bench_fft_metals.py ``--spectrum N --scheduler local``): the solves
of different wavelengths are independent, so k workers divide the wall time by about k when the
machine has k free cores, less the cold starts (one per chunk) and the start of the cluster
(a few seconds); on a cluster each worker needs the cell's memory (d + 1 vector fields).
"""

from __future__ import annotations

import time
import uuid
import warnings

import numpy as np

from nmmm.errors import InvalidInputError


def _chunk_bounds(n: int, k: int) -> list[tuple[int, int]]:
    k = max(1, min(int(k), n))
    edges = np.linspace(0, n, k + 1).round().astype(int)
    return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:]) if b > a]


def _solve_chunk(labels, eps_chunk, lo, hi, wavelength_nm, kwargs):
    """One task: fft_permittivity on wavelengths lo..hi−1 (warm starts along the chunk)."""
    from nmmm.homogenize.fft import fft_permittivity

    t = time.perf_counter()
    w = None if wavelength_nm is None else np.asarray(wavelength_nm)[lo:hi]
    # a worker's warnings (periodicity, quasi-static validity, solver fallbacks) would stay in its
    # log: record them and let the caller warn
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            r = fft_permittivity(labels, eps_chunk, wavelength_nm=w, progress=False, **kwargs)
        except Exception as exc:  # travels to the caller with the chunk named
            if hasattr(exc, "add_note"):
                exc.add_note(f"in the Dask task of wavelengths {lo}..{hi - 1} (fft_permittivity_spectrum)")
            raise
    found = [(c.category, str(c.message)) for c in caught]
    return lo, hi, r, time.perf_counter() - t, found


def fft_permittivity_spectrum(labels, eps, *, wavelength_nm=None, scheduler: str | None = None,
                              n_workers: int = 2, client=None, n_chunks: int | None = None,
                              **kwargs):
    """:func:`~nmmm.homogenize.fft.fft_permittivity` over a spectrum, one Dask task per chunk of
    contiguous wavelengths.

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
        Chunks of wavelengths (default: the number of workers); each is one task with warm
        starts along it.
    **kwargs
        Passed to :func:`~nmmm.homogenize.fft.fft_permittivity` (``workers`` defaults to 1
        thread per task here).

    Returns
    -------
    FFTHomogenization
        As from one call, with ``metadata["chunks"]``: per chunk (first, last + 1, seconds). The
        workers' warnings are warned here (each once); a worker's error is raised here with a note
        naming its chunk (its "wavelength index" counts within the chunk). A failed chunk fails the
        call: nothing is kept for a restart.
    """
    from nmmm.homogenize.fft import FFTHomogenization, _as_label_array, _compact_labels, _eps_table

    for bad in ("return_fields",):
        if kwargs.get(bad):
            raise InvalidInputError(f"{bad}=True is not supported over a cluster (the fields stay on the workers); "
                                    "call fft_permittivity for the fields")
    arr, _ = _as_label_array(labels)
    compact, values, _ = _compact_labels(arr)
    table, scalar = _eps_table(values, eps, wavelength_nm)
    if scalar:
        raise InvalidInputError("fft_permittivity_spectrum needs permittivities over wavelength (1-D arrays or "
                                "Materials with wavelength_nm); for one wavelength call fft_permittivity")
    nw = table.shape[0]
    by_label = {int(v): table[:, i] for i, v in enumerate(values)}
    kwargs.setdefault("workers", 1)
    kwargs["_decide_on"] = table
    from nmmm.cluster import dask_client

    with dask_client(client, scheduler, n_workers, caller="fft_permittivity_spectrum") as client:
        k = n_chunks or max(1, len(client.scheduler_info().get("workers", {})) or int(n_workers))
        bounds = _chunk_bounds(nw, k)
        # hash=False and a fresh key per call: a later call on the same cell must not meet the keys
        # of this one being released
        lab_f = client.scatter(labels if hasattr(labels, "labels") else arr, broadcast=True, hash=False)
        tag = uuid.uuid4().hex[:8]
        futs = [client.submit(_solve_chunk, lab_f, {v: e[lo:hi] for v, e in by_label.items()}, lo, hi,
                              wavelength_nm, kwargs, pure=False, key=f"nmmm-fft-chunk-{lo}-{hi}-{tag}")
                for lo, hi in bounds]
        parts = sorted(client.gather(futs), key=lambda p: p[0])
    rs = [p[2] for p in parts]
    seen = set()
    for lo, hi, _, _, found in parts:
        for category, message in found:
            if (category, message) not in seen:  # each chunk repeats the cell's own warnings: once
                seen.add((category, message))
                warnings.warn(f"{message} (first seen in the Dask task of wavelengths {lo}..{hi - 1})", category,
                              stacklevel=2)
    switches = []
    for lo, _, r, _, _ in parts:
        for s in r.switches:
            s = dict(s)
            if "wavelength_index" in s:
                s["wavelength_index"] += lo
            elif lo > 0:
                continue  # the whole-spectrum choices: once
            switches.append(s)
    meta = dict(rs[0].metadata)
    meta["green_used"] = np.concatenate([r.metadata["green_used"] for r in rs])
    meta["chunks"] = [(lo, hi, sec) for lo, hi, _, sec, _ in parts]
    return FFTHomogenization(
        tensor=np.concatenate([r.tensor for r in rs]),
        iterations=np.concatenate([r.iterations for r in rs]),
        residual_history=[h for r in rs for h in r.residual_history],
        solver=np.concatenate([r.solver for r in rs]),
        green=rs[0].green, fractions=rs[0].fractions, directions=rs[0].directions, shape=rs[0].shape,
        dtype=rs[0].dtype, fields=None, metadata=meta, switches=tuple(switches))


__all__ = ["fft_permittivity_spectrum"]
