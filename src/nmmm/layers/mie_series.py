"""Numba kernels of the Mie series for :mod:`nmmm.layers.mie_scattering` (its *Algorithm* section
says what they compute and cites the sources: Bohren & Huffman 1983, Wiscombe 1980, Yang 2003).

- :func:`_one_particle` — L ≥ 1 concentric layers, efficiencies and amplitudes S1, S2 (Yang 2003).
- :func:`_one_sphere` — one homogeneous sphere, efficiencies only (BHMIE).
- :func:`_mie_batch` / :data:`_mie_batch_serial` — a flattened batch, threaded / on the caller.
- :func:`_mie_single` — one sphere from plain numbers with its own input checks (the fast path).
"""

from __future__ import annotations

import math
import types

import numba
import numpy as np

@numba.njit(cache=True, nogil=True)
def _n_max(x):
    """Wiscombe's (1980) number of series terms for size parameter x."""
    return int(x + 4.05 * x ** (1.0 / 3.0) + 2.0)


#: below this outer size parameter the coefficients are formed without cancellation, with 3 more terms
SMALL_X = 1.0


@numba.njit(cache=True, nogil=True)
def _n_terms(x):
    """Series length: Wiscombe's n_max, + 3 below :data:`SMALL_X` (his criterion leaves ~1e-10 there)."""
    return _n_max(x) + 3 if x < SMALL_X else _n_max(x)


@numba.njit(cache=True, nogil=True)
def _small_x_functions(x, nmax, w):
    """For x < SMALL_X, write psi_n/xi_n, D_n(x) = psi_n'/psi_n, D3_n(x) = xi_n'/xi_n and
    E_n(x) = (n+1)/x - D_n(x) (n = 0..nmax) to w[0:k], w[k:2k], w[2k:3k], w[3k:4k], k = nmax + 1.

    The upward psi_1 = sin x/x - cos x, and a_n's numerator t psi_n - psi_{n-1}, cancel (2e-3 relative
    error in Q_sca at x = 1e-6): here D_n(x) comes down (BH eq. 4.89), psi_n = psi_{n-1}/(D_n + n/x)
    has no zero for x < pi, eta_n goes up (dominant), and a_n = (psi_n/xi_n)(H/m - D_n)/(H/m - D3_n);
    b_n's m D_n(mx) - D_n(x) = E_n(x) - m E_n(mx) (both D ~ (n+1)/x cancel otherwise)."""
    k = nmax + 1
    d = 0.0
    for n in range(nmax + 12, 0, -1):
        e = 1.0 / (d + n / x)
        d = n / x - e
        if n - 1 <= nmax:
            w[k + n - 1] = d
            w[3 * k + n - 1] = e
    psi, eta_m1, eta = math.sin(x), 0.0, -math.cos(x)
    xi_prev = complex(psi, eta)
    for n in range(1, nmax + 1):
        psi = psi / (w[k + n].real + n / x)
        eta, eta_m1 = ((2.0 * n - 1.0) / x * eta - eta_m1) if n > 1 else (-math.cos(x) / x - math.sin(x)), eta
        xi = complex(psi, eta)
        w[n] = psi / xi
        w[2 * k + n] = xi_prev / xi - n / x
        xi_prev = xi


