"""CIE tristimulus values of spectra, vectorised, built on colour-science.

- :func:`weighting_factors` — the (N, 3) weights W with XYZ = R @ W for a wavelength grid,
  an illuminant and an observer (the perfect white has Y = 100).
- :func:`spectra_to_xyz` — reflectance / transmittance spectra (last axis = wavelength) to
  CIE XYZ under an explicit illuminant.
- :func:`white_point` — XYZ of the perfect white under the same illuminant.
- :func:`as_spectral_distributions` — spectra on a grid as a colour-science
  ``SpectralDistribution`` (one) or ``MultiSpectralDistributions`` (a stack).

The illuminant and observer are always explicit (default D65 and the CIE 1931 2°
observer — colour-science's own default illuminant for ``sd_to_XYZ`` is E, a known trap).

Weighting. With a named or tabulated illuminant (a colour-science name or a
``colour.SpectralDistribution``) the weights are colour-science's ASTM E308 method
(:func:`colour.colorimetry.msds_to_XYZ_ASTME308` applied to the unit spectra of the grid, so
that XYZ = R @ W is exactly E308 for every R: Table 5/6 weights at 10 and 20 nm, the 1 nm
sum at 1 nm, the practice range 360–780 nm). E308 is defined for 1, 5, 10 and 20 nm
intervals; any other grid (2 nm, 40 nm, uneven) is interpolated linearly to 1 nm first.
The former path, the CIE tables interpolated onto the grid and summed with each sample weighted by its interval,
differs from E308 by up to 0.015 ΔE00 at 10 nm and 0.22 ΔE00 at 20 nm on the 24 ColorChecker
spectra (D65 and A, 380–780 nm; 0.12–0.22 ΔE00 at 400–700 nm / 20 nm): more than the
0.01 ΔE00 a faster path may differ by, so it is kept only where E308 cannot apply — an
illuminant given as values sampled on the grid (no 1 nm spectral power to weight with).

Inputs. Every entry point takes ``(wavelength_nm, values)`` arrays (last axis = wavelength) or
a colour-science ``SpectralDistribution`` / ``MultiSpectralDistributions`` alone
(``spectra_to_xyz(sd)``); :func:`as_spectral_distributions` returns nmmm spectra as them.

References
----------
- CIE 015:2018 Colorimetry, 4th ed. (white normalisation Y = 100).
- ASTM E308-22, Standard Practice for Computing the Colors of Objects by Using the CIE System.
- T. Mansencal et al., Colour 0.4.7, Zenodo, https://doi.org/10.5281/zenodo.3757045
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numba
import numpy as np
from numpy.typing import ArrayLike

from nmmm.colour.illuminants import canonical_illuminant, colour_matching_functions, illuminant_on_grid
from nmmm.errors import InvalidInputError, OutOfRangeError
from nmmm.spectra import as_wavelength_nm, check_finite


def _key(x):
    if isinstance(x, np.ndarray):
        return ("array", x.tobytes(), x.shape)
    return x if isinstance(x, str) else id(x)


@functools.lru_cache(maxsize=64)
def _weights_cached(w_bytes, w_shape, ill_key, obs_key, illuminant, observer):
    w = np.frombuffer(w_bytes, dtype=float).reshape(w_shape)
    cmfs = colour_matching_functions(observer)
    lo, hi = cmfs.wavelengths[0], cmfs.wavelengths[-1]
    if w.min() < lo - 1e-9 or w.max() > hi + 1e-9:
        raise OutOfRangeError(f"wavelengths {w.min():g}–{w.max():g} nm exceed the observer's range ({lo:g}–{hi:g} nm)")
    s = illuminant_on_grid(illuminant, w)
    import colour

    if isinstance(illuminant, (str, colour.SpectralDistribution)):
        W = _weights_astm_e308(w, illuminant, cmfs)
        W.setflags(write=False)
        return W
    cmf = np.stack([np.interp(w, cmfs.wavelengths, cmfs.values[:, i]) for i in range(3)], axis=-1)
    dw = np.gradient(w) if w.size > 1 else np.ones(1)
    W = s[:, None] * cmf * dw[:, None]
    norm = W[:, 1].sum()
    if norm <= 0:
        raise InvalidInputError("the illuminant has no power where the observer sees; cannot normalise Y")
    W = W * (100.0 / norm)
    W.setflags(write=False)
    return W


def _weights_astm_e308(w, illuminant, cmfs) -> np.ndarray:
    """ASTM E308 weights of the grid ``w``: colour-science's E308 XYZ of each unit spectrum."""
    import warnings

    import colour
    from colour.colorimetry import msds_to_XYZ_ASTME308

    if isinstance(illuminant, str):
        illuminant = colour.SDS_ILLUMINANTS[illuminant]
    steps = np.diff(w)
    if np.allclose(steps, steps[0], rtol=0, atol=1e-9) and round(float(steps[0]), 9) in (1.0, 5.0, 10.0, 20.0):
        grid, L = w, None
    else:  # E308 is defined at 1, 5, 10, 20 nm: other grids are interpolated (linearly) to 1 nm
        grid = np.arange(np.ceil(w[0] - 1e-9), np.floor(w[-1] + 1e-9) + 1.0)
        L = np.stack([np.interp(grid, w, e) for e in np.eye(w.size)], axis=1)  # (len(grid), N)
    unit = colour.MultiSpectralDistributions(np.eye(grid.size), grid, labels=[str(i) for i in range(grid.size)])
    with warnings.catch_warnings():  # colour-science's notes on aligning shapes, not ours to pass on
        warnings.simplefilter("ignore")
        W = np.array(msds_to_XYZ_ASTME308(unit, cmfs, illuminant), dtype=float)
    if L is not None:
        W = L.T @ W
    if W.shape != (w.size, 3) or not np.all(np.isfinite(W)) or W[:, 1].sum() <= 0:
        raise InvalidInputError("the illuminant has no power where the observer sees; cannot normalise Y")
    return W


