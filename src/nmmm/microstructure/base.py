"""The :class:`Microstructure` container and size distributions.

- :class:`Microstructure` — a voxelised (2-D or 3-D) unit cell: integer phase labels,
  voxel size in nm per axis (anisotropic voxels allowed), phase names, periodicity and the
  parameters of the model that produced it.
- :class:`SizeDistribution` — constant, lognormal, uniform or gamma distribution of a
  length (nm), with analytic raw moments (needed by the Boolean model, p = 1 − exp(−θ E[V])).
- :func:`as_size_distribution` — a number or a distribution → :class:`SizeDistribution`.
- :func:`as_voxel_nm` — validate a voxel size per axis.
- :func:`as_box_nm` — validate a cell size (2 or 3 positive lengths in nm).
- :func:`random_rotations` — uniformly distributed random rotation matrices (Shoemake).

Conventions: lengths in nm; label 0 is the matrix (binder), labels 1, 2, ... are phases;
array axes are (x, y) in 2-D and (x, y, z) in 3-D, z pointing away from the substrate.

References
----------
- Shoemake, K. (1992). Uniform random rotations. Graphics Gems III, 124–132.
- Jeulin, D. (2021). Morphological Models of Random Structures. Springer.
  https://doi.org/10.1007/978-3-030-75452-5
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import special

from nmmm.errors import InvalidInputError
from nmmm.spectra import check_positive

__all__ = [
    "Microstructure",
    "SizeDistribution",
    "as_size_distribution",
    "as_voxel_nm",
    "as_box_nm",
    "random_rotations",
]


def as_box_nm(box_nm, name: str = "box_nm") -> tuple[float, ...]:
    """Return a cell size as a tuple of 2 or 3 finite lengths > 0 (nm)."""
    try:
        b = np.atleast_1d(np.asarray(box_nm, dtype=float))
    except (TypeError, ValueError):
        raise InvalidInputError(f"{name} must hold 2 or 3 positive lengths (nm), got {box_nm!r}") from None
    if b.ndim != 1 or b.size not in (2, 3) or not np.all(np.isfinite(b)) or np.any(b <= 0):
        raise InvalidInputError(f"{name} must hold 2 or 3 positive lengths (nm), got {box_nm!r}")
    return tuple(float(x) for x in b)


def seed_param(seed):
    """How a seed is recorded in a model's parameters (an int, None, or "generator")."""
    return seed if isinstance(seed, (int, type(None))) else "generator"


def as_voxel_nm(voxel_nm, ndim: int) -> tuple[float, ...]:
    """Return the voxel size as a tuple of ``ndim`` positive floats (nm).

    A scalar means isotropic voxels.
    """
    v = np.atleast_1d(check_positive(voxel_nm, "voxel_nm")).astype(float)
    if v.size == 1:
        v = np.repeat(v, ndim)
    if v.size != ndim:
        raise InvalidInputError(f"voxel_nm needs 1 or {ndim} values for a {ndim}-D cell, got {v.size}")
    return tuple(float(x) for x in v)


