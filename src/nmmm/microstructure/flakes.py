"""Metal flakes in a paint layer: the mixed Boolean / deposit model.

After Couka, Willot & Jeulin (2012): aluminium flakes are thin discs (platelets) with a
diameter distribution and a thickness; their in-plane positions form a Poisson (Boolean)
process in the layer; their normals are close to the layer normal (tilt angles of a few
degrees); and they are *deposited* towards the substrate one after the other — each flake
falls vertically, without rotating, until it touches the substrate or a flake already
deposited, keeping an exclusion gap of binder between flakes. Rigid flakes resting on the
highest point under them leave binder-filled voids below, so a rigid deposit is looser
than the average stacking (about 1 µm of aluminium per 10 µm of layer for 20 µm flakes
with 3° tilts); a layer too thin for the flakes asked raises an error saying so. The stack is computed on a
height map (the top of the deposit in each column, ``grid_nm`` resolution), so the cost
is O(N · footprint pixels) and independent of the cell thickness.

Representation (bounded memory). The seed's metallic unit cell is 450 µm × 450 µm ×
20 µm with flakes tens of µm wide and a few hundred nm thick: a dense isotropic grid at
the flake thickness would hold ~10¹¹ voxels. :class:`FlakeDeposit` therefore keeps the
*analytic* list (centres, normals, diameters, thicknesses, all in nm — a few thousand
rows) and rasterises on demand at the resolution asked, with anisotropic voxels
(e.g. 1000 × 1000 × 100 nm → 450 × 450 × 200 voxels, 40 MB) or on a window of the cell.

- :class:`FlakeDeposit` — the analytic flake list; ``.rasterize(voxel_nm | shape)``,
  ``.window(origin_nm, size_nm)``, ``.tilt_deg``, ``.depth_nm``, ``.number_density_per_nm2``.
- :func:`flake_deposit` — draw a deposit (``mode="deposit"``) or a Boolean layer of flakes
  with uniform heights (``mode="boolean"``).
- :func:`flake_deposit_capacity` — how full the deposit model fills a layer: the volume
  fraction each of several reference cells holds before its first flake rises above the top.

References
----------
- Couka, E., Willot, F., Jeulin, D. (2012). A mixed Boolean and deposit model for the
  modeling of metal pigments in paint layers. Image Anal. Stereol. 32(2).
- Jeulin, D. (1997). Dead leaves models: from space tessellation to random functions;
  Jeulin, D. (2021). Morphological Models of Random Structures, Springer (sequential
  deposit models).
- Azzimonti, D. F., Willot, F., Jeulin, D. (2013). Optical properties of deposit models
  for paints: full-fields FFT computations and representative volume element.
  J. Mod. Opt. 60(7), 519–528.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.microstructure.base import Microstructure, as_size_distribution, seed_param
from nmmm.microstructure.particles import SHAPES, ParticleSet
from nmmm.spectra import check_fraction, check_positive

__all__ = ["FlakeDeposit", "flake_deposit", "flake_deposit_capacity", "normal_rotations", "SEED_METALLIC_CELL_NM"]

#: The seed paper's metallic unit cell: 450 µm × 450 µm × 20 µm (nm).
SEED_METALLIC_CELL_NM = (450_000.0, 450_000.0, 20_000.0)


def normal_rotations(normals) -> np.ndarray:
    """Rotation matrices (N, 3, 3) whose third row is the given unit normal."""
    n = np.asarray(normals, float).reshape(-1, 3)
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    ref = np.where(np.abs(n[:, :1]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
    u = np.cross(n, ref)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(n, u)
    return np.stack([u, v, n], axis=1)


@dataclass(frozen=True, eq=False)
class FlakeDeposit:
    """An analytic list of disc-shaped flakes in a layer (all lengths in nm).

    Parameters
    ----------
    centres_nm : (N, 3) array
        Flake centres; z = height above the substrate (0 ≤ z ≤ box_nm[2]).
    normals : (N, 3) array
        Unit normals, n_z > 0 (z is the layer normal, pointing to the air side).
    diameters_nm, thicknesses_nm : (N,) arrays
    box_nm : (3,) tuple
        Cell size: (Lx, Ly, layer thickness).
    periodic : bool
        Periodic in x and y (flakes wrap across the side faces); flakes never cross the
        bottom or top faces, so the voxelised cell is also periodic in z (binder around).
    params : dict
        Model parameters.
    """

    centres_nm: np.ndarray
    normals: np.ndarray
    diameters_nm: np.ndarray
    thicknesses_nm: np.ndarray
    box_nm: tuple = SEED_METALLIC_CELL_NM
    periodic: bool = True
    params: dict = field(default_factory=dict)

    def __post_init__(self):
        c = np.asarray(self.centres_nm, float).reshape(-1, 3)
        n = c.shape[0]
        nr = np.asarray(self.normals, float).reshape(-1, 3)
        d = np.asarray(self.diameters_nm, float).reshape(-1)
        t = np.asarray(self.thicknesses_nm, float).reshape(-1)
        if nr.shape[0] != n or d.size != n or t.size != n:
            raise InvalidInputError("centres_nm, normals, diameters_nm and thicknesses_nm must describe the same flakes")
        for name, a in (("centres_nm", c), ("normals", nr), ("diameters_nm", d), ("thicknesses_nm", t)):
            if not np.all(np.isfinite(a)):
                raise InvalidInputError(f"{name} must be finite")
        if n and (d.min() <= 0 or t.min() <= 0):
            raise InvalidInputError("flake diameters and thicknesses must be > 0 nm")
        norm = np.linalg.norm(nr, axis=1) if n else np.ones(0)
        if n and np.any(norm == 0):
            raise InvalidInputError("flake normals must be non-zero vectors")
        nr = nr / norm[:, None] if n else nr
        nr = np.where(nr[:, 2:3] < 0, -nr, nr)  # a disc's normal is defined up to sign: take n_z >= 0
        box = tuple(float(b) for b in self.box_nm)
        if len(box) != 3 or min(box) <= 0:
            raise InvalidInputError(f"box_nm must be (Lx, Ly, thickness) > 0 in nm, got {self.box_nm!r}")
        for name, a in (("centres_nm", c), ("normals", nr), ("diameters_nm", d), ("thicknesses_nm", t)):
            a.flags.writeable = False
        object.__setattr__(self, "centres_nm", c)
        object.__setattr__(self, "normals", nr)
        object.__setattr__(self, "diameters_nm", d)
        object.__setattr__(self, "thicknesses_nm", t)
        object.__setattr__(self, "box_nm", box)

    def __len__(self) -> int:
        return self.centres_nm.shape[0]

    @property
    def tilt_deg(self) -> np.ndarray:
        """Angle between each flake normal and the layer normal (degrees)."""
        return np.degrees(np.arccos(np.clip(self.normals[:, 2], -1, 1)))

    @property
    def azimuth_deg(self) -> np.ndarray:
        """Azimuth of each flake normal in the layer plane (degrees, from x)."""
        return np.degrees(np.arctan2(self.normals[:, 1], self.normals[:, 0])) % 360.0

    @property
    def depth_nm(self) -> np.ndarray:
        """Depth of each flake centre below the top of the layer (nm)."""
        return self.box_nm[2] - self.centres_nm[:, 2]

    @property
    def number_density_per_nm2(self) -> float:
        """Flakes per unit area of the layer (nm⁻²)."""
        return len(self) / (self.box_nm[0] * self.box_nm[1])

    @property
    def half_height_nm(self) -> np.ndarray:
        """Vertical half extent of each flake: r sin(tilt) + (t/2) cos(tilt)."""
        nz = self.normals[:, 2]
        return self.diameters_nm / 2 * np.sqrt(np.clip(1 - nz * nz, 0, 1)) + self.thicknesses_nm / 2 * nz

    def volume_fraction(self) -> float:
        """Nominal volume fraction of flakes, Σ π D²/4 · t / V (exact when flakes do not overlap)."""
        v = np.pi / 4 * self.diameters_nm**2 * self.thicknesses_nm
        return float(v.sum() / np.prod(self.box_nm))

    def to_particles(self, label: int = 1, phase: str = "aluminium") -> ParticleSet:
        """The flakes as a :class:`ParticleSet` of cylinders."""
        n = len(self)
        half = np.column_stack([self.diameters_nm / 2, self.diameters_nm / 2, self.thicknesses_nm / 2])
        return ParticleSet(self.centres_nm, normal_rotations(self.normals) if n else np.zeros((0, 3, 3)), half,
                           np.full(n, SHAPES["cylinder"]), np.full(n, 2.0), np.full(n, int(label)),
                           self.box_nm, self.periodic, {0: "binder", int(label): phase}, dict(self.params))

    def rasterize(self, voxel_nm=None, shape=None, label: int = 1, phase: str = "aluminium") -> Microstructure:
        """Voxelise at ``voxel_nm`` (scalar or per axis; anisotropic voxels welcome) or ``shape``.

        Flakes thinner than the vertical voxel size are only partly captured; the
        ``params["nominal_fraction"]`` of the result says what the analytic fraction is.
        """
        m = self.to_particles(label, phase).rasterize(voxel_nm=voxel_nm, shape=shape)
        return m.with_params(nominal_fraction=self.volume_fraction())

    def window(self, origin_nm, size_nm) -> "FlakeDeposit":
        """The flakes that meet the window [origin, origin + size) in x, y (whole thickness),
        shifted to the window's frame; the result is not periodic."""
        o = np.asarray(origin_nm, float).reshape(-1)[:2]
        s = np.asarray(size_nm, float).reshape(-1)[:2]
        if np.any(s <= 0) or not np.all(np.isfinite(o)):
            raise InvalidInputError("window needs a finite origin_nm and size_nm > 0 (x, y)")
        L = np.array(self.box_nm[:2])
        r = self.diameters_nm / 2 + self.thicknesses_nm
        c = self.centres_nm.copy()
        keep_c, keep_i = [], []
        shifts = [(0, 0)]
        if self.periodic:
            shifts = [(i, j) for i in (-1, 0, 1) for j in (-1, 0, 1)]
        for i, j in shifts:
            xy = c[:, :2] + np.array([i, j]) * L
            inside = np.all((xy + r[:, None] > o) & (xy - r[:, None] < o + s), axis=1)
            idx = np.flatnonzero(inside)
            cc = c[idx].copy()
            cc[:, :2] = xy[idx] - o
            keep_c.append(cc)
            keep_i.append(idx)
        idx = np.concatenate(keep_i)
        return FlakeDeposit(np.concatenate(keep_c), self.normals[idx], self.diameters_nm[idx],
                            self.thicknesses_nm[idx], (float(s[0]), float(s[1]), self.box_nm[2]), False,
                            dict(self.params, window_origin_nm=o.tolist()))

    def summary(self) -> dict:
        """Statistics that the appearance model needs (nm and degrees)."""
        return {
            "n_flakes": len(self),
            "number_density_per_mm2": self.number_density_per_nm2 * 1e12,
            "volume_fraction": self.volume_fraction(),
            "mean_diameter_nm": float(self.diameters_nm.mean()) if len(self) else float("nan"),
            "mean_thickness_nm": float(self.thicknesses_nm.mean()) if len(self) else float("nan"),
            "mean_tilt_deg": float(self.tilt_deg.mean()) if len(self) else float("nan"),
            "mean_depth_nm": float(self.depth_nm.mean()) if len(self) else float("nan"),
            "max_height_nm": float((self.centres_nm[:, 2] + self.half_height_nm).max()) if len(self) else 0.0,
        }


