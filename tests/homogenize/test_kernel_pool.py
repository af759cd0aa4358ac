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

SAME_BITS = f"""
import sys
sys.path.insert(0, {os.path.dirname(os.path.abspath(__file__))!r})
import test_threads_kernels
test_threads_kernels.test_each_kernel_gives_the_same_bits_at_every_thread_count()  # 1..4 threads here
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
