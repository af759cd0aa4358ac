"""Fused element-wise kernels (Numba) of the FFT solvers.

Each kernel makes one pass over the field arrays, so that an iteration costs little more than
its FFTs:

- :func:`project` — Γ(q) applied in place on the Fourier transform of a vector field, with Γ
  evaluated on the fly from the per-axis 1-D factors of a
  :class:`~nmmm.homogenize.green.GreenOperator` (``mode=1``: the reflection I − 2Γ of the
  Eyre-Milton scheme).
- :func:`direction_and_eps` — p ← r + β p, then q ← ε p, returning the bilinear form
  Σ ε p·p (which equals pᵀ Γ ε p because Γ p = p).
- :func:`cocg_update` — x ← x + α p, r ← r − α q, returning rᵀr and ‖r‖².
- :func:`mean_flux` — ⟨ε (E0 + x)⟩.
- :func:`stencil_divergence`, :func:`inverse_laplacian` and :func:`stencil_gradient` /
  :func:`cocg_update_stencil` — the rank-one form of Γ for the Willot operators: Γ ŵ = k s with
  the scalar s = kᴴ ŵ / |k|², and k_j = phase(q) · D_j(q) / h_j where D_j is the symbol of a
  real-space finite-difference stencil (forward difference for "willot2014"; the difference
  across the 2×2×2 voxel cube for "willot2015", with phase e^{−i Σ q/2} / 8i). The phase cancels
  in k s, so Γ w = D ψ / h with the potential ψ = Δ⁻¹ Dᵀ w / h, Δ = Σ_j D_jᵀ D_j / h_j²: the
  divergence Dᵀ w / h is taken in real space, then one forward FFT, the element-wise 1/Δ(q) and
  one inverse FFT of that scalar field; the gradient D ψ is taken in real space too — fused into
  the COCG update, which then reads one scalar field instead of q. Two FFTs of a scalar field per
  iteration, where the spectral form of Γ takes d forward and d inverse FFTs of a vector field
  (the potential form of FFT-accelerated finite elements, Ladecký et al. 2023, Appl. Math.
  Comput. 446, 127835; arXiv:2203.02962).

The two passes of each COCG iteration (:func:`direction_and_eps`, :func:`cocg_update_stencil`)
run on the real views of the complex fields, with β, α and ε split into real and imaginary
parts: written on complex values their loops did not vectorise (at 128³ complex64, 1 thread:
direction 24 -> 13 ms, stencil update 24 -> 17-19 ms; issue 22).

Fields are stored as ``(d, N)`` arrays (d components, N voxels, C order); labels as a flat
``(N,)`` integer array indexing a per-phase permittivity table.

Threads. Each kernel is one serial, GIL-free Numba build over a range of its outer loop (voxel
chunks or first-axis planes); :func:`_split` cuts that loop into one contiguous range per thread
and runs them on a small pool of Python threads (the caller runs the first). The thread count is
Numba's count of the calling thread (:func:`threads` sets it for a block and restores it), and
fields below :data:`SERIAL_BELOW` values run on the caller alone. Not Numba's ``parallel=True``:
its OpenMP workers spin for milliseconds after each kernel, on the cores that the next FFT's
threads (scipy.fft ``workers``) need — at 2 threads on 2 cores the FFTs of an iteration lost
up to half their speed to it (issue 22). Reductions are summed per chunk / per plane and then in
a fixed order, so a result does not depend on the thread count.
"""

from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor, wait
from contextlib import contextmanager

import numba
import numpy as np
from numba import njit

#: Values (``field.size``: d × voxels for a vector field) below which a field is processed by the
#: calling thread alone (a hand-off to the pool costs ~20-50 µs, more on a loaded machine).
SERIAL_BELOW = 1 << 17
CHUNK = 1 << 15  # voxels per reduction chunk of the flat (d, N) kernels (contiguous runs per component)