@numba.njit(cache=True, nogil=True)
def _one_particle(m, x, mu, out, s1, s2):
    """Mie series for one (possibly layered) sphere.

    m, x: (L,) relative indices and size parameters of the layers, inner to outer.
    mu: (A,) cos(θ) for the amplitudes (A may be 0). Writes out[0:4] = qext, qsca, qback, g
    and s1[:], s2[:].
    """
    L = m.shape[0]
    xL = x[L - 1]
    mL = m[L - 1]
    nmax = _n_terms(xL)
    small = xL < SMALL_X
    w = np.empty(4 * (nmax + 1), dtype=np.complex128)
    if small:
        _small_x_functions(xL, nmax, w)

    # arguments of the layer functions: z[0] = m_1 x_1; for layer l >= 1 (0-based):
    # z[2l-1] = m_l x_{l-1} (inner surface), z[2l] = m_l x_l (outer surface)
    nz = 2 * L - 1
    z = np.empty(nz, dtype=np.complex128)
    z[0] = m[0] * x[0]
    for l in range(1, L):
        z[2 * l - 1] = m[l] * x[l - 1]
        z[2 * l] = m[l] * x[l]

    # D_n^(1)(z) by downward recurrence (Wiscombe 1980; BH eq. 4.89)
    D1 = np.empty((nz, nmax + 1), dtype=np.complex128)
    EE = np.empty((nz, nmax + 1), dtype=np.complex128)  # E_n(z) = (n+1)/z - D_n(z), without cancelling
    for k in range(nz):
        # start well above both n_max and |z|: the margin grows like |z|^(1/3) (D_nmax agrees
        # with Lentz's continued fraction to < 1e-9 for |z| in [0.05, 1000], any phase)
        az = abs(z[k])
        nstart = int(max(nmax, az) + 4.0 * az ** (1.0 / 3.0)) + 10
        d = 0.0 + 0.0j
        zk = z[k]
        for n in range(nstart, 0, -1):
            e = 1.0 / (d + n / zk)
            d = n / zk - e
            if n - 1 <= nmax:
                D1[k, n - 1] = d
                EE[k, n - 1] = e
    # (the loop stores D_{n-1} for n - 1 <= nmax: indices 0..nmax are filled)

    # per-layer upward state (Yang 2003): psi*xi products, D^(3) and Q ratios
    nlay = L - 1
    pxi1 = np.empty(max(nlay, 1), dtype=np.complex128)
    pxi2 = np.empty(max(nlay, 1), dtype=np.complex128)
    d3a = np.empty(max(nlay, 1), dtype=np.complex128)  # D3_{n-1}(z1)
    d3b = np.empty(max(nlay, 1), dtype=np.complex128)  # D3_{n-1}(z2)
    Q = np.empty(max(nlay, 1), dtype=np.complex128)
    for l in range(1, L):
        z1 = z[2 * l - 1]
        z2 = z[2 * l]
        e1 = np.exp(2j * z1)
        e2 = np.exp(2j * z2)
        d3a[l - 1] = 1j
        d3b[l - 1] = 1j
        if abs(z2) < 1.0:  # 1 - e^{2iz} = -2i e^{iz} sin z, without cancelling for small z
            pxi1[l - 1] = -1j * np.exp(1j * z1) * np.sin(z1)
            pxi2[l - 1] = -1j * np.exp(1j * z2) * np.sin(z2)
            Q[l - 1] = np.exp(1j * (z2 - z1)) * np.sin(z1) / np.sin(z2)
            continue
        pxi1[l - 1] = 0.5 * (1.0 - e1)
        pxi2[l - 1] = 0.5 * (1.0 - e2)
        # Q_0 = [psi_0/xi_0](z1) / [psi_0/xi_0](z2), written so that nothing overflows
        Q[l - 1] = np.exp(2j * (z2 - z1)) * (e1 - 1.0) / (e2 - 1.0)

    # Riccati-Bessel functions of the real outer size parameter, upward (BH p. 478)
    sx = np.sin(xL)
    cx = np.cos(xL)
    psi_m1 = sx  # psi_0
    eta_m1 = -cx  # eta_0 = x y_0(x)
    # amplitude-function state
    A = mu.shape[0]
    pi_prev = np.zeros(A)
    pi_cur = np.ones(A)
    for a in range(A):
        s1[a] = 0.0
        s2[a] = 0.0

    qext = 0.0
    qsca = 0.0
    qback = 0.0 + 0.0j
    gsum = 0.0
    an_prev = 0.0 + 0.0j
    bn_prev = 0.0 + 0.0j
    psi_n = 0.0
    eta_n = 0.0
    for n in range(1, nmax + 1):
        if n == 1:
            psi_n = sx / xL - cx
            eta_n = -cx / xL - sx
        else:
            f = (2.0 * n - 1.0) / xL
            psi_new = f * psi_n - psi_m1
            eta_new = f * eta_n - eta_m1
            psi_m1 = psi_n
            eta_m1 = eta_n
            psi_n = psi_new
            eta_n = eta_new
        Ha = D1[0, n]
        Hb = Ha
        db = 0.0j  # Hb - D_n(z_outer), kept apart so that m Hb - D_n(x) does not cancel at small x
        for l in range(1, L):
            i1 = 2 * l - 1
            i2 = 2 * l
            z1 = z[i1]
            z2 = z[i2]
            D1z1 = D1[i1, n]
            D1z2 = D1[i2, n]
            # psi_n xi_n and D3_n, upward (Yang 2003, eqs. 18-20)
            pxi1[l - 1] = pxi1[l - 1] * EE[i1, n - 1] * (n / z1 - d3a[l - 1])  # n/z - D_{n-1} = E_{n-1}
            pxi2[l - 1] = pxi2[l - 1] * EE[i2, n - 1] * (n / z2 - d3b[l - 1])
            d3a_n = D1z1 + 1j / pxi1[l - 1]
            d3b_n = D1z2 + 1j / pxi2[l - 1]
            # Q_n = [psi_n/xi_n](z1) / [psi_n/xi_n](z2) (Yang 2003, eq. 32)
            r = x[l - 1] / x[l]
            Q[l - 1] = (
                Q[l - 1]
                * r
                * r
                * (z2 * D1z2 + n)
                * (n - z2 * d3b[l - 1])
                / ((z1 * D1z1 + n) * (n - z1 * d3a[l - 1]))
            )
            d3a[l - 1] = d3a_n
            d3b[l - 1] = d3b_n
            q = Q[l - 1]
            G1 = m[l] * Ha - m[l - 1] * D1z1
            G2 = m[l] * Ha - m[l - 1] * d3a_n
            Ha = (G2 * D1z2 - q * G1 * d3b_n) / (G2 - q * G1)
            G1 = m[l - 1] * Hb - m[l] * D1z1
            G2 = m[l - 1] * Hb - m[l] * d3a_n
            db = q * G1 * (D1z2 - d3b_n) / (G2 - q * G1)
            Hb = D1z2 + db

        if small:
            k = nmax + 1
            an = w[n] * (Ha / mL - w[k + n]) / (Ha / mL - w[2 * k + n])
            bnum = w[3 * k + n] - mL * EE[nz - 1, n] + mL * db  # = m Hb - D_n(x)
            bn = w[n] * bnum / (mL * Hb - w[2 * k + n])
        else:
            xi_n = psi_n + 1j * eta_n
            xi_m1 = psi_m1 + 1j * eta_m1
            ta = Ha / mL + n / xL
            tb = mL * Hb + n / xL
            an = (ta * psi_n - psi_m1) / (ta * xi_n - xi_m1)
            bn = (tb * psi_n - psi_m1) / (tb * xi_n - xi_m1)

        c = 2.0 * n + 1.0
        qext += c * (an.real + bn.real)
        qsca += c * (an.real * an.real + an.imag * an.imag + bn.real * bn.real + bn.imag * bn.imag)
        if n % 2 == 1:
            qback -= c * (an - bn)
        else:
            qback += c * (an - bn)
        if n > 1:
            nm = n - 1.0
            gsum += nm * (nm + 2.0) / (nm + 1.0) * (
                an_prev * np.conj(an) + bn_prev * np.conj(bn)
            ).real
        gsum += c / (n * (n + 1.0)) * (an * np.conj(bn)).real
        an_prev = an
        bn_prev = bn

        if A > 0:
            fn = c / (n * (n + 1.0))
            for a in range(A):
                # pi_n and tau_n by upward recurrence (BH eqs. 4.47)
                if n > 1:
                    pin = ((2.0 * n - 1.0) * mu[a] * pi_cur[a] - n * pi_prev[a]) / (n - 1.0)
                    pi_prev[a] = pi_cur[a]
                    pi_cur[a] = pin
                pin = pi_cur[a]
                taun = n * mu[a] * pin - (n + 1.0) * pi_prev[a]
                s1[a] += fn * (an * pin + bn * taun)
                s2[a] += fn * (an * taun + bn * pin)

    x2 = xL * xL
    out[0] = 2.0 * qext / x2
    out[1] = 2.0 * qsca / x2
    out[2] = (qback.real * qback.real + qback.imag * qback.imag) / x2
    out[3] = 4.0 * gsum / (x2 * out[1]) if out[1] > 0 else 0.0