@numba.njit(cache=True, inline="always")
def _footprint(x, y, nx, ny, nz, r, t, grid, gx, gy, periodic):
    ex = r * math.sqrt(max(0.0, 1 - nx * nx)) + 0.5 * t * abs(nx)
    ey = r * math.sqrt(max(0.0, 1 - ny * ny)) + 0.5 * t * abs(ny)
    i0 = int(math.floor((x - ex) / grid[0] - 0.5))
    i1 = int(math.ceil((x + ex) / grid[0] - 0.5))
    j0 = int(math.floor((y - ey) / grid[1] - 0.5))
    j1 = int(math.ceil((y + ey) / grid[1] - 0.5))
    if periodic:
        i1 = min(i1, i0 + gx - 1)
        j1 = min(j1, j0 + gy - 1)
    else:
        i0, j0, i1, j1 = max(i0, 0), max(j0, 0), min(i1, gx - 1), min(j1, gy - 1)
    return i0, i1, j0, j1


@numba.njit(cache=True)
def _deposit_kernel(xy, normals, radii, thick, gap, H, grid, periodic, stop_above=np.inf):
    """Sequential rigid deposit on a height map; returns centre heights and final normals.

    With a finite ``stop_above`` the deposit stops at the first flake whose top rises above it
    (its height is set; the later flakes' heights are left NaN): :func:`flake_deposit_capacity`."""
    n = xy.shape[0]
    gx, gy = H.shape
    z = np.full(n, np.nan)
    out_normals = normals.copy()
    for p in range(n):
        nx, ny, nz = normals[p, 0], normals[p, 1], normals[p, 2]
        r, t = radii[p], thick[p]
        x, y = xy[p, 0], xy[p, 1]
        out_normals[p, 0], out_normals[p, 1], out_normals[p, 2] = nx, ny, nz
        half_z = t / (2 * nz)
        hz = r * math.sqrt(max(0.0, 1 - nz * nz)) + 0.5 * t * nz
        i0, i1, j0, j1 = _footprint(x, y, nx, ny, nz, r, t, grid, gx, gy, periodic)
        zc = hz  # resting on the substrate
        # first pass: the lowest position that clears the deposit below (with the gap)
        for i in range(i0, i1 + 1):
            dx = (i + 0.5) * grid[0] - x
            ii = i % gx
            for j in range(j0, j1 + 1):
                dy = (j + 0.5) * grid[1] - y
                dz = -(nx * dx + ny * dy) / nz
                if dx * dx + dy * dy + dz * dz <= r * r:
                    h = H[ii, j % gy]
                    if h > 0.0:
                        need = h + gap - dz + half_z
                        if need > zc:
                            zc = need
        z[p] = zc
        if zc + hz > stop_above:
            break
        # second pass: raise the height map to the flake's upper surface
        for i in range(i0, i1 + 1):
            dx = (i + 0.5) * grid[0] - x
            ii = i % gx
            for j in range(j0, j1 + 1):
                dy = (j + 0.5) * grid[1] - y
                dz = -(nx * dx + ny * dy) / nz
                if dx * dx + dy * dy + dz * dz <= r * r:
                    top = zc + dz + half_z
                    jj = j % gy
                    if top > H[ii, jj]:
                        H[ii, jj] = top
    return z, out_normals