_kernel = njit(cache=True, fastmath=True, nogil=True)
#: The COCG kernels written on real views (:func:`_direction_and_eps`, :func:`_cocg_update_stencil`):
#: fast-math without ``contract``, so no fused multiply-add: every field value is rounded as written
#: (as NumPy's separate products and sums round it), the same bits from every compilation — under
#: ``fastmath=True`` the complex kernels were contracted in some compilations and not in others
#: (two builds of the same ``_cocg_update`` gave x differing in half its values). The reductions
#: may reassociate, and so vectorise: float64 sums of float32 terms, which move by ~1e-16 relative.
_kernel_split = njit(cache=True, fastmath={"nnan", "ninf", "nsz", "arcp", "reassoc", "afn"}, nogil=True)
#: Element-wise kernels without reductions (:func:`_stencil_divergence`, :func:`_inverse_laplacian`):
#: no fast-math at all. Their sums of stencil terms vectorise as written; with ``reassoc`` LLVM
#: associated them differently in the vector body and in the alignment peel, so the bits of a
#: voxel depended on the address of the output array (measured: 1e-16 relative, run to run).
_kernel_exact = njit(cache=True, nogil=True)


@njit(inline="always")
def _k_components(a, b, ny, has_ny, i1, i2, i3):
    k1 = a[0, i1] * b[1, i2] * b[2, i3]
    k2 = b[0, i1] * a[1, i2] * b[2, i3]
    k3 = b[0, i1] * b[1, i2] * a[2, i3]
    if has_ny:
        reg = ((i1 != 0) and not ny[0, i1]) or ((i2 != 0) and not ny[1, i2]) or ((i3 != 0) and not ny[2, i3])
        if reg:
            if ny[0, i1]:
                k1 = k1 * 0
            if ny[1, i2]:
                k2 = k2 * 0
            if ny[2, i3]:
                k3 = k3 * 0
    return k1, k2, k3


@_kernel
def _project(F, a, b, ny, has_ny, mode, lo, hi):
    """Apply Γ (mode 0) or I − 2Γ (mode 1) in place to the planes lo..hi−1 of F (d, N1, N2, N3)."""
    d = F.shape[0]
    n1, n2, n3 = F.shape[1], F.shape[2], F.shape[3]
    two = 2.0
    for i1 in range(n1):
        if i1 < lo or i1 >= hi:  # not range(lo, hi): i1 >= 0 unproven, indexing checks, 1.4x slower
            continue
        for i2 in range(n2):
            ab = a[0, i1] * b[1, i2]  # hoisted per-axis products
            ba = b[0, i1] * a[1, i2]
            bb = b[0, i1] * b[1, i2]
            for i3 in range(n3):
                if has_ny:
                    k1, k2, k3 = _k_components(a, b, ny, has_ny, i1, i2, i3)
                else:
                    k1 = ab * b[2, i3]
                    k2 = ba * b[2, i3]
                    k3 = bb * a[2, i3]
                f1 = F[0, i1, i2, i3]
                f2 = F[1, i1, i2, i3]
                n2k = k1.real * k1.real + k1.imag * k1.imag + k2.real * k2.real + k2.imag * k2.imag
                s = np.conj(k1) * f1 + np.conj(k2) * f2
                if d == 3:
                    f3 = F[2, i1, i2, i3]
                    n2k += k3.real * k3.real + k3.imag * k3.imag
                    s += np.conj(k3) * f3
                if n2k > 0.0:
                    s = s * (1.0 / n2k)
                    if mode == 0:
                        F[0, i1, i2, i3] = k1 * s
                        F[1, i1, i2, i3] = k2 * s
                        if d == 3:
                            F[2, i1, i2, i3] = k3 * s
                    else:
                        F[0, i1, i2, i3] = f1 - two * k1 * s
                        F[1, i1, i2, i3] = f2 - two * k2 * s
                        if d == 3:
                            F[2, i1, i2, i3] = f3 - two * k3 * s
                elif mode == 0:
                    F[0, i1, i2, i3] = 0
                    F[1, i1, i2, i3] = 0
                    if d == 3:
                        F[2, i1, i2, i3] = 0


