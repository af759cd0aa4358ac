"""Mie scattering by homogeneous, coated and multilayer spheres in a non-absorbing host.

Public functions
----------------
- :func:`mie` — homogeneous spheres: efficiencies ``qext, qsca, qabs, qback, g`` (and the
  amplitudes ``S1, S2`` on request), broadcasting over wavelengths × diameters × indices.
- :func:`mie_coated` — core–shell spheres.
- :func:`mie_multilayer` — concentric spheres with any number of layers.
- :class:`MieResult` — the frozen result object (efficiencies, cross sections, amplitudes).

Conventions: wavelengths and diameters in nm, angles in degrees, indices n + ik with k ≥ 0
and time dependence exp(−iωt) (Bohren & Huffman's convention), so the particle index is used
as given. The host must be non-absorbing (real index): Mie efficiencies are not uniquely
defined in an absorbing host, and :class:`nmmm.errors.InvalidInputError` says so. The
wavelength is the vacuum wavelength; the size parameter is x = π D n_medium / λ.

Algorithm
---------
One Numba kernel (:mod:`nmmm.layers.mie_series`), parallel over the flattened batch, handles L ≥ 1 layers with the recursion
of Yang (2003): the logarithmic derivative D_n⁽¹⁾(z) = ψ_n'/ψ_n is computed by *downward*
recurrence (Wiscombe 1980; Bohren & Huffman 1983, §4.8), started at
N* = max(n_max, |z|) + 16; D_n⁽³⁾ = ξ_n'/ξ_n and ψ_nξ_n upward; the series is stopped per
particle at Wiscombe's n_max = x + 4.05 x^{1/3} + 2. For L = 1 this is exactly the
Bohren–Huffman BHMIE algorithm. Below x = SMALL_X (1) the coefficients are written as ratios that do
not cancel (:func:`nmmm.layers.mie_series._small_x_functions`), with 3 more terms: 1e-13 relative to a 60-digit mpmath
evaluation for 1e-8 <= x < 1 (it was 6e-3 at x = 1e-6); the ratio form, not a truncated series. Efficiencies (Bohren & Huffman eqs. 4.61, 4.62, p. 120):

    Q_ext = 2/x² Σ (2n+1) Re(a_n + b_n),  Q_sca = 2/x² Σ (2n+1)(|a_n|² + |b_n|²)
    g Q_sca = 4/x² [Σ n(n+2)/(n+1) Re(a_n a*_{n+1} + b_n b*_{n+1}) + Σ (2n+1)/(n(n+1)) Re(a_n b*_n)]
    Q_back = 1/x² |Σ (2n+1)(−1)^n (a_n − b_n)|²

The amplitudes S1(θ), S2(θ) follow Bohren & Huffman eq. 4.74 (their normalization: the
differential scattering cross section for unpolarized light is (|S1|² + |S2|²) / (2k²),
k = 2π n_medium / λ).

References
----------
- C. F. Bohren, D. R. Huffman, *Absorption and Scattering of Light by Small Particles*,
  Wiley (1983), ch. 4, 8 and appendices A, B. doi:10.1002/9783527618156
- W. J. Wiscombe, "Improved Mie scattering algorithms", Appl. Opt. 19, 1505 (1980).
  doi:10.1364/AO.19.001505
- W. Yang, "Improved recursive algorithm for light scattering by a multilayered sphere",
  Appl. Opt. 42, 1710 (2003). doi:10.1364/AO.42.001710
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike

from nmmm.errors import InvalidInputError
from nmmm.layers.fresnel_equations import medium_nk
from nmmm.layers.mie_series import (  # noqa: F401  (SMALL_X: tests)
    MIN_SIZE_PARAMETER, SMALL_X, _mie_batch, _mie_batch_serial, _mie_single)
from nmmm.spectra import as_wavelength_nm, check_finite, check_positive

__all__ = ["MieResult", "mie", "mie_coated", "mie_multilayer"]


#: Series terms (Σ over particles of ~(x + 4 x^⅓ + 2) · (1 + angles)) above which a batch is
#: worth the parallel launch.
PARALLEL_ABOVE_TERMS = 20_000


def _work_terms(x_layers, n_angles) -> float:
    """Rough count of Mie series terms of a batch (outer size parameter per particle)."""
    x = x_layers[:, -1]
    return float(np.sum(x + 4.0 * np.cbrt(x) + 2.0)) * x_layers.shape[1] * (1 + n_angles)


_PLAIN_REAL = frozenset((int, float, np.float64, np.float32, np.int64, np.int32))
_PLAIN_COMPLEX = _PLAIN_REAL | {complex, np.complex128, np.complex64}
#: np.float64 scalars are made as value * _ONE (value a Python float): the same value, at half the cost
#: of np.float64(value)
_ONE = np.float64(1.0)
_new_object = object.__new__
_set_attribute = object.__setattr__


def _mie_scalar(n_particle, n_medium, diameter_nm, wavelength_nm):
    """Fast path of :func:`mie` for one sphere given as plain numbers, or None when any
    argument is not a plain valid number (the general path then validates and says why).

    Same kernel, same values; the result's fields are NumPy float64 scalars (shape ``()``,
    like the general path's 0-d arrays). The call costs about 1.6 µs, 0.7 of them the series
    (x ~ 3): every step here is timed against miepython's per-call cost (issue 22)."""
    if type(wavelength_nm) is float and type(diameter_nm) is float and type(n_medium) is float:
        w, d, nm = wavelength_nm, diameter_nm, n_medium  # the common case: no conversions
    elif type(wavelength_nm) in _PLAIN_REAL and type(diameter_nm) in _PLAIN_REAL and type(n_medium) in _PLAIN_REAL:
        w, d, nm = float(wavelength_nm), float(diameter_nm), float(n_medium)
    else:
        return None
    if type(n_particle) is complex:
        npc = n_particle
    elif type(n_particle) in _PLAIN_COMPLEX:
        npc = complex(n_particle)
    else:
        return None
    ok, qext, qsca, qback, g, x = _mie_single(npc, nm, d, w, MIE_MAX_SIZE_PARAMETER)
    if not ok:
        return None
    one = _ONE
    # the frozen dataclass's generated __init__ (12 object.__setattr__ calls) would cost more than
    # the series itself: fill the fields directly (angle_deg, s1, s2: the class defaults, None)
    result = _new_object(MieResult)
    _set_attribute(result, "__dict__", {
        "qext": qext * one, "qsca": qsca * one, "qabs": (qext - qsca) * one, "qback": qback * one, "g": g * one,
        "size_parameter": x * one, "diameter_nm": d * one, "wavelength_nm": w * one, "n_medium": nm * one})
    return result