@numba.njit(cache=True, nogil=True, inline="always")
def _rec(w):
    """1 / w for complex w (cheaper than a general complex division)."""
    s = 1.0 / (w.real * w.real + w.imag * w.imag)
    return complex(w.real * s, -w.imag * s)


@numba.njit(cache=True, nogil=True)
def _one_sphere(m, x, D):
    """Homogeneous-sphere fast path of :func:`_one_particle` (no amplitudes): (Q_ext, Q_sca, Q_back, g).

    D is a complex work array of length >= max(N* + 1, 6 (n_max + 1)). Same algorithm (BH appendix A
    with Wiscombe's downward recurrence and series length), written without allocations.
    """
    nmax = _n_terms(x)
    small = x < SMALL_X
    k = nmax + 1
    if small:
        _small_x_functions(x, nmax, D[k:])
    z = m * x
    zinv = _rec(z)
    az = abs(z)
    nstart = int(max(nmax, az) + 4.0 * az ** (1.0 / 3.0)) + 10
    d = 0.0 + 0.0j
    for n in range(nstart, 0, -1):
        nz = n * zinv
        e = _rec(d + nz)
        d = nz - e
        if n - 1 <= nmax:
            D[n - 1] = d
            if small:
                D[5 * k + n - 1] = e  # E_n(mx), see _small_x_functions
    minv = _rec(m)
    xinv = 1.0 / x
    sx = np.sin(x)
    cx = np.cos(x)
    psi_m1 = sx
    eta_m1 = -cx
    psi_n = sx * xinv - cx
    eta_n = -cx * xinv - sx
    qext = 0.0
    qsca = 0.0
    qbr = 0.0
    qbi = 0.0
    gsum = 0.0
    an_prev = 0.0 + 0.0j
    bn_prev = 0.0 + 0.0j
    for n in range(1, nmax + 1):
        if n > 1:
            f = (2.0 * n - 1.0) * xinv
            psi_new = f * psi_n - psi_m1
            eta_new = f * eta_n - eta_m1
            psi_m1 = psi_n
            eta_m1 = eta_n
            psi_n = psi_new
            eta_n = eta_new
        if small:
            ha, hb = D[n] * minv, D[n] * m
            an = D[k + n] * (ha - D[2 * k + n]) / (ha - D[3 * k + n])
            bn = D[k + n] * (D[4 * k + n] - m * D[5 * k + n]) / (hb - D[3 * k + n])
        else:
            nx = n * xinv
            xi_n = complex(psi_n, eta_n)
            xi_m1 = complex(psi_m1, eta_m1)
            ta = D[n] * minv + nx
            tb = D[n] * m + nx
            an = (ta * psi_n - psi_m1) * _rec(ta * xi_n - xi_m1)
            bn = (tb * psi_n - psi_m1) * _rec(tb * xi_n - xi_m1)
        c = 2.0 * n + 1.0
        qext += c * (an.real + bn.real)
        qsca += c * (an.real * an.real + an.imag * an.imag + bn.real * bn.real + bn.imag * bn.imag)
        sgn = -c if n % 2 == 1 else c
        qbr += sgn * (an.real - bn.real)
        qbi += sgn * (an.imag - bn.imag)
        if n > 1:
            nm = n - 1.0
            gsum += nm * (nm + 2.0) / (nm + 1.0) * (
                an_prev.real * an.real + an_prev.imag * an.imag + bn_prev.real * bn.real + bn_prev.imag * bn.imag
            )
        gsum += c / (n * (n + 1.0)) * (an.real * bn.real + an.imag * bn.imag)
        an_prev = an
        bn_prev = bn
    x2 = x * x
    qsca = 2.0 * qsca / x2
    return 2.0 * qext / x2, qsca, (qbr * qbr + qbi * qbi) / x2, 4.0 * gsum / (x2 * qsca) if qsca > 0 else 0.0


