"""Green (projection) operators of the periodic conductivity / permittivity problem.

The quasi-static problem ``div(ε(x) E(x)) = 0``, ``E = E0 + ∇φ`` with φ periodic, is solved
in Fourier space with the projection Γ onto periodic gradient fields of zero mean:

    Γ(q)_ij = k_i(q) conj(k_j(q)) / |k(q)|²,   Γ(0) = 0,

where k(q) is the *symbol* of the discrete gradient. Γ is an orthogonal projection at every
frequency; with a reference medium ε0 the classical Green operator is Γ0 = Γ / ε0. Every
symbol here factorises per axis,

    k_j(q) = a_j(q_j) · Π_{l ≠ j} b_l(q_l),

so an operator is stored as d pairs of 1-D arrays (a_j, b_j) of length N_j — never as
full-size arrays — and Γ is evaluated on the fly inside the Numba kernels.

Operators (registry :data:`GREEN_OPERATORS`, dispatcher :func:`green_operator`):

- :func:`green_continuous` — the spectral (Moulinec-Suquet) symbol k_j = q_j / h_j, with the
  Nyquist frequencies handled so that the real-space operator stays real and symmetric.
- :func:`green_willot2014` — the finite-difference (forward difference, "resistor
  network") symbol k_j = (exp(i q_j) − 1) / h_j of Willot, Abdallah & Pellegrini (2014).
- :func:`green_willot2015` — the "rotated" scheme of Willot (2015),
  k_j ∝ tan(q_j/2) Π_l (1 + exp(i q_l)), i.e. up to a common factor
  k_j = sin(q_j/2) Π_{l≠j} cos(q_l/2) (derivatives on the voxel corners), which removes
  most of the ringing of the spectral scheme.

Here q_j = 2π n_j / N_j is the reduced frequency on axis j and h_j the voxel size along j
(any unit: only ratios matter).

References
----------
- Moulinec, H., Suquet, P. (1998). A numerical method for computing the overall response of
  nonlinear composites with complex microstructure. Comput. Methods Appl. Mech. Eng. 157,
  69-94. doi:10.1016/S0045-7825(97)00218-1
- Willot, F., Abdallah, B., Pellegrini, Y.-P. (2014). Fourier-based schemes with modified
  Green operator for computing the electrical response of heterogeneous media with accurate
  local fields. Int. J. Numer. Methods Eng. 98(7), 518-533. doi:10.1002/nme.4641
- Willot, F. (2015). Fourier-based schemes for computing the mechanical response of
  composites with accurate local fields. C. R. Mécanique 343(3), 232-245.
  doi:10.1016/j.crme.2014.12.005
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nmmm.errors import InvalidInputError


@dataclass(frozen=True)
class GreenOperator:
    """A projection operator on periodic gradient fields, stored as per-axis 1-D factors.

    Attributes
    ----------
    name : str
        Registry name (``"continuous"``, ``"willot2014"``, ``"willot2015"``).
    a, b : tuple of 1-D complex arrays
        Per-axis factors: k_j(q) = a_j[n_j] · Π_{l≠j} b_l[n_l].
    nyquist : tuple of 1-D bool arrays
        Frequencies at the Nyquist index of an even axis, only flagged for the spectral
        symbol: there the component k_j is kept only for frequencies whose other components
        are all 0 or Nyquist (so that Γ(−q) = conj Γ(q) and the real-space operator is real).
    shape : tuple of int
        Grid shape.
    """

    name: str
    a: tuple
    b: tuple
    nyquist: tuple
    shape: tuple

    @property
    def ndim(self) -> int:
        return len(self.shape)

    def symbol(self) -> np.ndarray:
        """The full symbol k(q), shape ``(d, *shape)`` (for tests and plots; O(d·N) memory)."""
        d = self.ndim
        grids = []
        for j in range(d):
            kj = np.ones(self.shape, dtype=complex)
            for l in range(d):
                f = self.a[l] if l == j else self.b[l]
                kj = kj * f.reshape([-1 if m == l else 1 for m in range(d)])
            grids.append(kj)
        k = np.stack(grids)
        if any(ny.any() for ny in self.nyquist):
            regular = np.zeros(self.shape, dtype=bool)
            for l in range(d):
                n = np.arange(self.shape[l])
                reg_l = (n != 0) & ~self.nyquist[l]
                regular |= reg_l.reshape([-1 if m == l else 1 for m in range(d)])
            for j in range(d):
                ny = self.nyquist[j].reshape([-1 if m == j else 1 for m in range(d)])
                k[j] = np.where(ny & regular, 0.0, k[j])
        return k

    def matrix(self) -> np.ndarray:
        """The full projection Γ(q), shape ``(d, d, *shape)`` (tests only)."""
        k = self.symbol()
        n2 = np.sum(np.abs(k) ** 2, axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            g = k[:, None] * np.conj(k[None, :]) / n2
        return np.where(n2 > 0, g, 0.0)


def _reduced_frequencies(n: int) -> np.ndarray:
    return 2.0 * np.pi * np.arange(n) / n


def _check(shape, spacing):
    shape = tuple(int(s) for s in shape)
    if len(shape) not in (2, 3) or min(shape) < 1:
        raise InvalidInputError(f"grid shape must be 2-D or 3-D with positive sizes, got {shape}")
    if spacing is None:
        spacing = (1.0,) * len(shape)
    spacing = np.broadcast_to(np.asarray(spacing, dtype=float), (len(shape),))
    if not np.all(np.isfinite(spacing)) or np.any(spacing <= 0):
        raise InvalidInputError(f"voxel spacing must be finite and > 0, got {tuple(spacing)}")
    return shape, tuple(float(h) for h in spacing)


def green_continuous(shape, spacing=None) -> GreenOperator:
    """Spectral symbol k_j = q_j / h_j with q_j in (−π, π] (Moulinec & Suquet 1998).

    At the Nyquist index of an even axis q_j = π is used for frequencies whose other
    components are all 0 or Nyquist (e.g. a one-voxel laminate stays exact) and k_j = 0
    otherwise, which keeps the real-space operator real and symmetric.
    """
    shape, spacing = _check(shape, spacing)
    a, b, ny = [], [], []
    for n, h in zip(shape, spacing):
        m = np.arange(n)
        q = 2.0 * np.pi * np.where(m <= n // 2, m, m - n) / n
        flag = np.zeros(n, dtype=bool)
        if n % 2 == 0 and n > 1:
            q[n // 2] = np.pi
            flag[n // 2] = True
        a.append((q / h).astype(complex))
        b.append(np.ones(n, dtype=complex))
        ny.append(flag)
    return GreenOperator("continuous", tuple(a), tuple(b), tuple(ny), shape)


def green_willot2014(shape, spacing=None) -> GreenOperator:
    """Forward-difference symbol k_j = (exp(i q_j) − 1) / h_j (Willot, Abdallah, Pellegrini 2014)."""
    shape, spacing = _check(shape, spacing)
    a, b, ny = [], [], []
    for n, h in zip(shape, spacing):
        q = _reduced_frequencies(n)
        a.append((np.exp(1j * q) - 1.0) / h)
        b.append(np.ones(n, dtype=complex))
        ny.append(np.zeros(n, dtype=bool))
    return GreenOperator("willot2014", tuple(a), tuple(b), tuple(ny), shape)


def green_willot2015(shape, spacing=None) -> GreenOperator:
    """Rotated scheme of Willot (2015): k_j ∝ tan(q_j/2) Π_l (1 + exp(i q_l)) / h_j.

    Dropping the common factor Π_l 2 cos(q_l/2) exp(i q_l/2) (it cancels in Γ), the symbol
    is k_j = sin(q_j/2)/h_j · Π_{l≠j} cos(q_l/2), real, with exact zeros at the Nyquist index.
    """
    shape, spacing = _check(shape, spacing)
    a, b, ny = [], [], []
    for n, h in zip(shape, spacing):
        q = _reduced_frequencies(n)
        s = np.sin(q / 2.0)
        c = np.cos(q / 2.0)
        s[0] = 0.0
        if n % 2 == 0:
            c[n // 2] = 0.0
        a.append((s / h).astype(complex))
        b.append(c.astype(complex))
        ny.append(np.zeros(n, dtype=bool))
    return GreenOperator("willot2015", tuple(a), tuple(b), tuple(ny), shape)


#: Registry of Green operators: name -> constructor(shape, spacing).
GREEN_OPERATORS = {
    "continuous": green_continuous,
    "willot2014": green_willot2014,
    "willot2015": green_willot2015,
}

_ALIASES = {
    "spectral": "continuous",
    "moulinec-suquet": "continuous",
    "fd": "willot2014",
    "finite-difference": "willot2014",
    "wap2014": "willot2014",
    "rotated": "willot2015",
}


def green_operator(shape, method: str = "willot2015", spacing=None) -> GreenOperator:
    """Build the Green operator ``method`` (see :data:`GREEN_OPERATORS`) for a grid ``shape``."""
    if isinstance(method, GreenOperator):
        return method
    key = str(method).lower().replace("_", "-")
    key = _ALIASES.get(key, key)
    if key not in GREEN_OPERATORS:
        raise InvalidInputError(
            f"unknown Green operator {method!r}; choose one of {sorted(GREEN_OPERATORS)} "
            f"(aliases {sorted(_ALIASES)})"
        )
    return GREEN_OPERATORS[key](shape, spacing)


def stacked_factors(op: GreenOperator, dtype=np.complex128):
    """Pack the per-axis factors as ``(3, Nmax)`` arrays for the kernels (2-D padded to 3-D)."""
    shape = tuple(op.shape) + (1,) * (3 - op.ndim)
    nmax = max(shape)
    a = np.zeros((3, nmax), dtype=dtype)
    b = np.ones((3, nmax), dtype=dtype)
    ny = np.zeros((3, nmax), dtype=np.bool_)
    for j in range(op.ndim):
        n = op.shape[j]
        a[j, :n] = op.a[j]
        b[j, :n] = op.b[j]
        ny[j, :n] = op.nyquist[j]
    return a, b, ny, shape


__all__ = [
    "GreenOperator",
    "GREEN_OPERATORS",
    "green_operator",
    "green_continuous",
    "green_willot2014",
    "green_willot2015",
    "stacked_factors",
]
