"""The kernels' thread pool (homogenize/kernels.py, issue 22) under concurrent and failing callers.

Run in fresh processes with NUMBA_NUM_THREADS=4 (more ranges than a 2-core machine's default):
- a range that fails: the call raises only after every other range has finished (a range still
  running would write to the caller's arrays after the error);
- callers with different thread counts share one pool that is never replaced (a pool grown by
  shutting the old one down let a concurrent caller submit to it: "cannot schedule new futures
  after shutdown");
- a shut-down pool (interpreter exit) leaves the ranges to the caller;
- every kernel gives the same bits at 1, 2, 3 and 4 threads (one build, fixed partial sums).
"""

import os
import subprocess
import sys
import textwrap

FAILING_RANGE = """
import time
import numpy as np
from nmmm.homogenize import kernels
big = np.zeros(kernels.SERIAL_BELOW)
state = {}
def fake(lo, hi):
    if lo == 0:
        return
    if state.setdefault("first", lo) == lo:
        raise ValueError("range failed")
    time.sleep(0.3)
    state.setdefault("done", []).append(time.perf_counter())
with kernels.threads(4):
    try:
        kernels._split(fake, 4, big)
    except ValueError:
        t_raise = time.perf_counter()
    else:
        raise SystemExit("no error")
assert len(state["done"]) == 2 and max(state["done"]) <= t_raise, (state, t_raise)
"""

ONE_POOL = """
from concurrent.futures import ThreadPoolExecutor
import numpy as np
from nmmm.homogenize import kernels
big = np.zeros(kernels.SERIAL_BELOW)
with kernels.threads(2):
    kernels._split(lambda lo, hi: None, 2, big)
pool = kernels._pool
with kernels.threads(4):
    kernels._split(lambda lo, hi: None, 4, big)
assert kernels._pool is pool and pool._max_workers == 3
# a shut-down pool (as at interpreter exit): the caller runs every range
kernels._pool = ThreadPoolExecutor(1)
kernels._pool.shutdown()
seen = []
with kernels.threads(4):
    kernels._split(lambda lo, hi: seen.append((lo, hi)), 8, big)
assert sorted(seen) == [(0, 2), (2, 4), (4, 6), (6, 8)], seen
"""

SAME_BITS = """
import numpy as np
from nmmm.homogenize import geometries as G
from nmmm.homogenize import kernels
from nmmm.homogenize.green import green_operator
from nmmm.homogenize.solvers import Problem
shape = (40, 36, 32)
n = int(np.prod(shape))
lab = G.boolean_spheres(40, 0.3, 4.0, ndim=3, seed=1)[:, :36, :32].reshape(-1).astype(np.uint8)
tab = np.array([2.25, -50 + 5j], np.complex64)
prob = Problem(lab.reshape(shape), 2, green_operator(shape, "willot2015"), np.complex64, 1)
kind, ph, ih = prob.stencil
def run(w):
    rng = np.random.default_rng(0)
    p, q, r, x, F = [(rng.normal(size=(3, n)) + 1j * rng.normal(size=(3, n))).astype(np.complex64) for _ in range(5)]
    F = F.reshape((3,) + shape)
    psi = np.zeros(shape, np.complex64)
    sums = np.zeros(3, np.complex128)
    e = np.zeros((3, n), np.complex64)
    with kernels.threads(w):
        pq = kernels.direction_and_eps(p, q, r, np.complex64(0.3 - 0.1j), lab, tab, True, sums)
        rr = kernels.cocg_update(x, r, p, q, np.complex64(0.2 + 0.05j))
        kernels.eps_times(e, x, lab, tab, np.array([1, 0, 0], np.complex64))
        G1 = F.copy()
        kernels.project(G1, prob._a, prob._b, prob._ny, prob._has_ny, 1)
        kernels.potential(F, psi, prob._a, prob._b, ph)
        Fg = np.empty_like(F)
        kernels.stencil_gradient(psi, Fg, kind, ih)
        rs = kernels.cocg_update_stencil(x, r, p, psi, np.complex64(0.1), kind, ih, True)
    return [np.asarray(v) for v in (pq, sums, rr, p, q, r, x, e, G1, psi, Fg, rs)]
ref = run(1)
for w in (2, 3, 4):
    for a, b in zip(run(w), ref):
        assert np.array_equal(a, b), w
"""


def _run(code):
    env = dict(os.environ, NUMBA_NUM_THREADS="4")
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=env, capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0, out.stderr[-3000:]


def test_a_failing_range_raises_after_every_range_finished():
    _run(FAILING_RANGE)


def test_callers_with_different_thread_counts_share_one_pool():
    _run(ONE_POOL)


def test_kernels_give_the_same_bits_at_any_thread_count():
    _run(SAME_BITS)
