"""When the FFT homogenization means what it says: periodicity and the quasi-static limit.

- :func:`check_periodicity` — does the cell tile space without seams? (opposite faces are
  compared with neighbouring interior slices).
- :func:`periodize_mirror` — make any cell periodic by mirror images (doubles each axis).
- :func:`feature_size_nm` — mean size of the inclusions of each phase from the interface area:
  d = 2·dim·p / S_V (exact for spheres in 3-D, discs in 2-D), with S_V from the voxel faces
  corrected for the staircase (×2/3 in 3-D, ×π/4 in 2-D, Cauchy-Crofton).
- :func:`size_parameter` — x = π d n / λ, with n the real index of the matrix (majority phase).
- :func:`check_quasistatic` — warn (:class:`QuasiStaticWarning`) when x > 0.3.

The quasi-static problem div(ε ∇φ) = 0 describes the response only for features much smaller
than the wavelength in the medium. Above x ≈ 0.3 the result is still the *electrostatic*
effective permittivity of the microstructure — the long-wavelength limit, which ignores
retardation, magnetic dipoles and scattering losses. For 250 nm hematite grains in the
visible (x ≈ 2) it is not the permittivity that describes the layer's extinction: use a
size-corrected effective medium (Mie-based dynamic Maxwell Garnett / the layers package's
scattering model), and read the FFT result as the quasi-static term those corrections start
from (they coincide as x -> 0).

References
----------
- Bohren, C. F., Huffman, D. R. (1983). Absorption and Scattering of Light by Small Particles.
  Wiley, ch. 5 and 8 (size parameter x = 2π a n / λ, quasi-static limit).
- Santaló, L. A. (1976). Integral Geometry and Geometric Probability (Cauchy-Crofton
  formulas for surface estimation from intersections).
"""

from __future__ import annotations

import warnings

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.spectra import as_wavelength_nm

#: Size parameter above which the quasi-static result is flagged.
QUASISTATIC_LIMIT = 0.3


class QuasiStaticWarning(UserWarning):
    """The microstructure's features are not small against the wavelength in the medium."""


class PeriodicityWarning(UserWarning):
    """The cell's opposite faces do not match: the FFT solver would see seams."""


def _mismatch(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.mean(a != b))


def check_periodicity(labels, warn: bool = True, factor: float = 3.0, floor: float = 0.02) -> dict:
    """Compare the seam across each periodic boundary with the interior.

    For every axis, the fraction of differing voxels between the last and first slices is
    compared with the mean fraction between neighbouring interior slices. A seam ``factor``
    times worse than the mean, worse than every interior pair and above ``floor`` suggests the cell is not periodic: the FFT solver then
    computes the response of a cell with artificial interfaces at its boundaries.

    Returns ``{axis: (seam, interior)}``; warns with :class:`PeriodicityWarning` if ``warn``.
    """
    arr = np.asarray(labels)
    report = {}
    bad = []
    for ax in range(arr.ndim):
        n = arr.shape[ax]
        if n < 3:
            continue
        first = np.take(arr, 0, axis=ax)
        last = np.take(arr, n - 1, axis=ax)
        seam = _mismatch(first, last)
        axes = tuple(a for a in range(arr.ndim) if a != ax)
        pairs = np.mean(np.diff(arr, axis=ax) != 0, axis=axes)
        interior, worst = float(np.mean(pairs)), float(np.max(pairs))
        report[ax] = (seam, interior)
        if seam > max(factor * interior, worst, floor):
            bad.append(ax)
    if warn and bad:
        warnings.warn(
            f"the cell does not look periodic along axes {bad} (seam/interior mismatch "
            f"{[tuple(round(v, 3) for v in report[a]) for a in bad]}); the FFT solver assumes a "
            "periodic cell — generate a periodic microstructure or use periodize='mirror'",
            PeriodicityWarning,
            stacklevel=3,
        )
    return report