@numba.njit(parallel=True, cache=True)
def _mie_batch(m, x, mu, out, s1, s2, nchunk):
    """Run the Mie series over a batch: m, x (B, L); out (B, 4); s1, s2 (B, A).

    The batch is cut into chunks, one work array per chunk; chunks run in parallel.
    """
    B = m.shape[0]
    L = m.shape[1]
    A = mu.shape[0]
    for c in numba.prange(nchunk):
        lo = (B * c) // nchunk
        hi = (B * (c + 1)) // nchunk
        if L == 1 and A == 0:
            nwork = 72
            for b in range(lo, hi):
                az = abs(m[b, 0] * x[b, 0])
                nw = int(max(_n_terms(x[b, 0]), az) + 4.0 * az ** (1.0 / 3.0)) + 12
                if nw > nwork:
                    nwork = nw
            D = np.empty(nwork, dtype=np.complex128)
            for b in range(lo, hi):
                out[b, 0], out[b, 1], out[b, 2], out[b, 3] = _one_sphere(m[b, 0], x[b, 0], D)
        else:
            for b in range(lo, hi):
                _one_particle(m[b], x[b], mu, out[b], s1[b], s2[b])


def _serial_copy(fn):
    """``fn`` under its own qualified name. Numba's on-disk cache names an entry by module,
    qualified name, first line and signature, not by ``parallel=``: ``njit(cache=True)`` of the
    same function as a ``parallel=True`` build shares its entry, and whichever build compiled
    first then serves both (found in homogenize's kernels, issue 22)."""
    ser = types.FunctionType(fn.__code__, fn.__globals__, fn.__name__ + "_serial", fn.__defaults__, fn.__closure__)
    ser.__qualname__ = fn.__qualname__ + "_serial"
    return ser


