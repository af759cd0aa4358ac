"""nmmm's parallel kernels survive ``fork`` and concurrent Python threads.

After a ``parallel=True`` kernel has run on Numba's ``omp`` layer (GNU OpenMP), a forked child prints
"fork() called from a process already using GNU OpenMP, this is unsafe", dies, and a
``multiprocessing`` Pool waits forever. nmmm depends on the ``tbb`` wheel and makes its library
loadable (``nmmm._tbb_runtime``) so Numba picks the fork- and thread-safe ``tbb`` layer.

The user's pattern runs in a subprocess: two Numba threads, a Mie batch in the parent, then the same
batch in a fork Pool's children, then from four Python threads at once (which the ``workqueue``
layer aborts on). The Pool's result is awaited with a timeout inside the subprocess and the
subprocess itself has one, so the defect fails the test in seconds instead of hanging it.
"""

from __future__ import annotations

import json
import platform
import subprocess
import sys
import textwrap
from importlib import metadata

import numpy as np
import pytest

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="the fork start method and GNU OpenMP's fork problem are Linux's")

POOL_TIMEOUT_S = 10  # the healthy run takes ~1 s once the kernels are compiled (cached on disk)

_SCRIPT = textwrap.dedent(f"""
    import json, multiprocessing as mp, sys
    from concurrent.futures import ThreadPoolExecutor
    import numba, numpy as np
    from nmmm.layers import mie

    def work(i):
        d = np.linspace(100.0, 1000.0, 400)
        lam = np.linspace(380.0, 780.0, 81)
        return float(np.mean(mie(1.5 + 0.01j, 1.0, d[:, None], lam[None, :]).qext))

    if __name__ == "__main__":
        numba.set_num_threads(2)
        parent = work(0)
        report = {{"parent": parent, "layer": numba.threading_layer()}}
        print(json.dumps(report), flush=True)  # seen even if the Pool below never returns
        with mp.get_context("fork").Pool(2) as pool:
            try:
                report["children"] = pool.map_async(work, range(4)).get(timeout={POOL_TIMEOUT_S})
            except mp.TimeoutError:
                report["children"] = None
                print(json.dumps(report), flush=True)
                pool.terminate()
                sys.exit(3)
        with ThreadPoolExecutor(4) as ex:
            report["threads"] = list(ex.map(work, range(8)))
        print(json.dumps(report), flush=True)
""")


def _tbb_expected() -> bool:
    """pyproject.toml installs the tbb wheel on Linux x86-64 (the only Linux wheel there is)."""
    try:
        metadata.distribution("tbb")
    except metadata.PackageNotFoundError:
        return platform.machine() in ("x86_64", "AMD64")
    return True


def test_fork_pool_and_python_threads_after_a_parallel_kernel():
    if not _tbb_expected():
        pytest.skip(f"no tbb wheel for Linux {platform.machine()}: Numba uses GNU OpenMP here, which is not fork-safe")
    try:
        proc = subprocess.run([sys.executable, "-c", _SCRIPT], capture_output=True, text=True,
                              timeout=POOL_TIMEOUT_S + 100)  # + compilation on a cold cache
    except subprocess.TimeoutExpired as exc:
        pytest.fail(f"the fork/thread run hung past {exc.timeout} s; its stderr:\n{(exc.stderr or b'')[-2000:]!r}")
    reports = [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]
    last = reports[-1] if reports else {}
    detail = (f"exit {proc.returncode}, Numba threading layer {last.get('layer')!r} (want 'tbb': install the "
              f"'tbb' wheel pyproject.toml lists); stderr:\n{proc.stderr[-2000:]}")
    assert proc.returncode != 3, "the fork Pool's children died and the Pool hung (GNU OpenMP and fork): " + detail
    assert proc.returncode == 0 and "threads" in last, detail
    assert last["layer"] == "tbb", detail
    parent = last["parent"]
    assert 2.0 < parent < 3.0, parent  # mean Q_ext of 100-1000 nm spheres, n = 1.5 + 0.01i, visible
    np.testing.assert_allclose(last["children"], [parent] * 4, rtol=1e-13)
    np.testing.assert_allclose(last["threads"], [parent] * 8, rtol=1e-13)
