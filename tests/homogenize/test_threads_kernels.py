"""The element-wise kernels of the FFT solver at 1 and 2 threads (issue 22).

- The 2-thread path really splits the work between two OS threads, also when the on-disk Numba
  cache was filled by a serial (small-field) call first: the parallel=True and serial builds of
  a kernel once shared one cache entry (Numba keys it by function and signature, not options),
  so whichever compiled first served both and every 2-thread solve ran its element-wise passes
  on one thread. Checked from each thread's CPU time (/proc/self/task), in fresh processes with
  an empty cache; no wall-clock time is asserted.
- Every kernel gives the same bits at any thread count (one serial build per kernel run over
  ranges, the same per-chunk / per-plane partial sums added in the same order), and so does a
  solve.
"""

import json
import os
import subprocess
import sys
import textwrap

import numba
import numpy as np
import pytest

from nmmm.homogenize import geometries as G
from nmmm.homogenize import kernels
from nmmm.homogenize.green import green_operator
from nmmm.homogenize.solvers import Problem, solve_cocg

FILL_CACHE_SERIALLY = """
import numpy as np
from nmmm.homogenize import kernels
n = 4096  # below SERIAL_BELOW: the serial path
p = np.ones((3, n), np.complex64); q = p.copy(); r = p.copy(); x = p.copy()
lab = np.zeros(n, np.uint8); tab = np.array([2.25, -50 + 20j], np.complex64)
assert not kernels._parallel(p)
with kernels.threads(2):
    kernels.direction_and_eps(p, q, r, np.complex64(0.5), lab, tab, True)
    kernels.cocg_update(x, r, p, q, np.complex64(0.1))
"""

PER_THREAD_CPU = """
import json, os
import numpy as np
from nmmm.homogenize import kernels
TCK = os.sysconf("SC_CLK_TCK")
def cpu():
    out = {}
    for t in os.listdir("/proc/self/task"):
        f = open(f"/proc/self/task/{t}/stat").read().rsplit(")", 1)[1].split()
        out[t] = (int(f[11]) + int(f[12])) / TCK
    return out
n = 96 ** 3
p = np.ones((3, n), np.complex64); q = p.copy(); r = p.copy(); x = p.copy()
lab = (np.arange(n) % 2).astype(np.uint8); tab = np.array([2.25, -50 + 20j], np.complex64)
assert kernels._parallel(p)
res = {}
with kernels.threads(2):
    for name, f in (("direction_and_eps", lambda: kernels.direction_and_eps(p, q, r, np.complex64(0.5), lab, tab, True)),
                    ("cocg_update", lambda: kernels.cocg_update(x, r, p, q, np.complex64(0.1)))):
        f()
        c0 = cpu()
        for _ in range(60):
            f()
        c1 = cpu()
        res[name] = sorted((c1[t] - c0.get(t, 0.0) for t in c1), reverse=True)
print(json.dumps(res))
"""


def _run(code, env):
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=env, capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="per-thread CPU times need Linux /proc")
def test_two_threads_split_the_work_after_a_serial_call_filled_the_cache(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba-cache"), NUMBA_NUM_THREADS="2",
               OMP_WAIT_POLICY="PASSIVE")  # passive: a spinning idle thread would look busy
    _run(FILL_CACHE_SERIALLY, env)  # fresh cache: the serial builds compile (and are stored) first
    res = json.loads(_run(PER_THREAD_CPU, env).strip().splitlines()[-1])
    for name, per_thread in res.items():
        busiest, second = per_thread[0], per_thread[1]
        assert busiest > 0.05, (name, per_thread)  # enough ticks to judge (60 passes over 96³ × 3)
        # one thread doing everything was the bug; a balanced split gives second ≈ busiest
        assert second >= 0.3 * busiest, (name, per_thread)