def _draw_flakes(rng, n, box, ddist, tdist, tilt_std_deg):
    """n i.i.d. flakes in the order the deposit lays them: positions, diameters, thicknesses,
    tilts (half-normal of scale ``tilt_std_deg``, truncated at 80° by redrawing) and normals."""
    xy = rng.random((n, 2)) * np.array(box[:2])
    d = ddist.sample(rng, n)
    t = tdist.sample(rng, n)
    tilt = np.abs(rng.normal(0.0, math.radians(tilt_std_deg), n)) if tilt_std_deg > 0 else np.zeros(n)
    for _ in range(100):  # truncate at 80 degrees by redrawing
        bad = tilt > math.radians(80)
        if not bad.any():
            break
        tilt[bad] = np.abs(rng.normal(0.0, math.radians(tilt_std_deg), bad.sum()))
    tilt = np.minimum(tilt, math.radians(80))
    phi = rng.uniform(0, 2 * np.pi, n)
    normals = np.column_stack([np.sin(tilt) * np.cos(phi), np.sin(tilt) * np.sin(phi), np.cos(tilt)])
    return xy, d, t, tilt, normals


def _deposit_args(box_nm, diameter_nm, thickness_nm, tilt_std_deg, exclusion_nm):
    """The checked arguments shared by :func:`flake_deposit` and :func:`flake_deposit_capacity`
    -> (box (3 floats, nm), diameter distribution, thickness distribution)."""
    box = tuple(float(b) for b in check_positive(np.asarray(box_nm, float), "box_nm"))
    if len(box) != 3:
        raise InvalidInputError(f"box_nm must be (Lx, Ly, layer thickness) in nm, got {box_nm!r}")
    ddist = as_size_distribution(diameter_nm, "diameter_nm")
    tdist = as_size_distribution(thickness_nm, "thickness_nm")
    if not (math.isfinite(tilt_std_deg) and 0 <= tilt_std_deg <= 90):
        raise InvalidInputError(f"tilt_std_deg must lie in [0, 90] degrees, got {tilt_std_deg!r}")
    if not (math.isfinite(exclusion_nm) and exclusion_nm >= 0):
        raise InvalidInputError(f"exclusion_nm must be >= 0 nm, got {exclusion_nm!r}")
    return box, ddist, tdist