@_kernel_split
def _direction_and_eps(p, q, r, b_re, b_im, labels, t_re, t_im, update, part, lo, hi):
    """Chunks lo..hi−1: p ← r + β p (if ``update``), q ← ε p; part[c] ← (Σ ε p·p, Σ_i (ε p)_j).

    p, q, r are the real views (d, 2N) of the complex fields (re, im interleaved), β and the
    permittivity table are split into real and imaginary parts, and ε of the chunk is gathered
    once into a buffer: on complex values and with the gather in the loop, the loop did not
    vectorise and the pass took twice as long (issue 22)."""
    d, n2 = p.shape
    n = n2 // 2
    e = np.empty(2 * CHUNK, dtype=p.dtype)
    for c in range((n + CHUNK - 1) // CHUNK):
        if c < lo or c >= hi:
            continue
        i0 = c * CHUNK
        i1 = min(n, i0 + CHUNK)
        lab = labels[i0:i1]
        m = lab.size
        for i in range(m):
            e[2 * i] = t_re[lab[i]]
            e[2 * i + 1] = t_im[lab[i]]
        acc_re = 0.0
        acc_im = 0.0
        for j in range(d):
            pj = p[j, 2 * i0:2 * i1]
            qj = q[j, 2 * i0:2 * i1]
            rj = r[j, 2 * i0:2 * i1]
            s_re = 0.0
            s_im = 0.0
            for i in range(m):
                e_re = e[2 * i]
                e_im = e[2 * i + 1]
                p_re = pj[2 * i]
                p_im = pj[2 * i + 1]
                if update:
                    v_re = rj[2 * i] + (b_re * p_re - b_im * p_im)
                    v_im = rj[2 * i + 1] + (b_re * p_im + b_im * p_re)
                    pj[2 * i] = v_re
                    pj[2 * i + 1] = v_im
                else:
                    v_re = p_re
                    v_im = p_im
                ev_re = e_re * v_re - e_im * v_im
                ev_im = e_re * v_im + e_im * v_re
                qj[2 * i] = ev_re
                qj[2 * i + 1] = ev_im
                acc_re += ev_re * v_re - ev_im * v_im
                acc_im += ev_re * v_im + ev_im * v_re
                s_re += ev_re
                s_im += ev_im
            part[c, 2 + 2 * j] = s_re
            part[c, 3 + 2 * j] = s_im
        part[c, 0] = acc_re
        part[c, 1] = acc_im


@_kernel
def _cocg_update(x, r, p, q, alpha, part, lo, hi):
    """Chunks lo..hi−1: x ← x + α p, r ← r − α q; part[c] ← (rᵀr, ‖r‖²) of the chunk."""
    d, n = x.shape
    for c in range((n + CHUNK - 1) // CHUNK):
        if c < lo or c >= hi:
            continue
        i0 = c * CHUNK
        i1 = min(n, i0 + CHUNK)
        rr_re = 0.0
        rr_im = 0.0
        nr = 0.0
        for j in range(d):
            for i in range(i0, i1):
                x[j, i] = x[j, i] + alpha * p[j, i]
                v = r[j, i] - alpha * q[j, i]
                r[j, i] = v
                vr = v.real
                vi = v.imag
                rr_re += vr * vr - vi * vi
                rr_im += 2.0 * vr * vi
                nr += vr * vr + vi * vi
        part[c, 0] = rr_re
        part[c, 1] = rr_im
        part[c, 2] = nr


@njit(cache=True, nogil=True)
def _eps_times(q, x, labels, tab, e0, lo, hi):
    """Chunks lo..hi−1: q ← ε (e0 + x)."""
    d, n = x.shape
    for c in range((n + CHUNK - 1) // CHUNK):
        if c < lo or c >= hi:
            continue
        i0 = c * CHUNK
        i1 = min(n, i0 + CHUNK)
        for j in range(d):
            for i in range(i0, i1):
                q[j, i] = tab[labels[i]] * (e0[j] + x[j, i])


def _parallel(a) -> bool:
    return a.size >= SERIAL_BELOW and numba.get_num_threads() > 1


_pool: ThreadPoolExecutor | None = None
_pool_lock = threading.Lock()


def _executor() -> ThreadPoolExecutor:
    """The module's pool of kernel threads, made once: room for NUMBA_NUM_THREADS − 1 threads, the
    most any caller's Numba count asks for, started only as ranges wait for them. Never replaced
    (a pool grown by shutting the old one down let a concurrent caller submit to the old one:
    "cannot schedule new futures after shutdown")."""
    global _pool
    with _pool_lock:
        if _pool is None:
            _pool = ThreadPoolExecutor(max_workers=max(1, numba.config.NUMBA_NUM_THREADS - 1),
                                       thread_name_prefix="nmmm-kernel")
        return _pool


def _forget_pool():  # a forked child has none of its parent's threads
    global _pool, _pool_lock
    _pool, _pool_lock = None, threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_pool)


def _wait_all(futs) -> None:
    """Wait until every range has finished: none may still write to the caller's arrays when the
    call returns or raises. A KeyboardInterrupt while waiting waits again (a range lasts one pass
    of one kernel) and is then raised."""
    try:
        wait(futs)
    except BaseException:
        wait(futs)
        raise


def _split(kernel, n_outer: int, field, *args) -> None:
    """Run ``kernel(*args, lo, hi)`` over 0..n_outer−1: one contiguous range per thread (Numba's
    thread count of the caller) when ``field`` is large enough, else on the caller alone. Returns
    (or raises the first range's error) only when every range has finished."""
    k = min(numba.get_num_threads(), n_outer) if _parallel(field) else 1
    if k <= 1:
        kernel(*args, 0, n_outer)
        return
    edges = [(n_outer * i) // k for i in range(k + 1)]
    pool = _executor()
    futs = []
    try:
        for i in range(1, k):
            try:
                futs.append(pool.submit(kernel, *args, edges[i], edges[i + 1]))
            except RuntimeError:  # the pool is shut down (interpreter exit): the caller runs the range
                kernel(*args, edges[i], edges[i + 1])
        kernel(*args, edges[0], edges[1])
    finally:
        _wait_all(futs)
    for f in futs:
        f.result()


def _column_sums(part) -> list:
    """Sum of each column of the per-chunk partial sums (pairwise, in chunk order: the same for
    any thread count)."""
    return [float(part[:, j].sum()) for j in range(part.shape[1])]


def _nchunk(n: int) -> int:
    return (n + CHUNK - 1) // CHUNK


def _real_view(a):
    """The real view of a complex array: last axis doubled, (re, im) interleaved."""
    return a.view(a.real.dtype)


def _split_complex(z, real):
    """Real and imaginary parts of the complex array ``z`` (1-D) as contiguous ``real`` arrays."""
    z = np.asarray(z)
    return np.ascontiguousarray(z.real, dtype=real), np.ascontiguousarray(z.imag, dtype=real)


def direction_and_eps(p, q, r, beta, labels, tab, update, sums=None):
    """If ``update``: p ← r + β p. Then q ← ε p. Returns Σ ε p·p (bilinear, no conjugate), and
    writes Σ_voxels (ε p)_j into ``sums`` (complex128, length d) when given."""
    d, n = p.shape
    real = p.real.dtype
    beta = p.dtype.type(beta)
    t_re, t_im = _split_complex(np.asarray(tab, dtype=p.dtype), real)
    part = np.zeros((_nchunk(n), 2 + 2 * d))
    _split(_direction_and_eps, part.shape[0], p, _real_view(p), _real_view(q), _real_view(r), real.type(beta.real),
           real.type(beta.imag), labels, t_re, t_im, update, part)
    tot = _column_sums(part)
    if sums is not None:
        for j in range(d):
            sums[j] = complex(tot[2 + 2 * j], tot[3 + 2 * j])
    return complex(tot[0], tot[1])


def cocg_update(x, r, p, q, alpha):
    """x ← x + α p; r ← r − α q. Returns (rᵀr, ‖r‖²)."""
    part = np.zeros((_nchunk(x.shape[1]), 3))
    _split(_cocg_update, part.shape[0], x, x, r, p, q, alpha, part)
    tot = _column_sums(part)
    return complex(tot[0], tot[1]), float(tot[2])


def eps_times(q, x, labels, tab, e0):
    """q ← ε (e0 + x) (e0 a constant vector)."""
    _split(_eps_times, _nchunk(x.shape[1]), x, q, x, labels, tab, e0)
    return q


def project(F, a, b, ny, has_ny, mode):
    """Apply Γ (mode 0) or I − 2Γ (mode 1) in place to F of shape (d, N1, N2, N3), d = 2 or 3.

    Γ(q) = k k^H / |k|² is evaluated on the fly from the per-axis factors ``a``, ``b``
    (k_j = a_j Π_{l≠j} b_l), with the Nyquist rule of the spectral symbol when ``has_ny``.
    """
    _split(_project, F.shape[1], F, F, a, b, ny, has_ny, mode)
    return F


@_kernel_exact
def _stencil_divergence(F, s, kind, ih, lo, hi):
    """Planes lo..hi−1: s ← Σ_j D_jᵀ F_j / h_j, the real-space divergence adjoint to the gradient
    stencil of :func:`_grad_real` (so that its transform is Σ_j conj(D_j) F̂_j / h_j): backward
    differences (kind 1) or differences across the voxel cube x − {0, 1}³ (kind 2). Real views
    F (3, N1, N2, 2N3), s (N1, N2, 2N3); a stencil acts on real and imaginary parts alike, and the
    previous voxel along the row (k − 2, periodic) is read with the wrap outside the loop."""
    n1, n2, m = s.shape
    h0, h1, h2 = ih[0], ih[1], ih[2]
    for i1 in range(n1):
        if i1 < lo or i1 >= hi:
            continue
        j1 = i1 - 1 if i1 > 0 else n1 - 1
        for i2 in range(n2):
            j2 = i2 - 1 if i2 > 0 else n2 - 1
            out = s[i1, i2]
            if kind == 1:
                xa = F[0, i1, i2]
                xc = F[0, j1, i2]
                ya = F[1, i1, i2]
                yb = F[1, i1, j2]
                za = F[2, i1, i2]
                for k in range(2):
                    km = k + m - 2
                    out[k] = h0 * (xc[k] - xa[k]) + h1 * (yb[k] - ya[k]) + h2 * (za[km] - za[k])
                for k in range(2, m):
                    out[k] = h0 * (xc[k] - xa[k]) + h1 * (yb[k] - ya[k]) + h2 * (za[k - 2] - za[k])
            else:
                # row sums over the other two axes' {0, 1} offsets: x over (i2, j2), y over (i1, j1), z over all four
                xa = F[0, i1, i2]
                xb = F[0, i1, j2]
                xc = F[0, j1, i2]
                xd = F[0, j1, j2]
                ya = F[1, i1, i2]
                yb = F[1, i1, j2]
                yc = F[1, j1, i2]
                yd = F[1, j1, j2]
                za = F[2, i1, i2]
                zb = F[2, i1, j2]
                zc = F[2, j1, i2]
                zd = F[2, j1, j2]
                for k in range(m):
                    km = k - 2 if k >= 2 else k + m - 2
                    dx = (xc[k] + xc[km] + xd[k] + xd[km]) - (xa[k] + xa[km] + xb[k] + xb[km])
                    dy = (yb[k] + yb[km] + yd[k] + yd[km]) - (ya[k] + ya[km] + yc[k] + yc[km])
                    dz = (za[km] + zb[km] + zc[km] + zd[km]) - (za[k] + zb[k] + zc[k] + zd[k])
                    out[k] = h0 * dx + h1 * dy + h2 * dz


@_kernel_exact
def _inverse_laplacian(S, sq, kind, ih2, lo, hi):
    """Planes lo..hi−1: Ŝ ← Ŝ / Λ(q) (0 where Λ = 0: k = 0 and the rotated scheme's null modes), Λ =
    Σ_j |D_j(q)|² / h_j² the symbol of Σ_j D_jᵀ D_j / h_j²; sq = (4 sin²(q/2), 4 cos²(q/2)) per axis
    (2, 3, Nmax) with exact zeros, S the real view (N1, N2, 2N3) of the transform."""
    n1, n2, m = S.shape
    n3 = m // 2
    for i1 in range(n1):
        if i1 < lo or i1 >= hi:
            continue
        for i2 in range(n2):
            if kind == 1:
                c1 = sq[0, 0, i1] * ih2[0] + sq[0, 1, i2] * ih2[1]
                c2 = 0.0 * c1
                c3 = ih2[2] + 0.0 * c1
            else:
                c1 = sq[0, 0, i1] * sq[1, 1, i2] * ih2[0]
                c2 = sq[1, 0, i1] * sq[0, 1, i2] * ih2[1]
                c3 = sq[1, 0, i1] * sq[1, 1, i2] * ih2[2]
            row = S[i1, i2]
            for i3 in range(n3):
                if kind == 1:
                    lam = c1 + c3 * sq[0, 2, i3]
                else:
                    lam = (c1 + c2) * sq[1, 2, i3] + c3 * sq[0, 2, i3]
                w = 1.0 / lam if lam > 0.0 else 0.0 * lam
                row[2 * i3] = row[2 * i3] * w
                row[2 * i3 + 1] = row[2 * i3 + 1] * w


@njit(inline="always")
def _row_grad(psi, kind, i1, i2, j1, j2, g):
    """g[:, i3] ← D ψ along the row (i1, i2, :); j1, j2 the next indices (periodic).

    kind 1: forward differences (Willot et al. 2014); kind 2: differences across the voxel cube
    x + {0, 1}³ (Willot 2015), from the four rows A = (i1, i2), B = (i1, j2), C = (j1, i2),
    D = (j1, j2): D_1 = Σ(C + D) − Σ(A + B), D_2 = Σ(B + D) − Σ(A + C) over {i3, i3 + 1},
    D_3 = S(i3 + 1) − S(i3) with S = A + B + C + D."""
    n3 = psi.shape[2]
    A = psi[i1, i2]
    B = psi[i1, j2]
    C = psi[j1, i2]
    D = psi[j1, j2]
    for i3 in range(n3):
        _grad_real(A, B, C, D, kind, g, i3, i3 + 1 if i3 + 1 < n3 else 0)


@_kernel
def _stencil_gradient(psi, F, kind, ih, lo, hi):
    """Planes lo..hi−1: F_j ← D_j ψ / h_j, F of shape (3, N1, N2, N3)."""
    n1, n2, n3 = psi.shape
    for i1 in range(n1):
        if i1 < lo or i1 >= hi:
            continue
        j1 = i1 + 1 if i1 + 1 < n1 else 0
        g = np.empty((3, n3), dtype=psi.dtype)
        for i2 in range(n2):
            j2 = i2 + 1 if i2 + 1 < n2 else 0
            _row_grad(psi, kind, i1, i2, j1, j2, g)
            for c in range(3):
                h = ih[c]
                for i3 in range(n3):
                    F[c, i1, i2, i3] = g[c, i3] * h


@njit(inline="always")
def _grad_real(A, B, C, D, kind, g, k, kn):
    """g[:, k] ← D ψ at the real value k of the real views of the rows A..D (:func:`_row_grad`;
    a difference stencil acts on the real and imaginary parts alike); kn = k + 2 (periodic) is
    the same part of the next voxel."""
    if kind == 1:
        c = A[k]
        g[0, k] = C[k] - c
        g[1, k] = B[k] - c
        g[2, k] = A[kn] - c
    else:
        a = A[k] + A[kn]
        b = B[k] + B[kn]
        c = C[k] + C[kn]
        d = D[k] + D[kn]
        g[0, k] = (c + d) - (a + b)
        g[1, k] = (b + d) - (a + c)
        g[2, k] = (A[kn] + B[kn] + C[kn] + D[kn]) - (A[k] + B[k] + C[k] + D[k])


@njit(cache=True, nogil=True)
def _axpy(y, x, a_re, a_im, lo, hi):
    """Chunks lo..hi−1 of real views (d, 2N): y ← y + α x, rounded as Numba's complex y + α x (no
    fast-math: with reassociation LLVM rounds the sum differently). A pass of its own: a helper
    called from a fast-math kernel is compiled with the caller's flags."""
    d, n2 = y.shape
    n = n2 // 2
    for c in range((n + CHUNK - 1) // CHUNK):
        if c < lo or c >= hi:
            continue
        i0 = c * CHUNK
        i1 = min(n, i0 + CHUNK)
        for j in range(d):
            yj = y[j, 2 * i0:2 * i1]
            xj = x[j, 2 * i0:2 * i1]
            for i in range(i1 - i0):
                x_re = xj[2 * i]
                x_im = xj[2 * i + 1]
                yj[2 * i] = yj[2 * i] + (a_re * x_re - a_im * x_im)
                yj[2 * i + 1] = yj[2 * i + 1] + (a_re * x_im + a_im * x_re)


@_kernel_split
def _cocg_update_stencil(r, psi, a_re, a_im, kind, ih, part, lo, hi):
    """Planes lo..hi−1: r ← r − α D ψ / h (q = Γ ε p from its potential); part[i1] ← (rᵀr, ‖r‖²)
    of the plane.

    Real views: r (3, 2N), psi (N1, N2, 2 N3), α = a_re + i a_im (see :func:`_direction_and_eps`);
    the row gradient is taken on the real values with the wrap of the last voxel outside the
    loop, which then vectorises."""
    n1, n2, m = psi.shape
    n3 = m // 2
    for i1 in range(n1):
        if i1 < lo or i1 >= hi:
            continue
        j1 = i1 + 1 if i1 + 1 < n1 else 0
        g = np.empty((3, m), dtype=psi.dtype)
        rr_re = 0.0
        rr_im = 0.0
        nr = 0.0
        for i2 in range(n2):
            j2 = i2 + 1 if i2 + 1 < n2 else 0
            A = psi[i1, i2]
            B = psi[i1, j2]
            C = psi[j1, i2]
            D = psi[j1, j2]
            if kind == 1:
                for k in range(m - 2):
                    _grad_real(A, B, C, D, 1, g, k, k + 2)
            else:
                for k in range(m - 2):
                    _grad_real(A, B, C, D, 2, g, k, k + 2)
            _grad_real(A, B, C, D, kind, g, m - 2, 0)
            _grad_real(A, B, C, D, kind, g, m - 1, 1)
            base = 2 * (i1 * n2 + i2) * n3
            for c in range(3):
                h_re = a_re * ih[c]  # α / h_c
                h_im = a_im * ih[c]
                rc = r[c, base:base + m]
                gc = g[c]
                for i3 in range(n3):
                    g_re = gc[2 * i3]
                    g_im = gc[2 * i3 + 1]
                    v_re = rc[2 * i3] - (h_re * g_re - h_im * g_im)
                    v_im = rc[2 * i3 + 1] - (h_re * g_im + h_im * g_re)
                    rc[2 * i3] = v_re
                    rc[2 * i3 + 1] = v_im
                    rr_re += v_re * v_re - v_im * v_im
                    rr_im += 2.0 * v_re * v_im
                    nr += v_re * v_re + v_im * v_im
        part[i1, 0] = rr_re
        part[i1, 1] = rr_im
        part[i1, 2] = nr


def stencil_divergence(F, s, kind, ih):
    """s ← Σ_j D_jᵀ F_j / h_j (real space, F (3, N1, N2, N3), s (N1, N2, N3) complex)."""
    _split(_stencil_divergence, s.shape[0], F, _real_view(F), _real_view(s), kind, ih)
    return s


def inverse_laplacian(S, sq, kind, ih):
    """Ŝ ← Ŝ / Σ_j |D_j(q)|² / h_j² in place (0 where that vanishes); ``sq`` from :func:`stencil_symbols`."""
    ih2 = (np.asarray(ih) ** 2).astype(sq.dtype)
    _split(_inverse_laplacian, S.shape[0], S, _real_view(S), sq, kind, ih2)
    return S


def stencil_symbols(shape, dtype) -> np.ndarray:
    """(4 sin²(q/2), 4 cos²(q/2)) per axis, shape (2, 3, Nmax), real ``dtype``: |e^{iq} − 1|² and
    |e^{iq} + 1|², with exact zeros at q = 0 and at the Nyquist index of an even axis."""
    nmax = max(shape)
    sq = np.zeros((2, 3, nmax))
    for j, n in enumerate(shape):
        q = 2.0 * np.pi * np.arange(n) / n
        sn, cs = np.sin(q / 2.0), np.cos(q / 2.0)
        sn[0] = 0.0
        if n % 2 == 0:
            cs[n // 2] = 0.0
        sq[0, j, :n] = 4.0 * sn**2
        sq[1, j, :n] = 4.0 * cs**2
    return sq.astype(dtype)


def stencil_gradient(psi, F, kind, ih):
    """F_j ← D_j ψ / h_j (kind 1: forward difference; 2: voxel-cube difference)."""
    _split(_stencil_gradient, psi.shape[0], F, psi, F, kind, ih)
    return F


def cocg_update_stencil(x, r, p, psi, alpha, kind, ih, update_x=True):
    """x ← x + α p (if ``update_x``; else x is not touched); r ← r − α D ψ / h. Returns (rᵀr, ‖r‖²)."""
    real = r.real.dtype
    alpha = r.dtype.type(alpha)
    a_re, a_im = real.type(alpha.real), real.type(alpha.imag)
    if update_x:
        _split(_axpy, _nchunk(x.shape[1]), x, _real_view(x), _real_view(p), a_re, a_im)
    part = np.zeros((psi.shape[0], 3))
    _split(_cocg_update_stencil, psi.shape[0], r, _real_view(r), _real_view(psi), a_re, a_im, kind,
           np.asarray(ih, dtype=real), part)
    tot = _column_sums(part)
    return complex(tot[0], tot[1]), float(tot[2])


@njit(cache=True)
def _phase_sums(x, labels, nphase):
    d, n = x.shape
    out = np.zeros((nphase, d), dtype=np.complex128)
    for i in range(n):
        lab = labels[i]
        for j in range(d):
            out[lab, j] += x[j, i]
    return out


def mean_flux(x, labels, tab, e0, counts):
    """⟨ε (e0 + x)⟩ as a complex128 d-vector, phase by phase (sums in complex128)."""
    n = labels.size
    sums = _phase_sums(x, labels, tab.size) if x is not None else np.zeros((tab.size, len(e0)), complex)
    tab128 = tab.astype(np.complex128)
    per_phase = sums + counts[:, None] * np.asarray(e0, dtype=np.complex128)[None, :]
    return (tab128[:, None] * per_phase).sum(axis=0) / n


def set_threads(n: int) -> None:
    """Use at most ``n`` Numba threads from now on, in the calling thread (a lasting change:
    prefer :func:`threads`, which restores the previous count)."""
    numba.set_num_threads(max(1, min(int(n), numba.config.NUMBA_NUM_THREADS)))


@contextmanager
def threads(n: int):
    """Run the enclosed kernels with at most ``n`` Numba threads, then restore the previous
    count: a solve never changes the thread count of later kernels in the process."""
    before = numba.get_num_threads()
    set_threads(n)
    try:
        yield
    finally:
        numba.set_num_threads(before)