#: The same kernel compiled without threads: small batches run here, since waking the thread
#: pool costs ~10 µs on an idle machine and up to ~10 ms on a loaded one (issue 22).
_mie_batch_serial = numba.njit(cache=True)(_serial_copy(_mie_batch.py_func))

#: smallest size parameter the series is evaluated at: the small-x form is checked to 1e-10 against
#: 60-digit mpmath down to x = 1e-8 (tests/layers/test_mie_small_x.py); far below, x² underflows and the
#: efficiencies divide by zero. x = 1e-8 is a 2e-6 nm sphere in the visible, far below an atom.
MIN_SIZE_PARAMETER = 1.0e-8


@numba.njit(cache=True)
def _mie_single(n_particle, n_medium, diameter_nm, wavelength_nm, max_size_parameter):
    """One homogeneous sphere without amplitudes, from plain numbers: (ok, Q_ext, Q_sca, Q_back, g, x)
    by :func:`_one_sphere`; ok is False (and nothing computed) unless every argument is finite,
    n_medium, the diameter, the wavelength and n > 0, k >= 0 and MIN_SIZE_PARAMETER <= x <= ``max_size_parameter``: the
    general path then refuses the call and says why."""
    inf = np.inf
    # comparisons are False for NaN; the upper bounds exclude infinity
    if not (0.0 < wavelength_nm < inf and 0.0 < diameter_nm < inf and 0.0 < n_medium < inf
            and 0.0 < n_particle.real < inf and 0.0 <= n_particle.imag < inf):
        return False, 0.0, 0.0, 0.0, 0.0, 0.0
    x = math.pi * diameter_nm * n_medium / wavelength_nm
    if not MIN_SIZE_PARAMETER <= x <= max_size_parameter:
        return False, 0.0, 0.0, 0.0, 0.0, x
    s = 1.0 / n_medium  # m = n * (1 / n_medium) component by component, as _mie_layers forms it: the same bits
    m = complex(n_particle.real * s, n_particle.imag * s)
    az = abs(m * x)
    D = np.empty(max(72, int(max(_n_terms(x), az) + 4.0 * az ** (1.0 / 3.0)) + 12), dtype=np.complex128)
    qext, qsca, qback, g = _one_sphere(m, x, D)
    return True, qext, qsca, qback, g, x