def _height_grid(box, ddist, grid_nm):
    """Pixel (nm, per axis) and shape of the deposit's height map."""
    if grid_nm is None:
        grid_nm = min(ddist.mean_nm / 12, box[0] / 256, box[1] / 256)
    g = np.atleast_1d(check_positive(grid_nm, "grid_nm")).astype(float)
    g = np.resize(g, 2)
    shape = (max(1, int(round(box[0] / g[0]))), max(1, int(round(box[1] / g[1]))))
    if shape[0] * shape[1] > 64_000_000:
        raise InvalidInputError(f"height map {shape} too large; use a coarser grid_nm")
    return np.array(box[:2]) / np.array(shape), shape


#: default number of deposits whose capacities :func:`flake_deposit_capacity` returns
CAPACITY_REALISATIONS = 32
#: entropy of the reference deposits of :func:`flake_deposit_capacity` (fixed: the capacity is the model's, not a
#: seed's)
CAPACITY_ENTROPY = 2012_0032


def flake_deposit_capacity(
    box_nm=SEED_METALLIC_CELL_NM,
    diameter_nm=("lognormal", 20_000.0, 6_000.0),
    thickness_nm=300.0,
    tilt_std_deg: float = 3.0,
    exclusion_nm: float = 100.0,
    grid_nm=None,
    periodic: bool = True,
    realisations: int = CAPACITY_REALISATIONS,
    seed=CAPACITY_ENTROPY,
) -> np.ndarray:
    """How full the deposit model can fill a layer: the capacity of ``realisations`` cells, sorted.

    The deposit of :func:`flake_deposit` lays i.i.d. flakes one after the other, so a deposit of
    ``n`` flakes holds them all exactly when the first ``n`` flakes of an endless sequence stay
    below the top of the layer. One cell's *capacity* is the volume fraction (Σ π D²/4 · t / V)
    of the flakes laid before the first one that rises above the layer (or, like
    :func:`flake_deposit`, is taller than the layer by itself): a deposit of volume fraction φ in
    that cell succeeds about when φ is below it. Each realisation lays a long sequence (drawn from
    ``SeedSequence(seed, spawn_key=(k,))``) and stops at the first overflow, ~2-5 ms for a
    450 µm cell.

    The capacity is not a packing limit: rigid flakes resting on the highest point under them
    make a rough surface, and the layer overflows where its highest tower (a large tilted flake
    on a pile) reaches the top; the cell's capacity is therefore broad (the 20 µm × 300 nm
    aluminium flakes of the grey metallic, 6° spread, 450 µm × 20 µm cell: ~0.011-0.024) and
    falls as the cell grows (more towers to reach the top). Same arguments as
    :func:`flake_deposit`.
    """
    box, ddist, tdist = _deposit_args(box_nm, diameter_nm, thickness_nm, tilt_std_deg, exclusion_nm)
    realisations = int(realisations)
    if realisations < 1:
        raise InvalidInputError(f"realisations must be >= 1, got {realisations!r}")
    g, shape = _height_grid(box, ddist, grid_nm)
    vol = box[0] * box[1] * box[2]
    mean_v = math.pi / 4 * ddist.moment(2) * tdist.mean_nm
    n0 = max(64, int(math.ceil(0.05 * vol / mean_v)))  # 5 % by volume; doubled until the layer overflows
    caps = np.empty(realisations)
    for k in range(realisations):
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(k,)))
        H = np.zeros(shape)
        n, placed = n0, 0.0
        while True:
            xy, d, t, tilt, normals = _draw_flakes(rng, n, box, ddist, tdist, tilt_std_deg)
            z, _ = _deposit_kernel(xy, normals, d / 2, t, float(exclusion_nm), H, g, periodic, box[2])
            v = np.pi / 4 * d * d * t
            top = z + d / 2 * np.sin(tilt) + t / 2 * np.cos(tilt)  # NaN after the first flake over the top
            first = int(np.argmax(~(top <= box[2])))
            if not (top[first] <= box[2]):
                caps[k] = (placed + float(v[:first].sum())) / vol
                break
            placed += float(v.sum())
            if placed >= vol or n > 5_000_000:  # the layer is solid flakes and still below the top
                caps[k] = min(placed / vol, 1.0)
                break
            n *= 2
    return np.sort(caps)