def _split_spectral(wavelength_nm, values):
    """``(wavelength_nm, values)`` from arrays, or from a colour-science SpectralDistribution /
    MultiSpectralDistributions given alone (as ``wavelength_nm`` or as ``values``)."""
    import colour

    kinds = (colour.SpectralDistribution, colour.MultiSpectralDistributions)
    sd = wavelength_nm if isinstance(wavelength_nm, kinds) else values if isinstance(values, kinds) else None
    if sd is None:
        if values is None:
            raise InvalidInputError("give the spectra: spectra_to_xyz(wavelength_nm, values) with arrays, or a "
                                    "colour.SpectralDistribution / MultiSpectralDistributions alone")
        return wavelength_nm, values
    w_sd = np.asarray(sd.wavelengths, float)
    v = np.asarray(sd.values, float)
    v = v.T if isinstance(sd, colour.MultiSpectralDistributions) else v  # nmmm: last axis = wavelength
    if sd is values and wavelength_nm is not None:
        w = as_wavelength_nm(wavelength_nm)
        if w.shape != w_sd.shape or not np.allclose(w, w_sd):
            raise InvalidInputError(
                f"the distribution '{sd.name}' is sampled at {w_sd[0]:g}–{w_sd[-1]:g} nm ({w_sd.size} points), not on "
                "wavelength_nm: pass it alone (spectra_to_xyz(sd)) or align it first (sd.copy().align(...))")
    if sd is wavelength_nm and values is not None:
        raise InvalidInputError("a SpectralDistribution carries its own values: pass it alone, without values")
    return w_sd, v