# --------------------------------------------------------------------------------------
# public interface
# --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class MieResult:
    """Mie efficiencies (dimensionless, per geometric cross section π D²/4 of the outer sphere).

    Attributes
    ----------
    qext, qsca, qabs, qback, g : ndarray
        Extinction, scattering, absorption and backscattering efficiencies and the asymmetry
        parameter ⟨cos θ⟩, all of the broadcast shape of the inputs.
    size_parameter : ndarray
        x = π D n_medium / λ of the outer sphere.
    diameter_nm, wavelength_nm : ndarray
        The (broadcast) outer diameters and vacuum wavelengths.
    n_medium : ndarray
        The real host index (broadcast).
    angle_deg : ndarray or None
        Scattering angles of the amplitudes, if requested.
    s1, s2 : ndarray or None
        Complex amplitudes S1(θ), S2(θ) (Bohren & Huffman eq. 4.74), shape ``shape + (A,)``.
    """

    qext: np.ndarray
    qsca: np.ndarray
    qabs: np.ndarray
    qback: np.ndarray
    g: np.ndarray
    size_parameter: np.ndarray
    diameter_nm: np.ndarray
    wavelength_nm: np.ndarray
    n_medium: np.ndarray
    angle_deg: np.ndarray | None = None
    s1: np.ndarray | None = None
    s2: np.ndarray | None = None

    def _repr_html_(self) -> str:
        """Jupyter display: the input ranges and Q_ext, Q_sca, Q_abs, g against wavelength
        (or diameter, when only the diameter varies); other axes are shown at their first index."""
        from nmmm.html_repr import figure_png_base64, result_html

        w, d = np.broadcast_arrays(self.wavelength_nm, self.diameter_nm)
        curves = {"Q_ext": self.qext, "Q_sca": self.qsca, "Q_abs": self.qabs, "g": self.g}
        rows = [("shape", np.shape(self.qext)), ("wavelength", f"{np.min(w):g}–{np.max(w):g} nm"),
                ("diameter", f"{np.min(d):g}–{np.max(d):g} nm"),
                ("n_medium", f"{np.min(self.n_medium):g}–{np.max(self.n_medium):g}")]
        def varying(a):
            return next((i for i in range(a.ndim - 1, -1, -1) if np.ptp(a, axis=i).max() > 0), None)

        axis, x, xlabel = varying(w), w, "wavelength (nm)"
        if axis is None:
            axis, x, xlabel = varying(d), d, "diameter (nm)"
        if axis is None:  # one wavelength and diameter: the numbers only
            rows += [(k, f"{float(np.ravel(v)[0]):.6g}") for k, v in curves.items()]
            return result_html("MieResult", rows)

        rows += [(k, f"{np.min(v):.4g}–{np.max(v):.4g}") for k, v in curves.items()]

        def line(a):
            a = np.broadcast_to(a, w.shape)
            return np.moveaxis(a, axis, -1).reshape(-1, a.shape[axis])[0]

        png = figure_png_base64(line(x), {k: line(v) for k, v in curves.items()}, xlabel=xlabel,
                                ylabel="efficiency (1), g (1)", title="Mie efficiencies")
        return result_html("MieResult", rows, png)

    @property
    def geometric_cross_section_nm2(self) -> np.ndarray:
        """π D² / 4 (nm²)."""
        return np.pi * self.diameter_nm**2 / 4

    @property
    def cext_nm2(self) -> np.ndarray:
        """Extinction cross section (nm²)."""
        return self.qext * self.geometric_cross_section_nm2

    @property
    def csca_nm2(self) -> np.ndarray:
        """Scattering cross section (nm²)."""
        return self.qsca * self.geometric_cross_section_nm2

    @property
    def cabs_nm2(self) -> np.ndarray:
        """Absorption cross section (nm²)."""
        return self.qabs * self.geometric_cross_section_nm2

    @property
    def albedo(self) -> np.ndarray:
        """Single-scattering albedo Q_sca / Q_ext."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.qext > 0, self.qsca / self.qext, 0.0)

    def differential_cross_section_nm2(self) -> np.ndarray:
        """dC_sca/dΩ for unpolarized light, (|S1|² + |S2|²) / (2 k²) in nm²/sr (needs angles)."""
        if self.s1 is None:
            raise InvalidInputError("amplitudes were not computed; call mie(..., angles_deg=...)")
        k = 2 * np.pi * self.n_medium / self.wavelength_nm
        return (np.abs(self.s1) ** 2 + np.abs(self.s2) ** 2) / (2 * k[..., None] ** 2)


def _medium_index(n_medium, wavelength_nm):
    if hasattr(n_medium, "nk"):
        n_medium = n_medium.nk(wavelength_nm)
    nm = check_finite(n_medium, "n_medium")
    if np.iscomplexobj(nm):
        if np.any(nm.imag != 0):
            raise InvalidInputError(
                "n_medium is absorbing (k up to "
                f"{np.max(np.abs(nm.imag)):.3g}); Mie efficiencies are defined here only for a "
                "non-absorbing host: pass the real part of the host index and account for host "
                "absorption separately (e.g. nmmm.layers.paint adds the binder's 4πk/λ)"
            )
        nm = nm.real
    nm = nm.astype(float)
    if np.any(nm <= 0):
        raise InvalidInputError(f"n_medium must be > 0, got min {nm.min()!r}")
    return nm


def _particle_index(n_particle, wavelength_nm, name):
    nk = medium_nk(n_particle, wavelength_nm, name)
    if np.any(nk.real <= 0):
        raise InvalidInputError(f"{name} must have n > 0, got min n = {nk.real.min()!r}")
    return nk


def _angles(angles_deg):
    if angles_deg is None:
        return None
    a = check_finite(np.atleast_1d(np.asarray(angles_deg, dtype=float)), "angles_deg")
    if a.ndim != 1 or np.any((a < 0) | (a > 180)):
        raise InvalidInputError("angles_deg must be a 1-D array of scattering angles in [0, 180] degrees")
    return a


def _run(m_layers, x_layers, shape, angles_deg, diameter_nm, wavelength_nm, n_medium):
    """m_layers, x_layers: (B, L). Returns a MieResult of the given shape."""
    B = m_layers.shape[0]
    mu = np.cos(np.radians(angles_deg)) if angles_deg is not None else np.empty(0)
    A = mu.size
    out = np.empty((B, 4))
    s1 = np.empty((B, A), dtype=complex)
    s2 = np.empty((B, A), dtype=complex)
    parallel = numba.get_num_threads() > 1 and _work_terms(x_layers, A) >= PARALLEL_ABOVE_TERMS
    kernel = _mie_batch if parallel else _mie_batch_serial
    kernel(
        np.ascontiguousarray(m_layers, dtype=np.complex128),
        np.ascontiguousarray(x_layers, dtype=np.float64),
        np.ascontiguousarray(mu, dtype=np.float64),
        out,
        s1,
        s2,
        max(1, min(B, 8 * numba.get_num_threads())) if parallel else 1,
    )
    qext, qsca, qback, g = (out[:, i].reshape(shape) for i in range(4))
    return MieResult(
        qext=qext,
        qsca=qsca,
        qabs=qext - qsca,
        qback=qback,
        g=g,
        size_parameter=x_layers[:, -1].reshape(shape),
        diameter_nm=np.broadcast_to(diameter_nm, shape).copy(),
        wavelength_nm=np.broadcast_to(wavelength_nm, shape).copy(),
        n_medium=np.broadcast_to(n_medium, shape).copy(),
        angle_deg=angles_deg,
        s1=s1.reshape(shape + (A,)) if A else None,
        s2=s2.reshape(shape + (A,)) if A else None,
    )


def mie_multilayer(n_layers: ArrayLike, n_medium: ArrayLike, diameters_nm: ArrayLike, wavelength_nm: ArrayLike,
                   angles_deg: ArrayLike | None = None) -> MieResult:
    """Mie efficiencies of concentric multilayer spheres (Yang 2003).

    Parameters
    ----------
    n_layers : sequence of complex array_like or Material
        Complex indices n + ik (k ≥ 0) of the layers, **core first**; each broadcasts with the
        wavelengths and diameters. A :class:`~nmmm.materials.material.Material` is evaluated
        at ``wavelength_nm``.
    n_medium : float, array_like or Material
        Real index of the non-absorbing host.
    diameters_nm : sequence of array_like
        Outer diameters of the layers (nm), core first, strictly increasing.
    wavelength_nm : array_like
        Vacuum wavelengths (nm).
    angles_deg : array_like, optional
        Scattering angles (degrees) at which to return S1 and S2.

    Returns
    -------
    MieResult
        Efficiencies refer to the outer sphere's geometric cross section.

    References
    ----------
    W. Yang, Appl. Opt. 42, 1710 (2003); Bohren & Huffman (1983), §8.1 for the coated sphere.
    """
    if len(n_layers) != len(diameters_nm) or len(n_layers) < 1:
        raise InvalidInputError("give one index and one outer diameter per layer (core first)")
    names = [(f"n_layers[{i}]", f"diameters_nm[{i}]") for i in range(len(n_layers))]
    return _mie_layers(n_layers, n_medium, diameters_nm, wavelength_nm, angles_deg, names)


#: smallest size parameter of an inner layer (core or inner shell) accepted: its recursion underflows below ~1e-155
MIN_INNER_SIZE_PARAMETER = 1.0e-150
#: largest size parameter x = pi d n_medium / lambda accepted (the series needs ~x terms; x = 1e6 is a
#: 120 µm sphere in the visible, already a geometric-optics particle, which nmmm does not model)
MIE_MAX_SIZE_PARAMETER = 1.0e6
#: largest total number of series terms (sum over the grid of x + 4 x^(1/3) + 2) one call may spend (~20 s);
#: raise it (nmmm.layers.mie_scattering.MIE_MAX_TERMS = ...) for a long batch you mean to wait for
MIE_MAX_TERMS = 3.0e8
#: measured series terms per second of the kernel (200 x 1000 grid, x up to 40: 1.4e7 on this machine)
_TERMS_PER_S = 1.4e7


def _check_work(shape, w, nm, d_outer) -> None:
    """Refuse a size parameter beyond the series' domain, or a grid whose estimated work exceeds
    :data:`MIE_MAX_TERMS`, with the estimate (terms, time, memory) and the setting that raises it."""
    xmax = float(np.max(np.pi * np.asarray(d_outer) * np.max(nm) / np.min(w)))
    if xmax > MIE_MAX_SIZE_PARAMETER:
        raise InvalidInputError(
            f"size parameter x = pi d n / lambda reaches {xmax:.3g} (diameter up to {float(np.max(d_outer)):.4g} nm), "
            f"above {MIE_MAX_SIZE_PARAMETER:.0e}: the Mie series would need ~{xmax:.2g} terms per particle; a sphere "
            "that large is a geometric-optics scatterer (Q_ext -> 2), not a pigment for Mie theory: give the "
            "diameter in nm (1 µm = 1000 nm) or a smaller particle")
    npts = int(np.prod(shape)) if len(shape) else 1
    if npts < 100_000:
        return
    # the terms over the grid from a sample of x (exact enough for an estimate)
    x = np.broadcast_to(np.pi * np.asarray(d_outer) * nm / w, shape).ravel()
    sample = x[:: max(1, x.size // 100_000)]
    terms = float(np.mean(sample + 4 * np.cbrt(sample) + 2)) * npts
    if terms > MIE_MAX_TERMS:
        raise InvalidInputError(
            f"this Mie grid of {npts:,} particle-wavelength points needs ~{terms:.2g} series terms (~"
            f"{terms / _TERMS_PER_S / 60:.0f} min on one core, ~{npts * 120 / 1e9:.1f} GB of results), above the limit "
            f"MIE_MAX_TERMS = {MIE_MAX_TERMS:.0e}: use a coarser wavelength or diameter grid, or raise "
            "nmmm.layers.mie_scattering.MIE_MAX_TERMS if you mean to wait")


def _mie_layers(n_layers, n_medium, diameters_nm, wavelength_nm, angles_deg, names) -> MieResult:
    """Validate (naming each argument as the caller's signature does) and run the kernel."""
    w = as_wavelength_nm(wavelength_nm)
    idx = [_particle_index(n, w, nn) for n, (nn, _) in zip(n_layers, names)]
    ds = [check_positive(d, dn) for d, (_, dn) in zip(diameters_nm, names)]
    nm = _medium_index(n_medium, w)
    try:
        shape = np.broadcast_shapes(w.shape, nm.shape, *(i.shape for i in idx), *(d.shape for d in ds))
    except ValueError:
        told = [("wavelength_nm", w), ("n_medium", nm)] + [(nn, i) for i, (nn, _) in zip(idx, names)] + \
            [(dn, d) for d, (_, dn) in zip(ds, names)]
        raise InvalidInputError("shapes do not broadcast: " + ", ".join(f"{k} {v.shape}" for k, v in told) +
                                "; for a wavelength x diameter grid give wavelength_nm[:, None] (and n_particle[:, None])"
                                " and diameter_nm[None, :]") from None
    _check_work(shape, w, nm, ds[-1])
    L = len(idx)
    wb = np.broadcast_to(w, shape).ravel()
    nmb = np.broadcast_to(nm, shape).ravel()
    m = np.empty((wb.size, L), dtype=complex)
    x = np.empty((wb.size, L))
    for l in range(L):
        x[:, l] = np.pi * np.broadcast_to(ds[l], shape).ravel() * nmb / wb
    # the outer size parameter: the efficiencies divide by it; an inner layer's may be smaller (the tests
    # check cores at x = 3e-9), down to where its recursion underflows (a core below ~1e-155: a
    # ZeroDivisionError in the kernel), far below any real core
    floor = np.full(L, MIN_INNER_SIZE_PARAMETER)
    floor[-1] = MIN_SIZE_PARAMETER
    if x.size and not np.all(x >= floor):
        k, l = divmod(int(np.argmin(x >= floor)), L)
        raise InvalidInputError(
            f"size parameter x = pi d n_medium / lambda is {float(x[k, l]):.3g} (diameter "
            f"{float(np.broadcast_to(ds[l], shape).ravel()[k]):.3g} nm, n_medium {float(nmb[k]):.3g}, wavelength "
            f"{float(wb[k]):.4g} nm), below {floor[l]:.0e}: a {'particle' if l == L - 1 else 'core'} far smaller than an "
            "atom, where the series underflows; give the diameters and the wavelength in nm (1 µm = 1000 nm)")
    for l in range(L):
        # n * (1 / n_medium): exact component by component, as the one-sphere fast path forms it in Numba (a
        # complex division rounds differently in NumPy and in Numba, 1 ulp in 44 % of cases)
        m[:, l] = np.broadcast_to(idx[l], shape).ravel() * (1.0 / nmb)
    if L > 1 and np.any(np.diff(x, axis=1) <= 0):
        raise InvalidInputError("layer diameters must increase strictly from the core outwards")
    return _run(m, x, shape, _angles(angles_deg), ds[-1], w, nm)


def mie(n_particle: ArrayLike, n_medium: ArrayLike, diameter_nm: ArrayLike, wavelength_nm: ArrayLike,
        angles_deg: ArrayLike | None = None) -> MieResult:
    """Mie efficiencies of homogeneous spheres in a non-absorbing host.

    All array arguments broadcast together (NumPy rules); for a wavelength × diameter grid
    give ``wavelength_nm[:, None]`` (and ``n_particle[:, None]``) and ``diameter_nm[None, :]``.

    Parameters
    ----------
    n_particle : complex array_like or Material
        Particle index n + ik, k ≥ 0 (a Material is evaluated at ``wavelength_nm``).
    n_medium : float, array_like or Material
        Real, positive host index; an absorbing host raises :class:`InvalidInputError`.
    diameter_nm : array_like
        Sphere diameters (nm), > 0.
    wavelength_nm : array_like
        Vacuum wavelengths (nm).
    angles_deg : array_like, optional
        Scattering angles (degrees); S1 and S2 are then returned with a trailing angle axis.

    Returns
    -------
    MieResult

    Notes
    -----
    Bohren & Huffman (1983) ch. 4 with Wiscombe's (1980) downward recurrence and series
    length. Size parameters up to a few thousand are fine (the series is O(x) per particle).

    Examples
    --------
    Bohren & Huffman's BHMIE listing (appendix A, p. 482): m = 1.55, radius 0.525 µm,
    λ = 0.6328 µm in vacuum gives Q_ext = 3.10543, Q_back = 2.92534.

    >>> r = mie(1.55, 1.0, 1050.0, 632.8)
    >>> print(f"{float(r.qext):.5f} {float(r.qback):.5f}")
    3.10543 2.92534
    """
    if angles_deg is None and (one := _mie_scalar(n_particle, n_medium, diameter_nm, wavelength_nm)) is not None:
        return one
    return _mie_layers([n_particle], n_medium, [diameter_nm], wavelength_nm, angles_deg, [("n_particle", "diameter_nm")])


def mie_coated(n_core: ArrayLike, n_shell: ArrayLike, n_medium: ArrayLike, core_diameter_nm: ArrayLike,
               diameter_nm: ArrayLike, wavelength_nm: ArrayLike, angles_deg: ArrayLike | None = None) -> MieResult:
    """Mie efficiencies of core–shell spheres (Bohren & Huffman §8.1; Yang 2003).

    ``core_diameter_nm`` < ``diameter_nm`` (outer); efficiencies refer to the outer sphere.
    See :func:`mie_multilayer` for the parameters.
    """
    return _mie_layers(
        [n_core, n_shell],
        n_medium,
        [core_diameter_nm, diameter_nm],
        wavelength_nm,
        angles_deg,
        [("n_core", "core_diameter_nm"), ("n_shell", "diameter_nm")],
    )