def flake_deposit(
    box_nm=SEED_METALLIC_CELL_NM,
    diameter_nm=("lognormal", 20_000.0, 6_000.0),
    thickness_nm=300.0,
    fraction: float | None = 0.02,
    number_density_per_mm2: float | None = None,
    tilt_std_deg: float = 3.0,
    exclusion_nm: float = 100.0,
    mode: str = "deposit",
    grid_nm=None,
    seed=None,
    periodic: bool = True,
) -> FlakeDeposit:
    """Draw a layer of metal flakes (Couka, Willot & Jeulin 2012).

    Parameters
    ----------
    box_nm : (Lx, Ly, thickness)
        The cell; default the seed's 450 µm × 450 µm × 20 µm.
    diameter_nm : float, (kind, mean, std) or SizeDistribution
        Flake diameters (default lognormal, mean 20 µm, std 6 µm).
    thickness_nm : float or distribution
        Flake thickness (default 300 nm).
    fraction : float
        Volume fraction of flakes in the layer (nominal, Σ V / V_cell); or give
        ``number_density_per_mm2`` instead (flakes per mm² of layer).
    tilt_std_deg : float
        Tilts (angle of the normal to the layer normal) follow a half-normal law of this
        scale, truncated at 80°; azimuths are uniform. Flakes lie mostly parallel to the
        surface.
    exclusion_nm : float
        Minimum binder gap between a flake and the flake it rests on (nm).
    mode : {"deposit", "boolean"}
        ``deposit``: sequential vertical deposit towards the substrate (z = 0);
        ``boolean``: heights uniform in the layer, overlaps allowed (a pure Boolean layer).
    grid_nm : float, optional
        Height-map pixel (default: min(mean diameter / 12, Lx / 256)).
    seed : int or Generator

    Raises
    ------
    InvalidInputError
        When the deposit would rise above the layer thickness (too many or too thick
        flakes for the layer; the message gives the height reached).
    """
    box, ddist, tdist = _deposit_args(box_nm, diameter_nm, thickness_nm, tilt_std_deg, exclusion_nm)
    if mode not in ("deposit", "boolean"):
        raise InvalidInputError(f"mode must be 'deposit' or 'boolean', got {mode!r}")
    rng = np.random.default_rng(seed)
    area = box[0] * box[1]
    mean_v = math.pi / 4 * ddist.moment(2) * tdist.mean_nm
    if (fraction is None) == (number_density_per_mm2 is None):
        raise InvalidInputError("give exactly one of fraction (volume fraction) or number_density_per_mm2")
    if fraction is not None:
        lam = float(check_fraction(fraction)) * area * box[2] / mean_v
    else:
        lam = float(check_positive(number_density_per_mm2, "number_density_per_mm2")) * area * 1e-12
    n = int(rng.poisson(lam))
    if n > 5_000_000:
        raise InvalidInputError(f"{n} flakes requested: reduce the cell or the density")
    xy, d, t, tilt, normals = _draw_flakes(rng, n, box, ddist, tdist, tilt_std_deg)
    hz = d / 2 * np.sin(tilt) + t / 2 * np.cos(tilt)
    if np.any(2 * hz > box[2]):
        err = InvalidInputError(
            f"some flakes (tilted diameter up to {2 * hz.max():.4g} nm) do not fit in the layer thickness "
            f"{box[2]:.4g} nm; reduce tilt_std_deg or the diameters, or thicken the layer"
        )
        err.n_flakes, err.n_fit = n, int(np.argmax(2 * hz > box[2]))  # the layer overflows at that flake
        raise err
    if mode == "deposit":
        g, shape = _height_grid(box, ddist, grid_nm)
        H = np.zeros(shape)
        z, normals = _deposit_kernel(xy, normals, d / 2, t, float(exclusion_nm), H, g, periodic)
        hz = d / 2 * np.sqrt(np.clip(1 - normals[:, 2] ** 2, 0, 1)) + t / 2 * normals[:, 2]
        top = z + hz
        if n and top.max() > box[2]:
            k = int(np.argmax(top > box[2]))
            err = InvalidInputError(
                f"the deposit of {n} flakes rises to {top.max():.4g} nm, above the layer thickness {box[2]:.4g} nm "
                f"(the layer is full after about {k} flakes); lower the fraction, the exclusion gap or the flake "
                "thickness, or thicken the layer"
            )
            err.n_flakes, err.n_fit = n, k  # for callers that name the largest fraction that fits
            raise err
    else:
        z = hz + rng.random(n) * (box[2] - 2 * hz)
    centres = np.column_stack([xy, z])
    params = {
        "model": "flake_deposit",
        "mode": mode,
        "diameter_nm": ddist.to_dict(),
        "thickness_nm": tdist.to_dict(),
        "target_fraction": fraction,
        "number_density_per_mm2": n / area * 1e12,
        "tilt_std_deg": float(tilt_std_deg),
        "exclusion_nm": float(exclusion_nm),
        "seed": seed_param(seed),
        "box_nm": list(box),
    }
    if mode == "deposit":
        params["grid_nm"] = g.tolist()
    return FlakeDeposit(centres, normals, d, t, box, periodic, params)