def as_spectral_distributions(wavelength_nm: ArrayLike, values: ArrayLike, labels: Sequence[str] | None = None,
                              name: str = "nmmm") -> "colour.SpectralDistribution | colour.MultiSpectralDistributions":
    """Spectra (last axis = wavelength) as a colour-science ``SpectralDistribution`` (one
    spectrum) or ``MultiSpectralDistributions`` (a stack (M, N), labelled by ``labels``).

    >>> import numpy as np
    >>> sd = as_spectral_distributions(np.arange(380, 781, 10.0), np.full(41, 0.5))
    >>> type(sd).__name__, float(sd[550])
    ('SpectralDistribution', 0.5)
    """
    import colour

    w = as_wavelength_nm(wavelength_nm)
    v = check_finite(values, "spectra").astype(float, copy=False)
    if v.shape[-1] != w.size:
        raise InvalidInputError(f"spectra's last axis ({v.shape[-1]}) must match the wavelength grid ({w.size})")
    if v.ndim == 1:
        return colour.SpectralDistribution(v, w, name=name)
    v2 = v.reshape(-1, w.size)
    labels = [str(x) for x in labels] if labels is not None else [f"{name} {i}" for i in range(v2.shape[0])]
    if len(labels) != v2.shape[0]:
        raise InvalidInputError(f"{len(labels)} labels for {v2.shape[0]} spectra")
    return colour.MultiSpectralDistributions(v2.T, w, name=name, labels=labels)


#: least fraction of each colour-matching function's integral a grid must cover before
#: :func:`weighting_factors` warns that colours come from a truncated spectrum
#: (400–700 nm covers ≥ 99.5 % of x̄, ȳ, z̄; 420–680 nm only 95 % of z̄).
MIN_CMF_COVERAGE = 0.99


def _warn_if_truncated(w, observer):
    import warnings

    cmfs = colour_matching_functions(observer)
    inside = (cmfs.wavelengths >= w.min()) & (cmfs.wavelengths <= w.max())
    coverage = cmfs.values[inside].sum(axis=0) / cmfs.values.sum(axis=0)
    if np.any(coverage < MIN_CMF_COVERAGE):
        warnings.warn(
            f"the wavelength grid {w.min():g}–{w.max():g} nm covers only "
            f"{100 * coverage.min():.1f} % of a colour-matching function: colours are computed from a "
            "truncated spectrum (use at least 400–700 nm, ideally 380–780 nm)", UserWarning, stacklevel=3)


def weighting_factors(wavelength_nm: ArrayLike, illuminant: str = "D65", observer: str = "2") -> np.ndarray:
    """Weights W (N, 3) such that XYZ = values @ W, the perfect white giving Y = 100
    (ASTM E308 through colour-science for a named or tabulated illuminant; see the module notes).
    ``wavelength_nm`` may be a colour-science (Multi)SpectralDistribution: its wavelengths."""
    import colour

    if isinstance(wavelength_nm, (colour.SpectralDistribution, colour.MultiSpectralDistributions)):
        wavelength_nm = wavelength_nm.wavelengths
    w = as_wavelength_nm(wavelength_nm)
    if w.ndim != 1 or w.size < 2 or np.any(np.diff(w) <= 0):
        raise InvalidInputError("wavelength_nm must be a 1-D increasing grid of at least 2 points")
    _warn_if_truncated(w, observer)
    if isinstance(illuminant, np.ndarray) or not isinstance(illuminant, str):
        return _weights_cached.__wrapped__(w.tobytes(), w.shape, None, None, illuminant, observer)
    illuminant = canonical_illuminant(illuminant)  # F11, TL84, CWF ... (nmmm.colour.illuminants)
    return _weights_cached(w.tobytes(), w.shape, _key(illuminant), _key(observer), illuminant, observer)


#: spectra below -NEGATIVE_TOLERANCE are refused (a reflectance is >= 0; rounding may dip below 0)
NEGATIVE_TOLERANCE = 1e-6
_FUSED_MIN_SIZE = 1 << 18  # below ~0.25 M values the NumPy checks + BLAS product cost no more


#: LLVM may reorder the sums (SIMD lanes, FMA); the checks' comparisons keep their NaN semantics
#: (no 'nnan'/'ninf' flags: a NaN must still be counted)
_SUM_FASTMATH = {"reassoc", "contract"}


