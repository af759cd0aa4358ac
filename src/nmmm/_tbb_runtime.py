"""Make the TBB runtime that pip installs with nmmm loadable, so Numba's parallel kernels are fork-safe.

nmmm's ``parallel=True`` kernels (Mie series, thin film, tristimulus integration, particle fields, the
BRDF and render kernels) run on Numba's threading layer. Numba picks the first layer that loads, in
the order ``tbb``, ``omp``, ``workqueue``. On Linux the ``omp`` layer is GNU OpenMP, which is not
fork-safe: once a parallel kernel has run, a ``fork()`` (``multiprocessing``'s default start method on
Linux up to Python 3.13) gives children that print "fork() called from a process already using GNU
OpenMP, this is unsafe" and die, and a ``Pool`` waits for them forever. ``workqueue`` is fork-safe but
aborts when two Python threads call parallel kernels at once. ``tbb`` is both fork- and thread-safe
(Numba, *The Threading Layers*), which is why ``pyproject.toml`` depends on the ``tbb`` wheel (Linux
x86-64; Numba needs TBB ≥ 2021.6).

The wheel alone is not enough: it puts ``libtbb.so.12`` in ``<prefix>/lib`` and Numba opens it by its
bare name (``ctypes.CDLL("libtbb.so.12")`` and the ``tbbpool`` extension's ``DT_NEEDED``), which the
dynamic loader finds there only when the interpreter's run path names that directory — a
virtual environment's or a ``--user`` install's ``lib`` it never does (Numba issues 6108, 7148,
9740). :func:`load_pip_tbb` loads the wheel's library once by its full path; the loader then answers
every later request for ``libtbb.so.12`` with that library, so Numba's own default selection finds
TBB. Nothing is configured: ``numba.config.THREADING_LAYER`` and the priority stay the user's (a
``NUMBA_THREADING_LAYER=omp`` is still obeyed), and the effect on other Numba code in the process is
the one installing TBB has anywhere its library is on the search path.

It must run before Numba launches its threads (the first parallel call, or ``numba.set_num_threads``
/ ``get_num_threads``), so ``nmmm/__init__`` calls it; a program that launches Numba's threads before
importing nmmm keeps the layer already chosen.

References
----------
Numba documentation, *The Threading Layers*, https://numba.readthedocs.io/en/stable/user/threading-layer.html
(fork and thread safety of ``tbb``, ``omp``, ``workqueue``; selection priority).
Numba issue 6108, *TBB can't be loaded* (pip's ``libtbb`` not on the loader's path),
https://github.com/numba/numba/issues/6108.
"""

from __future__ import annotations

import os
import sys

LIBTBB_SONAME = "libtbb.so.12"  # oneTBB 2021 onwards; the name Numba's tbbpool links against
_loaded = None  # the ctypes handle, held for the life of the process


def _pip_libtbb_path() -> str | None:
    """Where pip put the ``tbb`` wheel's ``libtbb.so.12``, or None when it is not installed.

    ``<sys.prefix>/lib`` first (a virtual environment or a plain install: one ``stat``), then the file
    as the ``tbb`` distribution's RECORD lists it (``--user`` and other install schemes).
    """
    candidate = os.path.join(sys.prefix, "lib", LIBTBB_SONAME)
    if os.path.isfile(candidate):
        return candidate
    try:
        from importlib.metadata import PackageNotFoundError, files
    except ImportError:  # pragma: no cover - Python >= 3.8 always has it
        return None
    try:
        record = files("tbb") or ()
    except PackageNotFoundError:
        return None
    for entry in record:
        if entry.name == LIBTBB_SONAME:
            path = str(entry.locate())
            if os.path.isfile(path):
                return path
    return None


def load_pip_tbb() -> str | None:
    """Load the ``tbb`` wheel's ``libtbb.so.12`` by path so Numba can select the ``tbb`` layer.

    Returns the path loaded, or None where there is nothing to do: not Linux (no GNU OpenMP fork
    problem; the wheel's DLL layout differs), the wheel not installed (Numba then uses whatever it
    finds, as before), or the library failed to load (a broken install must not stop ``import nmmm``;
    Numba falls back to ``omp`` as it would without the wheel).
    """
    if not sys.platform.startswith("linux"):
        return None
    path = _pip_libtbb_path()
    if path is None:
        return None
    import ctypes

    global _loaded
    try:
        _loaded = ctypes.CDLL(path)
    except OSError:
        return None
    return path