@dataclass(frozen=True, eq=False)
class Microstructure:
    """A voxelised unit cell (2-D or 3-D) with physical units.

    Parameters
    ----------
    labels : ndarray of int, shape (nx, ny) or (nx, ny, nz)
        0 = matrix / binder, 1, 2, ... = phases (particles, flakes, ...).
    voxel_nm : tuple of float
        Voxel edge per axis in nm (anisotropic voxels allowed).
    phases : dict
        label -> phase name, e.g. ``{0: "binder", 1: "hematite"}``.
    periodic : bool
        True if the cell is periodic (particles wrap across faces): what the FFT
        homogenization solver needs.
    params : dict
        Parameters of the model that produced the cell (for provenance and files).

    Examples
    --------
    >>> m = Microstructure(np.array([[0, 1], [1, 1]]), voxel_nm=10.0)
    >>> m.shape, m.voxel_nm, round(m.volume_fraction(), 2)
    ((2, 2), (10.0, 10.0), 0.75)
    """

    labels: np.ndarray
    voxel_nm: tuple = (1.0,)
    phases: dict = field(default_factory=dict)
    periodic: bool = True
    params: dict = field(default_factory=dict)

    def __post_init__(self):
        lab = np.asarray(self.labels)
        if lab.ndim not in (2, 3):
            raise InvalidInputError(f"labels must be a 2-D or 3-D array, got {lab.ndim}-D with shape {lab.shape}")
        if lab.dtype.kind == "b":
            lab = lab.astype(np.uint8)
        if lab.dtype.kind not in "iu":
            raise InvalidInputError(
                f"labels must be integers (0 = matrix, 1.. = phases), got dtype {lab.dtype}; "
                "binarise grey-level images first (nmmm.microstructure.binarize)"
            )
        if lab.size and lab.min() < 0:
            raise InvalidInputError("labels must be >= 0 (0 = matrix, 1.. = phases)")
        lab = lab.view()
        lab.flags.writeable = False
        object.__setattr__(self, "labels", lab)
        object.__setattr__(self, "voxel_nm", as_voxel_nm(self.voxel_nm, lab.ndim))
        phases = dict(self.phases) if self.phases else {}
        for k in np.unique(lab).tolist():
            phases.setdefault(int(k), "matrix" if k == 0 else f"phase{k}")
        object.__setattr__(self, "phases", {int(k): str(v) for k, v in sorted(phases.items())})
        object.__setattr__(self, "periodic", bool(self.periodic))
        object.__setattr__(self, "params", dict(self.params))

    # -- geometry ---------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, ...]:
        return self.labels.shape

    @property
    def ndim(self) -> int:
        return self.labels.ndim

    @property
    def size_nm(self) -> tuple[float, ...]:
        """Cell edge lengths in nm."""
        return tuple(n * v for n, v in zip(self.shape, self.voxel_nm))

    @property
    def voxel_volume_nm(self) -> float:
        """Volume (3-D) or area (2-D) of one voxel in nm^d."""
        return float(np.prod(self.voxel_nm))

    def volume_fraction(self, label: int | None = None) -> float:
        """Fraction of voxels with ``label`` (default: all non-zero labels)."""
        if label is None:
            return float(np.count_nonzero(self.labels)) / self.labels.size
        return float(np.count_nonzero(self.labels == label)) / self.labels.size

    def fractions(self) -> dict:
        """Volume fraction of every phase, by name."""
        counts = np.bincount(self.labels.ravel())
        return {self.phases.get(k, str(k)): counts[k] / self.labels.size for k in range(counts.size) if counts[k]}

    def binary(self, label: int | None = None) -> np.ndarray:
        """Boolean indicator of one phase (default: all non-zero labels)."""
        return self.labels != 0 if label is None else self.labels == label

    def section(self, axis: int = 2, index: int | None = None) -> "Microstructure":
        """A 2-D planar section (an SEM-like cut) normal to ``axis`` at ``index`` (default: middle)."""
        if self.ndim != 3:
            raise InvalidInputError("section() needs a 3-D microstructure")
        if axis not in (0, 1, 2):
            raise InvalidInputError(f"axis must be 0, 1 or 2, got {axis}")
        n = self.shape[axis]
        index = n // 2 if index is None else int(index)
        if not 0 <= index < n:
            raise InvalidInputError(f"section index must lie in [0, {n - 1}], got {index}")
        lab = np.take(self.labels, index, axis=axis).copy()
        vox = tuple(v for i, v in enumerate(self.voxel_nm) if i != axis)
        params = dict(self.params, section_axis=axis, section_index=index)
        return Microstructure(lab, vox, self.phases, self.periodic, params)

    def with_params(self, **params) -> "Microstructure":
        """A copy with extra entries in ``params``."""
        return replace(self, labels=np.array(self.labels), params=dict(self.params, **params))

    def __repr__(self) -> str:
        fr = ", ".join(f"{k}={v:.4f}" for k, v in self.fractions().items())
        return (
            f"Microstructure(shape={self.shape}, voxel_nm={self.voxel_nm}, periodic={self.periodic}, "
            f"model={self.params.get('model', '?')!r}, fractions: {fr})"
        )


# ---------------------------------------------------------------------------------------
# size distributions
# ---------------------------------------------------------------------------------------
_KINDS = ("constant", "lognormal", "uniform", "gamma")


