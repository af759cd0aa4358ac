"""Representative volume element (Kanit et al. 2003).

The variance of an apparent property Z over realisations of a domain of volume V
decreases as

    D²_Z(V) = D²_Z · (A / V)^α                         (Kanit et al. 2003, eq. 14)

with D²_Z the point variance, A the integral range (for the volume fraction of a phase:
D²_Z = p(1 − p), α = 1 and A the integral range of the covariance). With n independent
realisations of volume V, the absolute error on the mean is 2 D_Z(V) / √n (95 %), and
the relative error

    ε_rel = 2 D_Z(V) / (Z̄ √n)                          (Kanit et al. 2003, eq. 16)

so a target ε_rel fixes V for a given n, or n for a given V.

- :func:`fit_rve` — fit D²(V) = K V^(−α) (K = D²_Z A^α) from values on realisations at
  several sizes → :class:`RVEFit`.
- :class:`RVEFit` — ``.volume_for(rel_precision, n_realisations)``,
  ``.realisations_for(rel_precision, volume)``, ``.size_for(...)`` (edge length),
  ``.variance(volume)``, ``.integral_range`` (when D²_Z is known).
- :func:`rve_study` — run a property on realisations of a model at several sizes
  (progress bar) and fit.

References
----------
- Kanit, T., Forest, S., Galliet, I., Mounoury, V., Jeulin, D. (2003). Determination of
  the size of the representative volume element for random composites: statistical and
  numerical approach. Int. J. Solids Struct. 40, 3647–3679.
  https://doi.org/10.1016/S0020-7683(03)00143-4
- Matheron, G. (1971). The theory of regionalized variables and its applications.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from tqdm.auto import tqdm

from nmmm.errors import InvalidInputError
from nmmm.spectra import check_finite, check_positive

__all__ = ["RVEFit", "fit_rve", "rve_study"]


@dataclass(frozen=True)
class RVEFit:
    """Fitted scaling of the variance with the domain volume, D²(V) = K · V^(−α).

    Attributes
    ----------
    K, alpha : float
        Fit parameters (K in property² · nm^(d·α)).
    mean : float
        Mean of the property (Z̄).
    point_variance : float or None
        D²_Z if known (e.g. p(1 − p) for a volume fraction); then
        ``integral_range = (K / D²_Z)^(1/α)``.
    ndim : int
        2 (areas, nm²) or 3 (volumes, nm³).
    volumes_nm, variances, counts : arrays
        The data fitted.
    """

    K: float
    alpha: float
    mean: float
    point_variance: float | None
    ndim: int
    volumes_nm: np.ndarray
    variances: np.ndarray
    counts: np.ndarray

    @property
    def integral_range(self) -> float | None:
        """A = (K / D²_Z)^(1/α) (nm^d), or None without a point variance."""
        if self.point_variance is None:
            return None
        return (self.K / self.point_variance) ** (1.0 / self.alpha)

    def variance(self, volume_nm):
        """D²(V) from the fit."""
        return self.K * np.asarray(volume_nm, float) ** (-self.alpha)

    def _check_eps(self, rel_precision):
        e = float(check_positive(rel_precision, "rel_precision"))
        if self.mean == 0:
            raise InvalidInputError("relative precision is undefined for a zero mean; use absolute variance")
        return e

    def volume_for(self, rel_precision: float, n_realisations: int = 1) -> float:
        """Domain volume (nm^d) so that n realisations give the mean within ``rel_precision``.

        V = (4 K / (n ε² Z̄²))^(1/α) (Kanit et al. 2003, eq. 16 solved for V).
        """
        e = self._check_eps(rel_precision)
        n = int(n_realisations)
        if n < 1:
            raise InvalidInputError("n_realisations must be >= 1")
        return (4 * self.K / (n * e * e * self.mean**2)) ** (1.0 / self.alpha)

    def size_for(self, rel_precision: float, n_realisations: int = 1) -> float:
        """Edge length (nm) of a square/cubic domain from :meth:`volume_for`."""
        return self.volume_for(rel_precision, n_realisations) ** (1.0 / self.ndim)

    def realisations_for(self, rel_precision: float, volume_nm: float) -> int:
        """Number of realisations of volume V for ``rel_precision``: n = 4 D²(V) / (ε Z̄)²."""
        e = self._check_eps(rel_precision)
        v = float(check_positive(volume_nm, "volume_nm"))
        return max(1, int(math.ceil(4 * self.variance(v) / (e * e * self.mean**2))))


def fit_rve(volumes_nm, values, point_variance: float | None = None, ndim: int = 3, fix_alpha: float | None = None):
    """Fit D²(V) = K V^(−α) to property values on realisations at several domain sizes.

    Parameters
    ----------
    volumes_nm : sequence of float
        Domain volume (nm³, or area nm² with ``ndim=2``) of each size.
    values : sequence of 1-D arrays
        Property values on the realisations of each size (at least 2 per size).
    point_variance : float, optional
        D²_Z, to report the integral range A.
    fix_alpha : float, optional
        Fix α (e.g. 1 for additive properties like the volume fraction) and fit K only.

    The fit is a least-squares line in (log V, log D²) weighted by the number of
    realisations (the variance of log s² is ≈ 2/(n − 1)).
    """
    V = np.atleast_1d(check_positive(volumes_nm, "volumes_nm")).astype(float)
    if len(values) != V.size:
        raise InvalidInputError(f"values must hold one array per volume ({V.size}), got {len(values)}")
    var, cnt, means = [], [], []
    for k, z in enumerate(values):
        z = np.asarray(check_finite(z, f"values[{k}]"), float).ravel()
        if z.size < 2:
            raise InvalidInputError(f"values[{k}] needs at least 2 realisations to estimate a variance")
        var.append(z.var(ddof=1))
        cnt.append(z.size)
        means.append(z.mean() * z.size)
    var, cnt = np.array(var), np.array(cnt)
    if np.any(var <= 0):
        raise InvalidInputError("a variance is zero: the property does not fluctuate at some size")
    if V.size < 2 and fix_alpha is None:
        raise InvalidInputError("need at least two domain sizes to fit alpha (or give fix_alpha)")
    w = (cnt - 1) / 2.0
    x, y = np.log(V), np.log(var)
    if fix_alpha is None:
        W = w.sum()
        xm, ym = (w * x).sum() / W, (w * y).sum() / W
        slope = (w * (x - xm) * (y - ym)).sum() / (w * (x - xm) ** 2).sum()
        alpha = -slope
        logK = ym - slope * xm
    else:
        alpha = float(fix_alpha)
        logK = (w * (y + alpha * x)).sum() / w.sum()
    mean = float(np.sum(means) / cnt.sum())
    return RVEFit(float(math.exp(logK)), float(alpha), mean, point_variance, int(ndim), V, var, cnt)


def rve_study(generate, prop, sizes, n_realisations=10, seed=0, point_variance=None, progress=True, **fit_kw):
    """Compute ``prop(generate(size, seed))`` on realisations at several sizes and fit.

    ``generate(size, seed)`` returns a :class:`~nmmm.microstructure.Microstructure` (or any
    object with ``size_nm``) of edge ``size`` (in its own units); ``prop`` maps it to a
    scalar. Returns (RVEFit, values per size).
    """
    rng = np.random.default_rng(seed)
    values, volumes, ndim = [], [], 3
    total = len(sizes) * int(n_realisations)
    with tqdm(total=total, desc="RVE realisations", disable=not progress, leave=False) as bar:
        for s in sizes:
            zs = []
            for _ in range(int(n_realisations)):
                m = generate(s, int(rng.integers(2**31 - 1)))
                zs.append(float(prop(m)))
                bar.update(1)
            ndim = len(m.size_nm)
            volumes.append(float(np.prod(m.size_nm)))
            values.append(np.array(zs))
    return fit_rve(volumes, values, point_variance=point_variance, ndim=ndim, **fit_kw), values