def _fields(shape, dtype, seed=0):
    rng = np.random.default_rng(seed)
    return [(rng.normal(size=shape) + 1j * rng.normal(size=shape)).astype(dtype) for _ in range(4)]


def test_each_kernel_gives_the_same_bits_at_every_thread_count():
    """Element-wise outputs and reductions of every kernel, 1 thread against 2 .. NUMBA_NUM_THREADS
    (tests/homogenize/test_kernel_pool.py runs this at 4 threads in a fresh process): bit for bit."""
    shape = (40, 36, 32)
    n = int(np.prod(shape))
    assert 3 * n >= kernels.SERIAL_BELOW
    lab = G.boolean_spheres(40, 0.3, 4.0, ndim=3, seed=1)[:, :36, :32].reshape(-1).astype(np.uint8)
    tab = np.array([2.25, -50 + 5j], np.complex64)
    op = green_operator(shape, "willot2015")
    prob = Problem(lab.reshape(shape), 2, op, np.complex64, 1)
    kind, sq, ih = prob.stencil
    runs = {}
    counts = range(1, numba.config.NUMBA_NUM_THREADS + 1)
    for w in counts:
        p, q, r, x = _fields((3, n), np.complex64)
        F = _fields((3,) + shape, np.complex64, seed=1)[0]
        psi = np.zeros(shape, np.complex64)
        sums = np.zeros(3, np.complex128)
        with kernels.threads(w):
            assert kernels._parallel(p) == (w > 1)
            pq = kernels.direction_and_eps(p, q, r, np.complex64(0.3 - 0.1j), lab, tab, True, sums)
            rr = kernels.cocg_update(x, r, p, q, np.complex64(0.2 + 0.05j))
            e = np.zeros((3, n), np.complex64)
            kernels.eps_times(e, x, lab, tab, np.array([1, 0, 0], np.complex64))
            G1 = F.copy()
            kernels.project(G1, prob._a, prob._b, prob._ny, prob._has_ny, 1)
            kernels.stencil_divergence(F, psi, kind, ih)
            kernels.inverse_laplacian(psi, sq, kind, ih)
            Fg = np.empty_like(F)
            kernels.stencil_gradient(psi, Fg, kind, ih)
            rs = kernels.cocg_update_stencil(x, r, p, psi, np.complex64(0.1), kind, ih, True)
        runs[w] = dict(pq=pq, sums=sums, rr=np.array(rr), p=p, q=q, x=x, r=r, e=e, G1=G1, psi=psi, Fg=Fg, rs=np.array(rs))
    for w in counts[1:]:
        for key, ref in runs[1].items():
            np.testing.assert_array_equal(runs[w][key], ref, err_msg=f"{key} at {w} threads")


@pytest.mark.parametrize("green", ["willot2015", "continuous"])
def test_cocg_gives_the_same_result_at_one_and_two_threads(green):
    """The rank-one stencil path (willot2015) and the d-FFT projection path (continuous) on a
    metal contrast, fields above the serial threshold: the same iterations, residuals and flux,
    bit for bit (every kernel's result is independent of the thread count)."""
    lab = G.boolean_spheres(36, 0.2, 3.0, ndim=3, seed=2).astype(np.uint8)
    assert 3 * lab.size >= kernels.SERIAL_BELOW
    op = green_operator(lab.shape, green)
    tab = np.array([2.25, -50 + 20j])
    e0 = np.eye(3)[0]
    before = numba.get_num_threads()
    for dtype, tol in ((np.complex64, 1e-5), (np.complex128, 1e-9)):
        out = {}
        for w in (1, 2):
            out[w] = solve_cocg(Problem(lab, 2, op, dtype, w), tab, e0, tol=tol, maxiter=3000)
            assert numba.get_num_threads() == before  # a solve restores the caller's thread count
        a, b = out[1], out[2]
        assert a.converged and b.converged
        assert a.iterations == b.iterations and a.history == b.history
        np.testing.assert_array_equal(b.flux, a.flux)
