"""Memory and time of an FFT homogenization, estimated before it starts (issue 21).

A 4096² three-phase cell, or any 3-D cell past a few hundred voxels a side, ran for tens of
minutes (or ran the machine out of memory) without saying so. :func:`fft_permittivity
<nmmm.homogenize.fft.fft_permittivity>` now estimates the work first and refuses it beyond
:data:`FFT_MAX_MEMORY_GB` / :data:`FFT_MAX_MINUTES` with the estimate and the options that raise
the limits (``max_memory_gb=`` / ``max_minutes=``, ``nmmm homogenize run --max-memory-gb /
--max-minutes``).

Public functions
----------------
- :func:`estimate_fft_work` — voxels, memory (GB) and time (s) of a solve.
- :func:`check_fft_work` — raise :class:`~nmmm.errors.InvalidInputError` beyond the limits.

The model (measured on the 2-core development machine, complex128, COCG):

- memory: :data:`FIELDS_IN_MEMORY` fields of d complex components per voxel are alive at once
  (solution, residual, search direction, work buffer, FFT scratch: 5-7.4 fields measured at
  512²-1024² and 64³-96³); GMRES, a fallback, keeps more;
- time: :data:`SECONDS_PER_COMPONENT_VOXEL` per component, voxel and projection (95-111 ns
  measured), times the projections a loading needs — about :data:`PROJECTIONS_DIELECTRIC` for
  dielectric contrasts and :data:`PROJECTIONS_METAL` for a metal beside a dielectric
  (Willot's operators, 44-450 measured) — times wavelengths × loadings.
"""

from __future__ import annotations

import os

import numpy as np

from nmmm.errors import InvalidInputError

__all__ = ["estimate_fft_work", "check_fft_work", "choose_spectrum_method", "FFT_MAX_MEMORY_GB", "FFT_MAX_MINUTES",
           "SPECTRUM_METHODS"]

#: Fields (d complex components per voxel each) alive during a COCG solve.
FIELDS_IN_MEMORY = 8
#: Seconds per field component, voxel and projection (measured ~1e-7 s, complex128).
SECONDS_PER_COMPONENT_VOXEL = 1.0e-7
#: Typical projections per loading.
PROJECTIONS_DIELECTRIC = 50
PROJECTIONS_METAL = 400
#: Default time limit of one call (estimated minutes).
FFT_MAX_MINUTES = 30.0

#: Spectra: projections of a warm-started wavelength / those of a cold one (aluminium flakes,
#: 128³: 124 warm vs 180-216 cold; 64³ measured in benchmarks/bench_fft_metals.py --method-cost).
WARM_START_FRACTION = 0.6
#: The Lanczos run of a loading lasts as long as its slowest wavelength's solve: its projections
#: / a typical wavelength's cold ones (128³ aluminium: 216 / 180-200).
LANCZOS_SLOWEST = 1.2
#: Seconds of one Lanczos step / one complex128 COCG projection on the same grid. Measured 64³
#: flakes, 80 steps, twice, on the loaded 2-core machine: 60-80 ms vs 21 ms (2.9-3.9); a
#: profile gives the FFTs ~20 ms and the step's NumPy vector work (single-threaded, strided real
#: views of the complex buffer) ~29 ms — a fused Numba step would bring it near 1.
LANCZOS_COST = 3.0
#: Methods :func:`choose_spectrum_method` chooses between.
SPECTRUM_METHODS = ("per_wavelength", "lanczos")


def _physical_memory_gb() -> float:
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 1e9
    except (ValueError, OSError, AttributeError):  # pragma: no cover - not POSIX
        return 16.0


#: Default memory limit (GB): half the machine's physical memory.
FFT_MAX_MEMORY_GB = round(0.5 * _physical_memory_gb(), 1)


def estimate_fft_work(shape, *, n_wavelengths: int = 1, n_loadings: int | None = None, dtype="complex128",
                      metal: bool = False, method: str = "per_wavelength", kept_fields: int = 0) -> dict:
    """Estimated size of an FFT homogenization of a cell of ``shape``; ``method`` "lanczos": one
    run per loading for all wavelengths (:func:`choose_spectrum_method`). ``kept_fields``: solution
    fields held beyond one solve's (the flux rule's pairing keeps every loading's but the last).

    Returns
    -------
    dict
        ``voxels``, ``memory_gb``, ``projections`` (per loading, typical), ``seconds`` (all
        wavelengths and loadings).

    >>> e = estimate_fft_work((4096, 4096, 4096))
    >>> round(e["memory_gb"] / 1e3), e["voxels"]
    (26, 68719476736)
    """
    shape = tuple(int(s) for s in shape)
    d = len(shape)
    voxels = int(np.prod(shape, dtype=np.float64))
    item = np.dtype(dtype).itemsize
    loadings = d if n_loadings is None else int(n_loadings)
    if method not in SPECTRUM_METHODS:
        raise InvalidInputError(f"unknown method {method!r}; choose one of {list(SPECTRUM_METHODS)}")
    # Lanczos runs a complex128 Problem with real float64 vectors whatever dtype was asked (48³
    # spheres, 8 λ, complex64 asked: peak 32-52 MB traced against 21 MB at complex64's size)
    mem_item = 16 if method == "lanczos" else item
    memory_gb = (FIELDS_IN_MEMORY + int(kept_fields)) * d * voxels * mem_item / 1e9
    projections = PROJECTIONS_METAL if metal else PROJECTIONS_DIELECTRIC
    speed = SECONDS_PER_COMPONENT_VOXEL * (0.6 if item == 8 else 1.0)
    if method == "lanczos":
        seconds = loadings * projections * LANCZOS_SLOWEST * LANCZOS_COST * d * voxels * SECONDS_PER_COMPONENT_VOXEL
    else:
        seconds = n_wavelengths * loadings * projections * d * voxels * speed
    return {"voxels": voxels, "memory_gb": memory_gb, "projections": projections, "seconds": seconds}