@dataclass(frozen=True)
class SizeDistribution:
    """Distribution of a length in nm (radius, diameter, thickness...).

    Parameters
    ----------
    kind : {"constant", "lognormal", "uniform", "gamma"}
    mean_nm : float
        Mean of the distribution (nm).
    std_nm : float
        Standard deviation (nm); 0 for ``constant``. For ``uniform`` the support is
        mean ± sqrt(3)·std.

    Notes
    -----
    Raw moments E[X^k] are analytic for every kind, so Boolean-model intensities follow
    exactly from p = 1 − exp(−θ E[V]) (Matheron 1975).

    Examples
    --------
    >>> d = SizeDistribution("lognormal", 100.0, 20.0)
    >>> round(d.moment(1), 6), round(d.moment(2) - d.moment(1) ** 2, 6)
    (100.0, 400.0)
    """

    kind: str = "constant"
    mean_nm: float = 1.0
    std_nm: float = 0.0

    def __post_init__(self):
        if self.kind not in _KINDS:
            raise InvalidInputError(f"size distribution kind must be one of {_KINDS}, got {self.kind!r}")
        check_positive(self.mean_nm, "mean_nm")
        if not np.isfinite(self.std_nm) or self.std_nm < 0:
            raise InvalidInputError(f"std_nm must be finite and >= 0, got {self.std_nm!r}")
        if self.kind == "uniform" and math.sqrt(3) * self.std_nm >= self.mean_nm:
            raise InvalidInputError("uniform size distribution needs std_nm < mean_nm / sqrt(3) (sizes > 0)")
        if self.kind != "constant" and self.std_nm == 0:
            object.__setattr__(self, "kind", "constant")

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """Draw ``n`` sizes (nm)."""
        m, s = float(self.mean_nm), float(self.std_nm)
        if self.kind == "constant":
            return np.full(n, m)
        if self.kind == "lognormal":
            s2 = math.log1p((s / m) ** 2)
            return rng.lognormal(math.log(m) - s2 / 2, math.sqrt(s2), n)
        if self.kind == "uniform":
            w = math.sqrt(3) * s
            return rng.uniform(m - w, m + w, n)
        k = (m / s) ** 2
        return rng.gamma(k, m / k, n)

    def moment(self, k: float) -> float:
        """Raw moment E[X^k] (nm^k), analytic."""
        m, s = float(self.mean_nm), float(self.std_nm)
        if self.kind == "constant":
            return m**k
        if self.kind == "lognormal":
            s2 = math.log1p((s / m) ** 2)
            mu = math.log(m) - s2 / 2
            return math.exp(k * mu + 0.5 * k * k * s2)
        if self.kind == "uniform":
            w = math.sqrt(3) * s
            a, b = m - w, m + w
            return (b ** (k + 1) - a ** (k + 1)) / ((k + 1) * (b - a))
        shape = (m / s) ** 2
        scale = m / shape
        return scale**k * math.exp(special.gammaln(shape + k) - special.gammaln(shape))

    @property
    def max_nm(self) -> float:
        """A practical upper bound (exact for constant/uniform, the 1 − 1e-6 quantile otherwise)."""
        m, s = float(self.mean_nm), float(self.std_nm)
        if self.kind == "constant":
            return m
        if self.kind == "uniform":
            return m + math.sqrt(3) * s
        from scipy import stats

        if self.kind == "lognormal":
            s2 = math.log1p((s / m) ** 2)
            return float(stats.lognorm.ppf(1 - 1e-6, math.sqrt(s2), scale=math.exp(math.log(m) - s2 / 2)))
        k = (m / s) ** 2
        return float(stats.gamma.ppf(1 - 1e-6, k, scale=m / k))

    def to_dict(self) -> dict:
        return {"kind": self.kind, "mean_nm": float(self.mean_nm), "std_nm": float(self.std_nm)}


def as_size_distribution(x, name: str = "size_nm") -> SizeDistribution:
    """A number (constant size, nm), a dict, a (kind, mean, std) tuple or a SizeDistribution."""
    if isinstance(x, SizeDistribution):
        return x
    if isinstance(x, dict):
        try:
            return SizeDistribution(**x)
        except TypeError as exc:
            raise InvalidInputError(f"{name}: bad size distribution {x!r} ({exc}); use kind, mean_nm, std_nm") from None
    if isinstance(x, (tuple, list)) and len(x) == 3 and isinstance(x[0], str):
        return SizeDistribution(x[0], float(x[1]), float(x[2]))
    try:
        v = float(check_positive(x, name))
    except TypeError:
        raise InvalidInputError(f"{name} must be a positive number (nm) or a SizeDistribution, got {x!r}") from None
    return SizeDistribution("constant", v, 0.0)


def random_rotations(rng: np.random.Generator, n: int, ndim: int = 3) -> np.ndarray:
    """``n`` rotation matrices, uniformly distributed (Haar measure); shape (n, 3, 3).

    In 3-D uses Shoemake's (1992) uniform quaternions; in 2-D rotates about z by a
    uniform angle. Rows of each matrix are the particle's local axes in the cell frame.
    """
    if ndim == 2:
        t = rng.uniform(0, 2 * np.pi, n)
        c, s = np.cos(t), np.sin(t)
        R = np.zeros((n, 3, 3))
        R[:, 0, 0], R[:, 0, 1], R[:, 1, 0], R[:, 1, 1], R[:, 2, 2] = c, s, -s, c, 1.0
        return R
    u1, u2, u3 = rng.random((3, n))
    a, b = np.sqrt(1 - u1), np.sqrt(u1)
    w, x = a * np.sin(2 * np.pi * u2), a * np.cos(2 * np.pi * u2)
    y, z = b * np.sin(2 * np.pi * u3), b * np.cos(2 * np.pi * u3)
    R = np.empty((n, 3, 3))
    R[:, 0, 0] = 1 - 2 * (y * y + z * z)
    R[:, 0, 1] = 2 * (x * y - z * w)
    R[:, 0, 2] = 2 * (x * z + y * w)
    R[:, 1, 0] = 2 * (x * y + z * w)
    R[:, 1, 1] = 1 - 2 * (x * x + z * z)
    R[:, 1, 2] = 2 * (y * z - x * w)
    R[:, 2, 0] = 2 * (x * z - y * w)
    R[:, 2, 1] = 2 * (y * z + x * w)
    R[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return R
