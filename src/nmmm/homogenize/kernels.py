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

Fields are stored as ``(d, N)`` arrays (d components, N voxels, C order); labels as a flat
``(N,)`` integer array indexing a per-phase permittivity table.
"""

from __future__ import annotations

import numba
import numpy as np
from numba import njit, prange


@njit(parallel=True, cache=True)
def project(F, a, b, ny, has_ny, mode):
    """Apply Γ (mode 0) or I − 2Γ (mode 1) in place to F of shape (d, N1, N2, N3)."""
    d = F.shape[0]
    n1, n2, n3 = F.shape[1], F.shape[2], F.shape[3]
    for i1 in prange(n1):
        k = np.zeros(3, dtype=F.dtype)
        for i2 in range(n2):
            for i3 in range(n3):
                a1 = a[0, i1]
                a2 = a[1, i2]
                a3 = a[2, i3]
                b1 = b[0, i1]
                b2 = b[1, i2]
                b3 = b[2, i3]
                k[0] = a1 * b2 * b3
                k[1] = b1 * a2 * b3
                k[2] = b1 * b2 * a3
                if has_ny:
                    reg = ((i1 != 0) and not ny[0, i1]) or ((i2 != 0) and not ny[1, i2]) or (
                        (i3 != 0) and not ny[2, i3]
                    )
                    if reg:
                        if ny[0, i1]:
                            k[0] = 0.0
                        if ny[1, i2]:
                            k[1] = 0.0
                        if ny[2, i3]:
                            k[2] = 0.0
                n2k = 0.0
                s = 0.0 + 0.0j
                for j in range(d):
                    kr = k[j].real
                    ki = k[j].imag
                    n2k += kr * kr + ki * ki
                    s += np.conj(k[j]) * F[j, i1, i2, i3]
                if n2k > 0.0:
                    s = s / n2k
                    if mode == 0:
                        for j in range(d):
                            F[j, i1, i2, i3] = k[j] * s
                    else:
                        for j in range(d):
                            F[j, i1, i2, i3] = F[j, i1, i2, i3] - 2.0 * k[j] * s
                else:
                    if mode == 0:
                        for j in range(d):
                            F[j, i1, i2, i3] = 0.0
    return F


@njit(parallel=True, cache=True)
def direction_and_eps(p, q, r, beta, labels, tab, update):
    """If ``update``: p ← r + β p. Then q ← ε p. Returns Σ ε p·p (bilinear, no conjugate)."""
    d, n = p.shape
    acc = 0.0 + 0.0j
    for i in prange(n):
        e = tab[labels[i]]
        loc = 0.0 + 0.0j
        for j in range(d):
            if update:
                v = r[j, i] + beta * p[j, i]
                p[j, i] = v
            else:
                v = p[j, i]
            ev = e * v
            q[j, i] = ev
            loc += ev * v
        acc += loc
    return acc


@njit(parallel=True, cache=True)
def cocg_update(x, r, p, q, alpha):
    """x ← x + α p; r ← r − α q. Returns (rᵀr, ‖r‖²)."""
    d, n = x.shape
    rr = 0.0 + 0.0j
    nr = 0.0
    for i in prange(n):
        lrr = 0.0 + 0.0j
        lnr = 0.0
        for j in range(d):
            x[j, i] = x[j, i] + alpha * p[j, i]
            v = r[j, i] - alpha * q[j, i]
            r[j, i] = v
            lrr += v * v
            lnr += v.real * v.real + v.imag * v.imag
        rr += lrr
        nr += lnr
    return rr, nr


@njit(parallel=True, cache=True)
def eps_times(q, x, labels, tab, e0):
    """q ← ε (e0 + x) (e0 a constant vector; x may be the zero field when all-zero)."""
    d, n = x.shape
    for i in prange(n):
        e = tab[labels[i]]
        for j in range(d):
            q[j, i] = e * (e0[j] + x[j, i])
    return q


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
    """Use at most ``n`` Numba threads (the machine's cores are shared)."""
    numba.set_num_threads(max(1, min(int(n), numba.config.NUMBA_NUM_THREADS)))