@numba.njit(cache=True, nogil=True, fastmath=_SUM_FASTMATH)
def _checked_pair_sums(v, i, k, Wt, tolerance):  # pragma: no cover - compiled
    """(X, Y, Z) of rows ``i`` and ``k`` of the spectra ``v`` (M, N) with the weights ``Wt`` (3, N),
    and the count of their values that are not finite or below ``-tolerance``, in one read.

    Vectorised over wavelength (reassociated sums: rounding like BLAS's); two rows per pass share
    the loads of the weights (15 % faster than one row at 1e5 x 401; ``k = i`` is allowed)."""
    x = 0.0
    y = 0.0
    z = 0.0
    x2 = 0.0
    y2 = 0.0
    z2 = 0.0
    bad = 0
    for j in range(v.shape[1]):
        r = v[i, j]
        s = v[k, j]
        bad += not ((r >= -tolerance) & (r < np.inf))  # NaN, ±inf and negatives
        bad += not ((s >= -tolerance) & (s < np.inf))
        wx = Wt[0, j]
        wy = Wt[1, j]
        wz = Wt[2, j]
        x += r * wx
        y += r * wy
        z += r * wz
        x2 += s * wx
        y2 += s * wy
        z2 += s * wz
    return x, y, z, x2, y2, z2, bad


