"""Image analysis of SEM-like sections and parameter estimation of the random models.

All lengths are in nm: pass the pixel size ``pixel_nm`` (scalar or per axis). Binary
images are boolean arrays, True = particles. Functions work on 2-D images; the
covariance, integral range and granulometry also accept 3-D arrays.

- :func:`read_image` — read a grey-level image (PNG, TIFF, JPEG…) as floats in [0, 1].
- :func:`binarize` — Otsu (1979) or manual threshold, optional smoothing and cleaning.
- :func:`area_fraction` — fraction of particle pixels (= volume fraction by Delesse's
  principle for isotropic, stationary media).
- :func:`covariance` — two-point covariance C(h) = P(x ∈ A, x + h ∈ A), by FFT (periodic or
  with the exact overlap correction of a finite window).
- :func:`covariance_profile` — C as a function of |h| (nm), radially averaged.
- :func:`integral_range` — A = ∫ (C(h) − p²) dh / (p(1 − p)) over the lags |h_i| ≤ L_i / 4,
  i.e. over a centred box of half the cell: a periodic covariance summed over the
  whole cell gives exactly zero (Σ_h C(h) = N p²).
- :func:`granulometry` — area fraction remaining after openings by discs of growing
  radius (Matheron 1975), by exact Euclidean distance transforms; its derivative is the
  granulometric size distribution.
- :func:`label_particles` — connected components (periodic wrap optional); defined in
  :mod:`nmmm.microstructure.labelling` (shared with the model estimators) and re-exported here.
- :func:`particle_statistics` — centroids, areas, equivalent diameters in nm.
- :func:`nearest_neighbour_distances` — centre-to-centre nearest-neighbour distances.
- :func:`exclusion_radius` — half the hard-core distance (minimum centre distance).
- :func:`estimate_boolean` — fit of the Boolean model (discs, or sections of spheres) to the
  measured covariance: radius and intensity.
- :func:`estimate_hardcore` — fraction, particle radius, exclusion radius, number density.
- :func:`analyze_image` — all of the above → :class:`ImageAnalysis` (``.summary()``, ``.plot()``).

References
----------
- Otsu, N. (1979). A threshold selection method from gray-level histograms. IEEE Trans.
  Syst. Man Cybern. 9(1), 62–66. https://doi.org/10.1109/TSMC.1979.4310076
- Matheron, G. (1975). Random Sets and Integral Geometry. Wiley (covariance,
  granulometries, Boolean model).
- Serra, J. (1982). Image Analysis and Mathematical Morphology. Academic Press.
- Lantuéjoul, C. (1991). Ergodicity and integral range. J. Microsc. 161, 387–403.
- Couka, E., Willot, F., Jeulin, D., et al. (2015). J. Nanosci. Nanotechnol. 15(5), 3515
  (exclusion zones and hard-core models from SEM images of hematite coatings).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy import ndimage, optimize
from scipy.spatial import cKDTree

from nmmm.errors import DataFileError, InvalidInputError
from nmmm.microstructure.base import Microstructure, as_voxel_nm
from nmmm.microstructure.boolean import covariogram_ratio
from nmmm.microstructure.estimation import estimate_aggregates, estimate_flakes
from nmmm.microstructure.labelling import _as_binary, _as_image, label_particles
from nmmm.spectra import check_finite

__all__ = [
    "read_image",
    "binarize",
    "area_fraction",
    "covariance",
    "covariance_profile",
    "integral_range",
    "granulometry",
    "label_particles",
    "particle_statistics",
    "ParticleStatistics",
    "nearest_neighbour_distances",
    "exclusion_radius",
    "estimate_boolean",
    "estimate_hardcore",
    "analyze_image",
    "ImageAnalysis",
]


def read_image(path) -> np.ndarray:
    """Read a grey-level (or colour, averaged) 2-D image as floats in [0, 1].

    Raises :class:`DataFileError` for a missing or unreadable file.
    """
    p = Path(path)
    if not p.is_file():
        raise DataFileError(f"image file not found: {p}")
    try:
        if p.suffix.lower() in (".tif", ".tiff"):
            import tifffile

            a = tifffile.imread(p)
        else:
            from PIL import Image

            with Image.open(p) as im:
                a = np.asarray(im)
    except Exception as exc:  # PIL/tifffile raise many kinds
        raise DataFileError(f"cannot read image {p}: {exc}; give a PNG, TIFF or JPEG file") from None
    a = np.asarray(a)
    if a.ndim == 3 and a.shape[-1] in (3, 4):
        a = a[..., :3].mean(axis=-1) if a.dtype.kind == "f" else a[..., :3].astype(float).mean(axis=-1)
    if a.ndim != 2:
        raise DataFileError(f"{p}: expected a 2-D grey-level image, got an array of shape {a.shape}")
    if a.dtype == bool:
        return a.astype(float)
    a = a.astype(float)
    if not np.all(np.isfinite(a)):
        raise DataFileError(f"{p}: image contains NaN or infinite values")
    lo, hi = a.min(), a.max()
    if hi == lo:
        raise DataFileError(f"{p}: the image is uniform (all pixels = {lo}); nothing to analyse")
    return (a - lo) / (hi - lo)


def binarize(image, threshold="otsu", invert: bool = False, smooth_px: float = 0.0, min_size_px: int = 0):
    """Binary image of the particles: pixels brighter than the threshold (darker if ``invert``).

    Parameters
    ----------
    image : 2-D array
        Grey levels (any scale).
    threshold : "otsu" or float
        Otsu's (1979) between-class variance maximiser, or a manual threshold in the
        image's grey-level units.
    smooth_px : float
        Gaussian smoothing (pixels) before thresholding, against noise.
    min_size_px : int
        Remove connected components smaller than this (noise specks).
    """
    a = _as_image(image).astype(float)
    if smooth_px > 0:
        a = ndimage.gaussian_filter(a, smooth_px, mode="wrap")
    if isinstance(threshold, str):
        if threshold.lower() != "otsu":
            raise InvalidInputError(f"threshold must be 'otsu' or a number, got {threshold!r}")
        from skimage.filters import threshold_otsu

        if np.ptp(a) == 0:
            raise InvalidInputError("the image is uniform: no threshold separates particles from matrix")
        t = float(threshold_otsu(a))
    else:
        t = float(check_finite(threshold, "threshold"))
    b = a < t if invert else a > t
    if min_size_px > 1:
        lab, n = ndimage.label(b)
        small = np.bincount(lab.ravel()) < int(min_size_px)
        small[0] = False
        b = b & ~small[lab]
    return b


def area_fraction(binary) -> float:
    """Fraction of particle pixels (A_A = V_V, Delesse 1847)."""
    return float(np.mean(_as_binary(binary)))


def covariance(binary, periodic: bool = True) -> np.ndarray:
    """Two-point covariance C(h) for every lag h, with h = 0 at the array centre (fftshift).

    ``periodic=True`` treats the image as a periodic cell (circular correlation);
    otherwise C(h) is the exact estimator of a finite window: Σ I(x)I(x+h) over the
    N(h) pairs inside the window, divided by N(h).
    """
    b = _as_binary(binary).astype(float)
    if periodic:
        f = np.fft.rfftn(b)
        c = np.fft.irfftn(f * np.conj(f), s=b.shape) / b.size
        return np.fft.fftshift(c)
    s = [2 * n for n in b.shape]
    f = np.fft.rfftn(b, s)
    num = np.fft.irfftn(f * np.conj(f), s)
    g = np.fft.rfftn(np.ones_like(b), s)
    den = np.fft.irfftn(g * np.conj(g), s)
    c = num / np.maximum(np.round(den), 1)
    c = np.fft.fftshift(c)
    # keep lags |h| < n (the centred (2n-1)-wide block)
    sl = tuple(slice(1, 2 * n) for n in b.shape)
    return c[sl]


def _lag_grid(shape, voxel):
    """|h| (nm) and per-axis lags for a centred (fftshifted) lag array."""
    axes = [(np.arange(n) - n // 2) * v for n, v in zip(shape, voxel)]
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.sqrt(sum(m * m for m in mesh)), mesh


def covariance_profile(binary, pixel_nm=1.0, periodic: bool = True, max_lag_nm: float | None = None):
    """Radially averaged covariance: (h_nm, C(h)) with C(0) = p.

    Lags are binned by the smallest pixel size; ``max_lag_nm`` defaults to a quarter of the
    smallest cell edge.
    """
    b = _as_binary(binary)
    v = as_voxel_nm(pixel_nm, b.ndim)
    c = covariance(b, periodic)
    r, _ = _lag_grid(c.shape, v)
    step = min(v)
    if max_lag_nm is None:
        max_lag_nm = min(n * x for n, x in zip(b.shape, v)) / 4
    idx = np.rint(r / step).astype(np.int64)
    nb = int(max_lag_nm / step) + 1
    m = idx < nb
    sums = np.bincount(idx[m], c[m], minlength=nb)
    cnt = np.bincount(idx[m], minlength=nb)
    ok = cnt > 0
    return np.arange(nb)[ok] * step, sums[ok] / cnt[ok]


def integral_range(binary, pixel_nm=1.0, periodic: bool = True, extent: float | None = None) -> float:
    """Integral range A = ∫ (C(h) − p²) dh / (p(1 − p)) (nm^d).

    The integral runs over the centred box of lags |h_i| ≤ extent · L_i / 2, at most half
    the cell per axis (extent = 0.5, |h_i| ≤ L_i / 4): for a periodic cell the sum over all
    lags vanishes identically, so the whole cell must not be used. By default (``extent=None``)
    the box is cut to 4 correlation lengths (the first lag where C(h) − p² falls below 2 %
    of p(1 − p)) when that is smaller than half the cell: beyond, C(h) = p² and summing
    noise only adds variance (std ≈ 120 % instead of 13 % for Boolean discs of radius
    5 px in 512² cells). The variance of the
    fraction over a domain V ≫ A is p(1 − p) A / V (Lantuéjoul 1991).

    Bias correction: with the sample fraction p̂ in place of p, E[Ĉ(h) − p̂²] ≈
    C(h) − p² − Var(p̂) and Var(p̂) ≈ p(1 − p) A / |V|, so the sum over the box B of lags
    estimates A (1 − |B|/|V|); the result is divided by that factor (0.75 in 2-D and
    0.875 in 3-D for the default box). The periodic identity (sum over the whole cell = 0)
    is the case |B| = |V|. For a non-periodic window the covariance at lag h is centred
    by the means over the N(h) overlapping pairs and the factor is 1 − Σ_{h∈B} 1/N(h).
    """
    b = _as_binary(binary)
    if extent is not None and not 0 < extent <= 0.5:
        raise InvalidInputError(
            f"extent must lie in (0, 0.5] (fraction of the cell edge spanned by the lags |h_i| <= extent L_i / 2); "
            f"got {extent}; over the whole periodic cell the integral is exactly zero"
        )
    v = as_voxel_nm(pixel_nm, b.ndim)
    p = float(b.mean())
    if not 0 < p < 1:
        raise InvalidInputError(f"integral range needs both phases present, got fraction {p}")
    if periodic:
        k = covariance(b, True) - p * p
        npairs = np.full(k.shape, float(b.size))
    else:
        k, npairs = _centred_covariance_window(b)
    r, mesh = _lag_grid(k.shape, v)
    half = [0.25 * n * x for n, x in zip(b.shape, v)]
    if extent is None:
        step = min(v)
        idx = np.rint(r / step).astype(np.int64)
        prof = np.bincount(idx.ravel(), k.ravel()) / np.maximum(np.bincount(idx.ravel()), 1)
        below = np.flatnonzero(prof <= 0.02 * p * (1 - p))
        if below.size:
            half = [min(hh, 4 * below[0] * step) for hh in half]
    else:
        half = [extent * n * x / 2 for n, x in zip(b.shape, v)]
    mask = np.ones(k.shape, bool)
    for m, hh in zip(mesh, half):
        mask &= np.abs(m) <= hh + 1e-9
    raw = float(k[mask].sum() * np.prod(v) / (p * (1 - p)))
    return raw / (1.0 - float(np.sum(1.0 / npairs[mask])))


def _centred_covariance_window(b):
    """Centred covariance of a finite window: for each lag, the mean of I(x)I(x+h) over the
    N(h) pairs inside the window minus the product of the two local means."""
    x = b.astype(float)
    s = [2 * n for n in x.shape]
    fi = np.fft.rfftn(x, s)
    fw = np.fft.rfftn(np.ones_like(x), s)

    def corr(f, g):
        return np.fft.irfftn(f * np.conj(g), s)

    n = np.maximum(np.round(corr(fw, fw)), 1)
    c2 = corr(fi, fi) / n
    m1 = corr(fi, fw) / n
    m2 = corr(fw, fi) / n
    sl = tuple(slice(1, 2 * m) for m in x.shape)
    return np.fft.fftshift(c2 - m1 * m2)[sl], np.fft.fftshift(n)[sl]


def _edt(b, v, periodic):
    if not periodic:
        return ndimage.distance_transform_edt(b, sampling=v)
    pad = [(n // 2, n // 2) for n in b.shape]
    big = np.pad(b, pad, mode="wrap")
    d = ndimage.distance_transform_edt(big, sampling=v)
    return d[tuple(slice(p0, p0 + n) for (p0, _), n in zip(pad, b.shape))]


def granulometry(binary, radii_nm, pixel_nm=1.0, periodic: bool = True) -> dict:
    """Granulometry by openings with discs (balls in 3-D) of radius r (Matheron 1975).

    Returns ``{"radius_nm", "fraction"}`` (area fraction after each opening) and
    ``"distribution"``: G(r) = 1 − fraction(r)/fraction(0), the fraction of the particle
    phase in grains smaller than r. Openings are exact Euclidean: the erosion is
    {EDT(A) > r}, the dilation of a set E by r is {EDT(not E) ≤ r}.
    """
    b = _as_binary(binary)
    v = as_voxel_nm(pixel_nm, b.ndim)
    radii = np.atleast_1d(check_finite(radii_nm, "radii_nm")).astype(float)
    if np.any(radii < 0):
        raise InvalidInputError("radii_nm must be >= 0")
    d_in = _edt(b, v, periodic)
    p0 = float(b.mean())
    frac = np.empty(radii.size)
    for k, r in enumerate(radii):
        if r == 0:
            frac[k] = p0
            continue
        ero = d_in > r
        if not ero.any():
            frac[k] = 0.0
            continue
        d_out = _edt(~ero, v, periodic)
        frac[k] = float(np.mean(d_out <= r))
    dist = 1 - frac / p0 if p0 > 0 else np.zeros_like(frac)
    return {"radius_nm": radii, "fraction": frac, "distribution": dist}


@dataclass(frozen=True)
class ParticleStatistics:
    """Per-particle measurements (nm, nm²) from a binary image."""

    centroids_nm: np.ndarray
    areas_nm2: np.ndarray
    equivalent_diameters_nm: np.ndarray
    on_border: np.ndarray
    labels: np.ndarray = field(repr=False)
    box_nm: tuple = ()

    @property
    def count(self) -> int:
        return int(self.areas_nm2.size)


def particle_statistics(binary, pixel_nm=1.0, periodic: bool = False, min_area_px: int = 1) -> ParticleStatistics:
    """Centroids, areas and equivalent-disc diameters of the connected particles.

    For a non-periodic image, particles cut by the frame are flagged ``on_border`` (exclude
    them from size distributions: minus-sampling edge correction). For a periodic image,
    particles wrapping across edges are merged and their centroids computed on the torus.
    """
    b = _as_binary(binary)
    if b.ndim != 2:
        raise InvalidInputError("particle_statistics works on 2-D sections")
    v = np.array(as_voxel_nm(pixel_nm, 2))
    lab, n = label_particles(b, periodic)
    counts = np.bincount(lab.ravel(), minlength=n + 1)
    if min_area_px > 1 and n:
        small = counts < min_area_px
        small[0] = False
        if small.any():
            lab = np.where(small[lab], 0, lab)
            lab, n = label_particles(lab > 0, periodic)
            counts = np.bincount(lab.ravel(), minlength=n + 1)
    shape = np.array(b.shape)
    L = shape * v
    if n == 0:
        e = np.zeros(0)
        return ParticleStatistics(np.zeros((0, 2)), e, e, np.zeros(0, bool), lab, tuple(L))
    idx = np.nonzero(lab)
    ids = lab[idx]
    coords = np.stack(idx, axis=1).astype(float) + 0.5
    if periodic:
        _, first = np.unique(ids, return_index=True)
        ref = np.zeros((n + 1, 2))
        ref[ids[first]] = coords[first]
        delta = coords - ref[ids]
        delta -= shape * np.round(delta / shape)
        cen = np.stack([np.bincount(ids, delta[:, k], minlength=n + 1) for k in range(2)], axis=1)
        cen = ref + cen / np.maximum(counts, 1)[:, None]
        cen = np.mod(cen, shape)
        border = np.zeros(n + 1, bool)
    else:
        cen = np.stack([np.bincount(ids, coords[:, k], minlength=n + 1) for k in range(2)], axis=1)
        cen /= np.maximum(counts, 1)[:, None]
        border = np.zeros(n + 1, bool)
        for ax in range(2):
            for sl in (0, -1):
                border[np.unique(np.take(lab, sl, axis=ax))] = True
    areas = counts[1:] * float(np.prod(v))
    return ParticleStatistics(cen[1:] * v, areas, np.sqrt(4 * areas / np.pi), border[1:], lab, tuple(L))


def nearest_neighbour_distances(centroids_nm, box_nm=None) -> np.ndarray:
    """Centre-to-centre nearest-neighbour distance of each point (nm); periodic if ``box_nm``."""
    c = np.asarray(check_finite(centroids_nm, "centroids_nm"), float)
    if c.ndim != 2 or c.shape[0] < 2:
        raise InvalidInputError("need at least two particle centres for nearest-neighbour distances")
    if box_nm is not None:
        box = np.asarray(box_nm, float)
        tree = cKDTree(np.mod(c, box), boxsize=box)
    else:
        tree = cKDTree(c)
    d, _ = tree.query(c if box_nm is None else np.mod(c, box), k=2)
    return d[:, 1]


def exclusion_radius(nn_distances_nm, quantile: float = 0.0) -> float:
    """Radius of the exclusion zones: half the hard-core distance.

    The hard-core distance is estimated by the minimum nearest-neighbour centre distance
    (the maximum-likelihood estimator for a hard-core process), or by a low ``quantile``
    to be robust to segmentation errors (two touching particles merged or split).
    """
    d = np.asarray(nn_distances_nm, float)
    if d.size == 0:
        raise InvalidInputError("no nearest-neighbour distances given")
    return 0.5 * float(np.quantile(d, quantile) if quantile > 0 else d.min())


def estimate_boolean(binary, pixel_nm=1.0, grain: str = "disc", periodic: bool = True,
                     max_lag_nm: float | None = None) -> dict:
    """Fit a Boolean model of equal discs (2-D) or spheres (seen in a planar section) to an image.

    The fraction p is the area fraction; the radius R minimises the squared misfit of the
    radially averaged covariance with C(h) = 1 − 2q + q^(2 − r(h; R)) (Matheron 1975);
    the intensity follows from θ = −ln(1 − p)/E[V] (per nm² for discs, per nm³ for spheres,
    whose covariogram along a section is the 3-D one). ``grain="sphere"`` recovers the
    3-D model from a 2-D section.
    """
    b = _as_binary(binary)
    v = as_voxel_nm(pixel_nm, b.ndim)
    p = float(b.mean())
    if not 0 < p < 1:
        raise InvalidInputError(f"the image must contain both phases (fraction {p})")
    if grain not in ("disc", "sphere"):
        raise InvalidInputError(f"grain must be 'disc' or 'sphere', got {grain!r}")
    h, c = covariance_profile(b, v, periodic, max_lag_nm)
    q = 1 - p

    def model(R):
        return 1 - 2 * q + q ** (2 - covariogram_ratio(h, R, grain))

    def cost(R):
        return float(np.sum((model(R) - c) ** 2))

    lo, hi = min(v) / 2, h.max() / 2
    grid = np.geomspace(lo, hi, 60)
    k = int(np.argmin([cost(R) for R in grid]))
    res = optimize.minimize_scalar(cost, bounds=(grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]),
                                   method="bounded", options={"xatol": 1e-4 * min(v)})
    R = float(res.x)
    ev = math.pi * R * R if grain == "disc" else 4 / 3 * math.pi * R**3
    theta = -math.log(q) / ev
    return {
        "model": "boolean_" + grain + "s",
        "fraction": p,
        "radius_nm": R,
        "intensity": theta,
        "intensity_unit": "per nm^2" if grain == "disc" else "per nm^3",
        "rms_residual": math.sqrt(res.fun / h.size),
        "lag_nm": h,
        "covariance": c,
        "covariance_fit": model(R),
    }


def _nn_with_partner(st: ParticleStatistics, periodic: bool):
    """NN distances and a mask of the particles whose centroid and neighbour's centroid are
    both unbiased (neither cut by the frame of a non-periodic image)."""
    c = st.centroids_nm
    if periodic:
        box = np.asarray(st.box_nm, float)
        d, j = cKDTree(np.mod(c, box), boxsize=box).query(np.mod(c, box), k=2)
        return d[:, 1], np.ones(c.shape[0], bool)
    d, j = cKDTree(c).query(c, k=2)
    inner = ~st.on_border
    return d[:, 1], inner & inner[j[:, 1]]


def estimate_hardcore(binary, pixel_nm=1.0, periodic: bool = False, min_area_px: int = 4,
                      quantile: float = 0.0) -> dict:
    """Estimate a hard-core model of discs from an image.

    Returns the area fraction, the particle radius sqrt(mean area / π) (particles on the
    frame excluded), the exclusion radius (half the hard-core distance, see
    :func:`exclusion_radius`) and the number density (per nm²).
    """
    b = _as_binary(binary)
    st = particle_statistics(b, pixel_nm, periodic, min_area_px)
    if st.count < 2:
        raise InvalidInputError(f"found {st.count} particle(s): too few to estimate a hard-core model")
    inner = ~st.on_border
    if inner.sum() == 0:
        inner = np.ones(st.count, bool)
    nn, pair_inner = _nn_with_partner(st, periodic)
    area = float(np.prod(st.box_nm))
    return {
        "model": "hardcore_discs",
        "fraction": float(b.mean()),
        "n_particles": st.count,
        "number_density_per_nm2": st.count / area,
        "radius_nm": float(np.sqrt(st.areas_nm2[inner].mean() / np.pi)),
        "exclusion_radius_nm": exclusion_radius(nn[pair_inner] if pair_inner.any() else nn, quantile),
        "nn_distances_nm": nn,
        "statistics": st,
    }


@dataclass(frozen=True, eq=False)
class ImageAnalysis:
    """Result of :func:`analyze_image`; ``summary()`` gives the scalars, ``plot()`` the figure."""

    image: np.ndarray = field(repr=False)
    binary: np.ndarray = field(repr=False)
    pixel_nm: tuple
    threshold: object
    fraction: float
    particles: ParticleStatistics = field(repr=False)
    nn_distances_nm: np.ndarray = field(repr=False)
    exclusion_radius_nm: float
    boolean: dict = field(repr=False)
    hardcore: dict | None = field(repr=False)
    integral_range_nm2: float
    granulometry: dict = field(repr=False)
    model_estimate: dict | None = field(default=None, repr=False)

    def summary(self) -> dict:
        d = self.particles.equivalent_diameters_nm[~self.particles.on_border]
        out = {
            "pixel_nm": list(self.pixel_nm),
            "threshold": self.threshold,
            "area_fraction": self.fraction,
            "n_particles": self.particles.count,
            "number_density_per_um2": self.particles.count / float(np.prod(self.particles.box_nm)) * 1e6,
            "mean_equivalent_diameter_nm": float(d.mean()) if d.size else float("nan"),
            "std_equivalent_diameter_nm": float(d.std()) if d.size else float("nan"),
            "mean_nn_distance_nm": float(self.nn_distances_nm.mean()) if self.nn_distances_nm.size else float("nan"),
            "exclusion_radius_nm": self.exclusion_radius_nm,
            "integral_range_nm2": self.integral_range_nm2,
            "boolean_radius_nm": self.boolean["radius_nm"],
            "boolean_intensity_per_nm2": self.boolean["intensity"],
        }
        if self.hardcore is not None:
            out["hardcore_radius_nm"] = self.hardcore["radius_nm"]
        if self.model_estimate is not None:
            name = self.model_estimate["model"]
            for k, val in self.model_estimate.items():
                if isinstance(val, (int, float, np.floating, np.integer)) and not isinstance(val, bool):
                    out[f"{name}.{k}"] = float(val) if isinstance(val, (float, np.floating)) else int(val)
        return out

    def plot(self, path=None, title: str | None = None):
        """Figure as in the seed's Fig. 8: the image with detected particles and their exclusion
        zones, the covariance with the Boolean fit, nearest-neighbour and size histograms."""
        import matplotlib

        matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt
        from matplotlib.patches import Circle

        fig, ax = plt.subplots(2, 2, figsize=(10, 9))
        v = self.pixel_nm
        ext = [0, self.image.shape[1] * v[1] / 1e3, self.image.shape[0] * v[0] / 1e3, 0]
        a = ax[0, 0]
        a.imshow(self.image, cmap="gray", extent=ext)
        a.contour(np.linspace(ext[0], ext[1], self.binary.shape[1]), np.linspace(ext[3], ext[2], self.binary.shape[0]),
                  self.binary.astype(float), levels=[0.5], colors="tab:orange", linewidths=0.6)
        cen = self.particles.centroids_nm / 1e3
        a.plot(cen[:, 1], cen[:, 0], "+", color="tab:red", ms=4)
        rex = self.exclusion_radius_nm / 1e3
        for y, x in cen:
            a.add_patch(Circle((x, y), rex, fill=False, ec="tab:cyan", lw=0.6))
        a.set_title(f"particles ({self.particles.count}) and exclusion zones (R = {self.exclusion_radius_nm:.0f} nm)")
        a.set_xlabel("y (µm)")
        a.set_ylabel("x (µm)")
        a = ax[0, 1]
        b = self.boolean
        a.plot(b["lag_nm"], b["covariance"], ".", ms=3, label="measured C(h)")
        a.plot(b["lag_nm"], b["covariance_fit"], "-", label=f"Boolean discs, R = {b['radius_nm']:.0f} nm")
        a.axhline(self.fraction**2, color="k", lw=0.5, ls="--", label="p²")
        a.set_xlabel("h (nm)")
        a.set_ylabel("C(h)")
        a.legend(fontsize=8)
        a.set_title("covariance")
        a = ax[1, 0]
        if self.nn_distances_nm.size:
            a.hist(self.nn_distances_nm, bins=30, color="tab:blue", alpha=0.8)
            a.axvline(2 * self.exclusion_radius_nm, color="tab:cyan", label="hard-core distance")
            a.legend(fontsize=8)
        a.set_xlabel("nearest-neighbour distance (nm)")
        a.set_ylabel("number of pairs (1)")
        a = ax[1, 1]
        d = self.particles.equivalent_diameters_nm[~self.particles.on_border]
        if d.size:
            a.hist(d, bins=30, color="tab:green", alpha=0.8)
        a.set_xlabel("equivalent diameter (nm)")
        a.set_ylabel("number of particles (1)")
        fig.suptitle(title or f"area fraction {self.fraction:.3f}")
        fig.tight_layout()
        if path is not None:
            fig.savefig(path, dpi=120)
            plt.close(fig)
            return str(path)
        return fig


def analyze_image(image, pixel_nm=1.0, threshold="otsu", invert: bool = False, smooth_px: float = 1.0,
                  min_size_px: int = 4, periodic: bool = False, granulometry_radii_nm=None,
                  model: str | None = None) -> ImageAnalysis:
    """Analyse an SEM-like image: binarise, measure, estimate the models' parameters.

    ``image`` is a grey-level array, a binary array, a :class:`Microstructure` (2-D) or a
    path to an image file. ``model`` adds a model fit (``.model_estimate``, prefixed keys
    in ``summary()``): ``"aggregates"`` (:func:`~nmmm.microstructure.estimation.estimate_aggregates`)
    or ``"flakes"`` (:func:`~nmmm.microstructure.estimation.estimate_flakes`, for a
    cross-section with the substrate horizontal, i.e. along the image rows).
    """
    if model not in (None, "aggregates", "flakes"):
        raise InvalidInputError(f"model must be None, 'aggregates' or 'flakes', got {model!r}")
    if isinstance(image, (str, Path)):
        image = read_image(image)
    if isinstance(image, Microstructure):
        if image.ndim != 2:
            raise InvalidInputError("analyze_image needs a 2-D image; take a section first (Microstructure.section)")
        pixel_nm = image.voxel_nm
        periodic = image.periodic
        image = (image.labels != 0).astype(float)
    img = _as_image(image).astype(float)
    if img.ndim != 2:
        raise InvalidInputError("analyze_image needs a 2-D image")
    v = as_voxel_nm(pixel_nm, 2)
    if set(np.unique(img).tolist()) <= {0.0, 1.0}:
        b, thr = img > 0.5, "binary input"
    else:
        b = binarize(img, threshold, invert, smooth_px, min_size_px)
        thr = threshold if not isinstance(threshold, str) else "otsu"
    st = particle_statistics(b, v, periodic, min_size_px)
    if st.count >= 2:
        nn, pair_inner = _nn_with_partner(st, periodic)
        rex = exclusion_radius(nn[pair_inner] if pair_inner.any() else nn)
    else:
        nn, rex = np.zeros(0), float("nan")
    boo = estimate_boolean(b, v, "disc", periodic)
    hc = None
    if st.count >= 2:
        hc = estimate_hardcore(b, v, periodic, min_size_px)
    A = integral_range(b, v, periodic=True) if periodic else integral_range(b, v, periodic=False, extent=0.5)
    if granulometry_radii_nm is None:
        granulometry_radii_nm = np.linspace(0, 3 * boo["radius_nm"], 13)
    gr = granulometry(b, granulometry_radii_nm, v, periodic)
    est = None
    if model is not None:
        if model == "aggregates":
            est = estimate_aggregates(b, v, periodic)
        else:  # the substrate along the rows: estimate_flakes wants it along axis 0
            est = estimate_flakes(b.T, (v[1], v[0]), periodic, min_size_px)
    return ImageAnalysis(img, b, v, thr, float(b.mean()), st, nn, rex, boo, hc, A, gr, est)