def choose_spectrum_method(n_wavelengths: int, dtype="complex128") -> tuple[str, str]:
    """"lanczos" or "per_wavelength" for a two-phase cell over ``n_wavelengths``, and why.

    Per wavelength, warm-started: P (1 + :data:`WARM_START_FRACTION` (n − 1)) projections per
    loading at the ``dtype``'s cost; one Lanczos run: :data:`LANCZOS_SLOWEST` P steps at
    :data:`LANCZOS_COST` complex128 projections each. P — the projections of one cold solve —
    cancels, so the choice depends on the number of wavelengths and the precision only
    (complex128: Lanczos from 6 wavelengths on; complex64: from 10).

    >>> choose_spectrum_method(81, "complex64")[0]
    'lanczos'
    >>> choose_spectrum_method(9, "complex64")[0]
    'per_wavelength'
    """
    n = int(n_wavelengths)
    item = np.dtype(dtype).itemsize
    per = (1.0 + WARM_START_FRACTION * (n - 1)) * (0.6 if item == 8 else 1.0)
    lz = LANCZOS_SLOWEST * LANCZOS_COST
    if n > 1 and lz < per:
        return "lanczos", (f"two-phase cell over {n} wavelengths: one Lanczos run per loading is estimated at "
                           f"{lz / per:.2g} of the time of per-wavelength {np.dtype(dtype).name} COCG with warm "
                           f"starts ({lz:.2g} vs {per:.3g} cold-solve times)")
    return "per_wavelength", (f"{n} wavelength(s): per-wavelength solves estimated at {per:.3g} cold-solve times, "
                              f"one Lanczos run at {lz:.2g}")


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    if seconds < 2 * 86400:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.3g} days"


def check_fft_work(shape, *, n_wavelengths: int = 1, n_loadings: int | None = None, dtype="complex128",
                   metal: bool = False, max_memory_gb: float | None = None, max_minutes: float | None = None,
                   advice: str | None = None, method: str = "per_wavelength", kept_fields: int = 0) -> dict:
    """The estimate of :func:`estimate_fft_work`, or :class:`InvalidInputError` with it when the
    memory exceeds ``max_memory_gb`` (default :data:`FFT_MAX_MEMORY_GB`) or the time
    ``max_minutes`` (default :data:`FFT_MAX_MINUTES`); ``float('inf')`` lifts a limit.
    ``advice``: what the refusal tells the user to change, in the caller's terms (``nmmm run``:
    the recipe's keys), instead of this function's arguments and the CLI options."""
    mem_lim = FFT_MAX_MEMORY_GB if max_memory_gb is None else float(max_memory_gb)
    min_lim = FFT_MAX_MINUTES if max_minutes is None else float(max_minutes)
    if not (mem_lim > 0 and min_lim > 0):
        raise InvalidInputError(f"max_memory_gb and max_minutes must be > 0, got {mem_lim:g} and {min_lim:g}")
    e = estimate_fft_work(shape, n_wavelengths=n_wavelengths, n_loadings=n_loadings, dtype=dtype, metal=metal,
                          method=method, kept_fields=kept_fields)
    over = []
    if e["memory_gb"] > mem_lim:
        over.append(f"memory {e['memory_gb']:.3g} GB > {mem_lim:g} GB"
                    + ("" if advice else " (max_memory_gb=, --max-memory-gb)"))
    if e["seconds"] > 60.0 * min_lim:
        over.append(f"time ~{_duration(e['seconds'])} > {min_lim:g} min" + ("" if advice else " (max_minutes=, --max-minutes)"))
    if over:
        grid = " x ".join(str(int(s)) for s in shape)
        loadings = len(tuple(shape)) if n_loadings is None else n_loadings
        raise InvalidInputError(
            f"FFT homogenization of a {grid} cell ({e['voxels']:.3g} voxels, {n_wavelengths} wavelength(s) x "
            f"{loadings} loading(s), ~{e['projections']} projections each{' (metal contrast)' if metal else ''}) "
            f"is refused: {'; '.join(over)}. " + (advice or (
                "Use a smaller cell (an RVE study, nmmm.homogenize.resolution, says "
                "how small is enough), complex64 (dtype='complex64', --single: half the memory), fewer loadings "
                "(directions=), or raise the limit named")))
    return e