def periodize_mirror(labels) -> np.ndarray:
    """Return the cell mirrored along every axis (shape doubled per axis): periodic by construction."""
    arr = np.asarray(labels)
    for ax in range(arr.ndim):
        arr = np.concatenate([arr, np.flip(arr, axis=ax)], axis=ax)
    return arr


def interface_area_density(labels, voxel_nm: float = 1.0) -> dict:
    """Interface area per unit volume S_V (nm⁻¹; length per area in 2-D) of each label.

    Counted on the periodic grid from differing face neighbours and multiplied by the
    Cauchy-Crofton correction for an isotropic interface (2/3 in 3-D, π/4 in 2-D).
    """
    arr = np.asarray(labels)
    h = float(voxel_nm)
    corr = 2.0 / 3.0 if arr.ndim == 3 else np.pi / 4.0
    out = {}
    values = np.unique(arr)
    volume = arr.size * h**arr.ndim
    for v in values:
        m = arr == v
        faces = 0
        for ax in range(arr.ndim):
            faces += int(np.count_nonzero(m != np.roll(m, 1, axis=ax)))
        out[int(v)] = corr * faces * h ** (arr.ndim - 1) / volume
    return out


def feature_size_nm(labels, voxel_nm: float) -> dict:
    """Mean feature size d = 2·dim·p / S_V of each phase (nm): the diameter for spheres/discs."""
    arr = np.asarray(labels)
    sv = interface_area_density(arr, voxel_nm)
    out = {}
    for v, s in sv.items():
        p = float(np.mean(arr == v))
        out[v] = (2 * arr.ndim * p / s) if s > 0 else np.inf
    return out


def size_parameter(feature_nm, n_medium, wavelength_nm):
    """x = π d n / λ (Bohren & Huffman 1983), d the feature diameter, n the medium's real index."""
    w = as_wavelength_nm(wavelength_nm)
    return np.pi * np.asarray(feature_nm, float) * np.real(n_medium) / w


def check_quasistatic(labels, voxel_nm, wavelength_nm, eps_table, label_values, warn: bool = True,
                      limit: float = QUASISTATIC_LIMIT) -> dict:
    """Size parameter of every minority phase; warn with :class:`QuasiStaticWarning` above ``limit``.

    ``eps_table`` has shape (n_wavelengths, n_phases) in the order of ``label_values``; the
    matrix is the majority phase, n its real index. Returns ``{label: max x}``.
    """
    arr = np.asarray(labels)
    if voxel_nm is None:
        raise InvalidInputError("voxel_nm is needed to compute the size parameter")
    h = float(np.mean(np.atleast_1d(voxel_nm)))
    w = as_wavelength_nm(np.atleast_1d(wavelength_nm))
    sizes = feature_size_nm(arr, h)
    values = [int(v) for v in label_values]
    fr = [np.mean(arr == v) for v in values]
    host = int(np.argmax(fr))
    from nmmm.materials.material import eps_to_nk

    n_host = eps_to_nk(np.asarray(eps_table)[:, host]).real
    xs = {}
    for i, v in enumerate(values):
        if i == host:
            continue
        x = size_parameter(sizes[v], n_host, w)
        xs[v] = float(np.max(x))
    worst = {v: x for v, x in xs.items() if x > limit}
    if warn and worst:
        v, x = max(worst.items(), key=lambda kv: kv[1])
        warnings.warn(
            f"size parameter x = π d n / λ reaches {x:.2f} for phase {v} (feature size "
            f"{sizes[v]:.0f} nm) — above {limit}: the FFT gives the quasi-static (electrostatic) "
            "effective permittivity, which neglects retardation and scattering; for such grains use "
            "a size-corrected (Mie-based) effective medium or a scattering model for the layer, and "
            "read this result as its long-wavelength limit",
            QuasiStaticWarning,
            stacklevel=3,
        )
    return xs


__all__ = [
    "QUASISTATIC_LIMIT",
    "QuasiStaticWarning",
    "PeriodicityWarning",
    "check_periodicity",
    "periodize_mirror",
    "interface_area_density",
    "feature_size_nm",
    "size_parameter",
    "check_quasistatic",
]