@numba.njit(parallel=True, cache=True)
def _checked_weighted_sums(v, Wt, tolerance, out):  # pragma: no cover - compiled
    """``out = v @ Wt.T`` for (M, N) spectra and (3, N) weights, and in the same pass over the
    spectra the count of values that are not finite or below ``-tolerance`` (the input checks
    of :func:`spectra_to_xyz`): one read of the data instead of three (issue 22)."""
    bad = 0
    M = v.shape[0]
    for h in numba.prange((M + 1) // 2):
        i = 2 * h
        k = min(i + 1, M - 1)
        out[i, 0], out[i, 1], out[i, 2], out[k, 0], out[k, 1], out[k, 2], b = _checked_pair_sums(v, i, k, Wt, tolerance)
        bad += b
    return bad


@numba.njit(cache=True, nogil=True)
def _lab_f(t):  # pragma: no cover - compiled
    """CIE 1976 f(t) as colour-science writes it (``intermediate_lightness_function_CIE1976``)."""
    return t ** (1.0 / 3.0) if t > (24.0 / 116.0) ** 3 else (841.0 / 108.0) * t + 16.0 / 116.0


@numba.njit(cache=True, nogil=True)
def _lab_row(x, y, z, y_white, xyz_n, out, i):  # pragma: no cover - compiled
    """out[i] = CIELAB of (x, y, z) / ``y_white`` against the white ``xyz_n`` (Y_n = 1), CIE 015:2018
    as colour-science's ``XYZ_to_Lab`` computes it."""
    fx = _lab_f((x / y_white) / xyz_n[0])
    fy = _lab_f((y / y_white) / xyz_n[1])
    fz = _lab_f((z / y_white) / xyz_n[2])
    out[i, 0] = 116.0 * fy - 16.0
    out[i, 1] = 500.0 * (fx - fy)
    out[i, 2] = 200.0 * (fy - fz)


@numba.njit(parallel=True, cache=True)
def _checked_lab(v, Wt, tolerance, y_white, xyz_n, out):  # pragma: no cover - compiled
    """CIELAB of each row of ``v`` (:func:`_lab_row`) in the same pass as :func:`_checked_weighted_sums`;
    returns the count of refused values (then ``out`` is not to be used)."""
    bad = 0
    M = v.shape[0]
    for h in numba.prange((M + 1) // 2):
        i = 2 * h
        k = min(i + 1, M - 1)
        x, y, z, x2, y2, z2, b = _checked_pair_sums(v, i, k, Wt, tolerance)
        _lab_row(x, y, z, y_white, xyz_n, out, i)
        _lab_row(x2, y2, z2, y_white, xyz_n, out, k)
        bad += b
    return bad


def _fused_applies(values, n_wavelengths: int) -> bool:
    """Large C-contiguous float64 stacks on a grid of ``n_wavelengths`` go through the fused kernels."""
    return (isinstance(values, np.ndarray) and values.dtype == np.float64 and values.ndim >= 2
            and values.size >= _FUSED_MIN_SIZE and values.shape[-1] == n_wavelengths and values.flags.c_contiguous)


def _fused_xyz_or_lab(values, W, lab: bool = False):
    """XYZ (or CIELAB, white W.sum(0)) of ``values`` through the fused check-and-sum kernels, or
    None when they do not apply or found a NaN, an infinity or a negative value (the NumPy checks
    of :func:`spectra_to_xyz` then name it)."""
    if not _fused_applies(values, W.shape[0]):
        return None
    flat = values.reshape(-1, W.shape[0])
    out = np.empty((flat.shape[0], 3))
    Wt = np.ascontiguousarray(W.T)
    if lab:
        white = W.sum(axis=0)
        bad = _checked_lab(flat, Wt, NEGATIVE_TOLERANCE, float(white[1]), _lab_white(white), out)
    else:
        bad = _checked_weighted_sums(flat, Wt, NEGATIVE_TOLERANCE, out)
    return out.reshape(values.shape[:-1] + (3,)) if bad == 0 else None


def _lab_white(white) -> np.ndarray:
    """The white (X_n, 1, Z_n) as colour-science's ``XYZ_to_Lab`` rebuilds it from the white's xy."""
    import colour

    return np.asarray(colour.xy_to_XYZ(colour.XYZ_to_xy(white / white[1])), dtype=float)


def spectra_to_xyz(wavelength_nm: ArrayLike, values: ArrayLike | None = None, illuminant: str = "D65",
                   observer: str = "2") -> np.ndarray:
    """CIE XYZ (last axis X, Y, Z; white Y = 100) of spectra ``values`` (..., N), or of a
    colour-science SpectralDistribution / MultiSpectralDistributions given alone.

    >>> import numpy as np
    >>> w = np.arange(380, 781, 5.0)
    >>> np.round(spectra_to_xyz(w, np.ones_like(w)), 2)  # ASTM E308 at 5 nm (1 nm sums: 95.047, 108.883)
    array([  95.05,  100.  ,  108.9 ])
    >>> import colour
    >>> sd = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]["dark skin"]
    >>> np.round(spectra_to_xyz(sd), 2)  # alone, on its own 5 nm grid; = colour.sd_to_XYZ(..., method="ASTM E308")
    array([ 10.97,   9.7 ,   6.06])
    """
    wavelength_nm, values = _split_spectral(wavelength_nm, values)
    W = weighting_factors(wavelength_nm, illuminant, observer)
    xyz = _fused_xyz_or_lab(values, W)
    if xyz is not None:
        return xyz
    # small, other dtypes, or a NaN, an infinity or a negative value: the checks below name it
    v = check_finite(values, "spectra").astype(float, copy=False)
    if v.shape[-1] != W.shape[0]:
        raise InvalidInputError(f"spectra's last axis ({v.shape[-1]}) must match the wavelength grid ({W.shape[0]})")
    if v.size and v.min() < -NEGATIVE_TOLERANCE:
        i = int(np.argmin(v.ravel()))
        raise InvalidInputError(
            f"spectra hold {v.ravel()[i]:.4g} at flat index {i} (wavelength {wavelength_nm[i % v.shape[-1]]:g} nm): a "
            "reflectance, transmittance or reflectance factor is >= 0; check the data (or the sign of the model)")
    return v @ W


def white_point(wavelength_nm: ArrayLike, illuminant: str = "D65", observer: str = "2") -> np.ndarray:
    """XYZ of the perfect white under the illuminant (Y = 100)."""
    return weighting_factors(wavelength_nm, illuminant, observer).sum(axis=0)
