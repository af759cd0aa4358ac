"""Hard-core models: random sequential adsorption (RSA) with exclusion zones.

Each particle is implanted inside an *exclusion sphere* (disc in 2-D) of radius
R_ex ≥ its circumscribed radius; exclusion spheres never overlap, so particles never
touch and keep a binder shell of at least 2(R_ex − R_circ) between them — the hard-core
model with exclusion zones used for the hematite coatings of Couka et al. (2015).
Centres are drawn uniformly and accepted when they do not violate the exclusion
(random sequential addition, Widom 1966); a cell list keeps each test O(1).

RSA cannot fill space: the exclusion spheres jam at a saturation fraction

- 0.38278 for spheres in 3-D (Torquato, Uche, Stillinger 2006),
- 0.547069 for discs in 2-D (Hinrichsen, Feder, Jøssang 1986),

so the particle fraction is bounded by jamming × V_particle / V_exclusion (0.14 for
exact cubes in their circumscribed spheres, 0.20 for pseudo-cubes of exponent 8).
A target beyond it raises :class:`~nmmm.errors.InvalidInputError` naming the limit; the
approach to jamming is algebraically slow (fraction ∝ t^(−1/d)), so targets above
≈ 95 % of it may exhaust ``max_attempts`` and raise :class:`~nmmm.errors.ConvergenceError`.

- :data:`RSA_JAMMING` — the jamming limits above.
- :func:`rsa_centres` — RSA of (polydisperse) exclusion spheres in a box (Numba).
- :func:`hardcore_particles` — a hard-core realisation as a :class:`ParticleSet`.
- :func:`hardcore_spheres` — voxelised hard-core spheres (discs on a 2-D grid).
- :func:`hardcore_pseudocubes` — voxelised hard-core pseudo-cubes with random orientations,
  sized by their large diagonal (hematite: 250 nm).
- :func:`max_hardcore_fraction` — the highest particle fraction RSA can reach.

References
----------
- Widom, B. (1966). Random sequential addition of hard spheres to a volume.
  J. Chem. Phys. 44, 3888. https://doi.org/10.1063/1.1726548
- Torquato, S., Uche, O. U., Stillinger, F. H. (2006). Random sequential addition of hard
  spheres in high Euclidean dimensions. Phys. Rev. E 74, 061308.
  https://doi.org/10.1103/PhysRevE.74.061308
- Hinrichsen, E. L., Feder, J., Jøssang, T. (1986). Geometry of random sequential
  adsorption. J. Stat. Phys. 44, 793–827. https://doi.org/10.1007/BF01011908
- Couka, E., Willot, F., Jeulin, D., et al. (2015). Multiscale dispersion of nanoparticles
  in a hematite coating. J. Nanosci. Nanotechnol. 15(5), 3515.
- Manickavasagam, S., Saltiel, C., Giesche, H. (2004). J. Colloid Interface Sci. 280, 417
  (hematite pseudo-cubes).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from tqdm.auto import tqdm

from nmmm.errors import ConvergenceError, InvalidInputError
from nmmm.microstructure.base import Microstructure, as_box_nm, as_size_distribution, random_rotations, seed_param
from nmmm.microstructure.boolean import cell_box_nm
from nmmm.microstructure.particles import SHAPES, ParticleSet, superball_volume
from nmmm.spectra import check_fraction, check_positive

__all__ = [
    "RSA_JAMMING",
    "rsa_centres",
    "hardcore_particles",
    "hardcore_spheres",
    "hardcore_pseudocubes",
    "max_hardcore_fraction",
    "pseudocube_half_size",
    "unit_grain_geometry",
    "grain_geometry",
]

#: RSA saturation (jamming) fraction of equal exclusion spheres, by dimension.
RSA_JAMMING = {
    3: (0.38278, "Torquato, Uche & Stillinger, Phys. Rev. E 74, 061308 (2006)"),
    2: (0.547069, "Hinrichsen, Feder & Jossang, J. Stat. Phys. 44, 793 (1986)"),
}


@numba.njit(cache=True)
def _rsa_kernel(centres, radii, placed, head, nxt, ncell, csize, box, ndim, periodic, seed, attempts):
    np.random.seed(seed)
    n_total = radii.shape[0]
    tried = 0
    nx, ny, nz = ncell[0], ncell[1], ncell[2]
    while placed < n_total and tried < attempts:
        tried += 1
        r = radii[placed]
        x = np.random.random() * box[0]
        y = np.random.random() * box[1]
        z = np.random.random() * box[2] if ndim == 3 else 0.0
        cx = min(int(x / csize[0]), nx - 1)
        cy = min(int(y / csize[1]), ny - 1)
        cz = min(int(z / csize[2]), nz - 1) if ndim == 3 else 0
        ok = True
        # neighbour cells (all cells of an axis when it has fewer than 3)
        ax0 = cx - 1 if nx >= 3 else 0
        ax1 = cx + 1 if nx >= 3 else nx - 1
        ay0 = cy - 1 if ny >= 3 else 0
        ay1 = cy + 1 if ny >= 3 else ny - 1
        az0 = cz - 1 if nz >= 3 else 0
        az1 = cz + 1 if nz >= 3 else nz - 1
        for a in range(ax0, ax1 + 1):
            if not ok:
                break
            if not periodic and (a < 0 or a >= nx):
                continue
            aa = a % nx
            for b in range(ay0, ay1 + 1):
                if not ok:
                    break
                if not periodic and (b < 0 or b >= ny):
                    continue
                bb = b % ny
                for c in range(az0, az1 + 1):
                    if not periodic and (c < 0 or c >= nz):
                        continue
                    cc = c % nz
                    j = head[(aa * ny + bb) * nz + cc]
                    while j >= 0:
                        dx = x - centres[j, 0]
                        dy = y - centres[j, 1]
                        dz = z - centres[j, 2]
                        if periodic:
                            dx -= box[0] * round(dx / box[0])
                            dy -= box[1] * round(dy / box[1])
                            if ndim == 3:
                                dz -= box[2] * round(dz / box[2])
                        dmin = r + radii[j]
                        if dx * dx + dy * dy + dz * dz < dmin * dmin:
                            ok = False
                            break
                        j = nxt[j]
                    if not ok:
                        break
        if ok:
            centres[placed, 0] = x
            centres[placed, 1] = y
            centres[placed, 2] = z
            cell = (cx * ny + cy) * nz + cz
            nxt[placed] = head[cell]
            head[cell] = placed
            placed += 1
    return placed, tried


def rsa_centres(box_nm, exclusion_radii_nm, seed=None, periodic: bool = True, max_attempts: int | None = None,
                progress: bool = False):
    """Random sequential addition of non-overlapping exclusion spheres (discs in 2-D).

    Parameters
    ----------
    box_nm : tuple
        Cell size (nm), 2 or 3 entries.
    exclusion_radii_nm : array (N,)
        Exclusion radius of each particle, placed in this order (sort large first for
        polydisperse packings).
    seed : int or Generator
    periodic : bool
        Minimum-image distances across the faces.
    max_attempts : int
        Trials before giving up (default max(10⁶, 5000·N)).

    Returns
    -------
    centres_nm : (N, 3) array (z = 0 in 2-D)

    Raises
    ------
    ConvergenceError
        When ``max_attempts`` trials could not place all particles (the packing is too
        close to jamming); ``history`` holds the number placed.
    """
    box_nm = as_box_nm(box_nm)
    box = np.array(list(box_nm) + [0.0] * (3 - len(box_nm)))
    ndim = len(box_nm)
    radii = np.ascontiguousarray(np.atleast_1d(exclusion_radii_nm), float)
    if radii.ndim != 1:
        raise InvalidInputError(
            f"exclusion_radii_nm must be a 1-D array (one radius per particle), got shape {radii.shape}"
        )
    if radii.size:
        check_positive(radii, "exclusion_radii_nm")
    n = radii.size
    centres = np.zeros((n, 3))
    if n == 0:
        return centres
    rmax = float(radii.max())
    vol = float(np.prod(box[:ndim]))
    fill = float((math.pi * radii**2).sum() if ndim == 2 else (4 / 3 * math.pi * radii**3).sum()) / vol
    jam, src = RSA_JAMMING[ndim]
    equal = np.ptp(radii) <= 1e-9 * rmax
    if (equal and fill >= jam) or fill >= 1.0:
        raise InvalidInputError(
            f"{n} exclusion zones would fill {fill:.4g} of the cell, beyond the RSA jamming limit {jam} "
            f"({'spheres in 3-D' if ndim == 3 else 'discs in 2-D'}; {src}); lower the number or the radii, "
            "or enlarge the cell"
        )
    if ndim == 2:
        box[2] = 1.0
    ncell = np.maximum(1, np.floor(box / (2 * rmax)).astype(np.int64))
    if ndim == 2:
        ncell[2] = 1
    while np.prod(ncell) > 2**24:
        ncell = np.maximum(1, ncell // 2)
    csize = box / ncell
    head = -np.ones(int(np.prod(ncell)), np.int64)
    nxt = -np.ones(n, np.int64)
    if max_attempts is None:
        max_attempts = max(10**6, 5000 * n)
    rng = np.random.default_rng(seed)
    chunk = max(200_000, 20 * n)
    placed, tried = 0, 0
    with tqdm(total=n, desc="RSA", unit="particle", disable=not progress, leave=False) as bar:
        while placed < n and tried < max_attempts:
            s = int(rng.integers(2**31 - 1))
            new, t = _rsa_kernel(centres, radii, placed, head, nxt, ncell, csize, box, ndim, periodic, s,
                                 min(chunk, max_attempts - tried))
            bar.update(new - placed)
            placed, tried = new, tried + t
    if placed < n:
        vol = np.prod(box[:ndim])
        unit = math.pi * radii[:placed] ** 2 if ndim == 2 else 4 / 3 * math.pi * radii[:placed] ** 3
        reached = float(unit.sum() / vol)
        jam, src = RSA_JAMMING[ndim]
        raise ConvergenceError(
            f"random sequential addition placed {placed} of {n} particles in {tried} trials: the exclusion "
            f"zones fill {reached:.4f} of the cell, close to the RSA jamming limit {jam} ({src}); "
            "lower the fraction or the exclusion distance, or raise max_attempts",
            history=[placed],
        )
    return centres


def pseudocube_half_size(diagonal_nm, exponent: float, ndim: int = 3) -> float:
    """Half edge a of a superball |x|^m + |y|^m + |z|^m ≤ a^m of large diagonal D.

    The diagonal runs from corner to corner through the centre: D = 2 a √d · d^(−1/m)
    (d = 2 or 3), i.e. D = a·2√3 for an exact cube (m = ∞).
    """
    inv = 0.0 if math.isinf(exponent) else 1.0 / exponent
    return float(diagonal_nm) / (2 * math.sqrt(ndim) * ndim ** (-inv))


def unit_grain_geometry(shape: str, exponent: float, ndim: int) -> tuple[float, float]:
    """Volume (area in 2-D) and circumscribed radius of a grain of unit size.

    ``"sphere"``: the size is the radius (V = 4π/3, π in 2-D; R = 1); ``"pseudocube"``: the
    size is the large diagonal (a superball of :func:`pseudocube_half_size`; R = 1/2).
    """
    if shape == "sphere":
        return (math.pi if ndim == 2 else 4 / 3 * math.pi), 1.0
    a = pseudocube_half_size(1.0, exponent, ndim)
    return float(superball_volume(np.array([a, a, a]), exponent, ndim)), 0.5


def grain_geometry(rng, sizes_nm, shape: str, exponent: float, ndim: int):
    """Rotations, half sizes, shape codes and exponents of ``len(sizes_nm)`` grains.

    ``"sphere"``: ``sizes_nm`` are radii, no rotation; ``"pseudocube"``: large diagonals,
    uniformly random orientations drawn from ``rng`` (an exact cube for ``exponent = inf``).
    Returns ``(rotations (n, 3, 3), half_sizes (n, 3), kinds (n,), exponents (n,))`` as
    :class:`~nmmm.microstructure.particles.ParticleSet` takes them.
    """
    sizes = np.asarray(sizes_nm, float)
    n = sizes.size
    half = np.empty((n, 3))
    if shape == "sphere":
        rot = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
        half[:] = sizes[:, None]
        return rot, half, np.full(n, SHAPES["superball"]), np.full(n, 2.0)
    rot = random_rotations(rng, n, ndim)
    half[:] = (sizes * pseudocube_half_size(1.0, exponent, ndim))[:, None]
    kinds = np.full(n, SHAPES["box"] if math.isinf(exponent) else SHAPES["superball"])
    return rot, half, kinds, np.full(n, float(exponent))


def max_hardcore_fraction(particle_volume_nm, exclusion_radius_nm, ndim: int = 3) -> float:
    """The RSA limit of the particle fraction: jamming × V_particle / V_exclusion."""
    jam = RSA_JAMMING[ndim][0]
    vex = math.pi * exclusion_radius_nm**2 if ndim == 2 else 4 / 3 * math.pi * exclusion_radius_nm**3
    return jam * float(particle_volume_nm) / vex


def hardcore_particles(
    box_nm,
    shape: str = "sphere",
    size_nm=50.0,
    fraction: float = 0.1,
    exclusion_nm: float = 0.0,
    exponent: float = 8.0,
    seed=None,
    periodic: bool = True,
    max_attempts: int | None = None,
    progress: bool = False,
    label: int = 1,
    phase: str = "particles",
) -> ParticleSet:
    """A hard-core (RSA) model with exclusion zones, as an analytic particle list.

    Parameters
    ----------
    box_nm : tuple
        Cell size (nm), 2 or 3 entries.
    shape : {"sphere", "pseudocube", "cube"}
        sphere: ``size_nm`` is the radius (discs in 2-D); pseudocube/cube: ``size_nm`` is
        the large diagonal (corner to corner), orientations uniformly random; pseudo-cubes
        are superballs of ``exponent`` (8 by default; ∞ = exact cube).
    size_nm : float or SizeDistribution
    fraction : float
        Target volume (area) fraction of the particles.
    exclusion_nm : float
        Minimum binder gap between the circumscribed spheres of two particles (nm); the
        exclusion radius is R_circ + exclusion_nm / 2.

    Raises
    ------
    InvalidInputError
        If the target is beyond the RSA jamming limit for these sizes (message names it).
    ConvergenceError
        If it is within the limit but too close to it for ``max_attempts``.
    """
    box = as_box_nm(box_nm)
    ndim = len(box)
    p = float(check_fraction(fraction, "fraction"))
    if not math.isfinite(exclusion_nm) or exclusion_nm < 0:
        raise InvalidInputError(f"exclusion_nm must be >= 0 (nm), got {exclusion_nm!r}")
    dist = as_size_distribution(size_nm, "size_nm")
    if shape == "cube":
        shape, exponent = "pseudocube", math.inf
    if shape not in ("sphere", "pseudocube"):
        raise InvalidInputError(f"shape must be 'sphere', 'pseudocube' or 'cube', got {shape!r}")
    if shape == "pseudocube" and not (exponent >= 2):
        raise InvalidInputError(f"pseudo-cube exponent must be >= 2 (inf = cube), got {exponent!r}")

    vol_per_size, circ_per_size = unit_grain_geometry(shape, exponent, ndim)
    ebox = float(np.prod(box))
    jam, src = RSA_JAMMING[ndim]
    # monodisperse reachability (the limit is higher for polydisperse packings)
    if dist.kind == "constant":
        s = dist.mean_nm
        pmax = max_hardcore_fraction(vol_per_size * s**ndim, circ_per_size * s + exclusion_nm / 2, ndim)
        if p >= pmax:
            what = "spheres in 3-D" if ndim == 3 else "discs in 2-D"
            raise InvalidInputError(
                f"a hard-core fraction of {p:.4g} is beyond reach: random sequential addition of the exclusion "
                f"zones jams at {jam} for {what} ({src}), which caps the particle fraction at {pmax:.4g} for this "
                f"shape and exclusion distance; use fraction < {0.95 * pmax:.3g} (or a smaller exclusion_nm, or "
                "a Boolean model if overlaps are allowed)"
            )
    target_vol = p * ebox
    rng = np.random.default_rng(seed)
    mean_v = vol_per_size * dist.moment(ndim)
    n_est = int(target_vol / mean_v) + 1
    if n_est > 20_000_000:
        raise InvalidInputError(f"about {n_est} particles: too many for this cell; use a smaller cell or larger particles")
    if dist.kind == "constant":
        n = int(round(target_vol / mean_v))
        sizes = np.full(n, dist.mean_nm)
    else:
        sizes = dist.sample(rng, 2 * n_est + 100)
        cum = np.cumsum(vol_per_size * sizes**ndim)
        n = int(np.searchsorted(cum, target_vol) + 1)
        if n > 1 and abs(cum[n - 2] - target_vol) < abs(cum[n - 1] - target_vol):
            n -= 1
        sizes = np.sort(sizes[:n])[::-1]  # large first: packs further before jamming
    rex = circ_per_size * sizes + exclusion_nm / 2
    if np.any(2 * rex >= np.array(box)[:, None].min()) and n:
        raise InvalidInputError("particles (with exclusion zone) larger than the cell; enlarge the cell")
    centres = rsa_centres(box, rex, seed=rng, periodic=periodic, max_attempts=max_attempts, progress=progress)
    rot, half, kinds, expo = grain_geometry(rng, sizes, shape, exponent, ndim)
    params = {
        "model": f"hardcore_{shape}s",
        "shape": shape,
        "size_nm": dist.to_dict(),
        "size_meaning": "radius" if shape == "sphere" else "large diagonal",
        "target_fraction": p,
        "exclusion_nm": float(exclusion_nm),
        "exclusion_radius_nm": float(rex.mean() if n else circ_per_size * dist.mean_nm + exclusion_nm / 2),
        "seed": seed_param(seed),
        "box_nm": list(box),
    }
    if shape == "pseudocube":
        params["exponent"] = float(exponent)
    return ParticleSet(centres, rot, half, kinds, expo, np.full(n, int(label)), box, periodic,
                       {0: "matrix", int(label): phase}, params)


def hardcore_spheres(shape, voxel_nm, radius_nm, fraction, exclusion_nm=0.0, seed=None, periodic=True,
                     max_attempts=None, progress=False, phase="particles") -> Microstructure:
    """Voxelised hard-core (RSA) spheres of ``radius_nm`` (discs on a 2-D grid) at ``fraction``.

    >>> m = hardcore_spheres((64, 64, 64), 1.0, 4.0, 0.1, seed=0)
    >>> abs(m.volume_fraction() - 0.1) < 0.01
    True
    """
    box = cell_box_nm(shape, voxel_nm)
    radius = as_size_distribution(radius_nm, "radius_nm")
    ps = hardcore_particles(box, "sphere", radius, fraction, exclusion_nm, seed=seed, periodic=periodic,
                            max_attempts=max_attempts, progress=progress, phase=phase)
    return ps.rasterize(shape=shape)


def hardcore_pseudocubes(shape, voxel_nm, diagonal_nm=250.0, fraction=0.05, exponent=8.0, exclusion_nm=0.0,
                         seed=None, periodic=True, max_attempts=None, progress=False,
                         phase="hematite") -> Microstructure:
    """Voxelised hard-core pseudo-cubes with random orientations (hematite: 250 nm diagonal, 5-10 %)."""
    box = cell_box_nm(shape, voxel_nm)
    diagonal = as_size_distribution(diagonal_nm, "diagonal_nm")
    ps = hardcore_particles(box, "pseudocube", diagonal, fraction, exclusion_nm, exponent=exponent, seed=seed,
                            periodic=periodic, max_attempts=max_attempts, progress=progress, phase=phase)
    return ps.rasterize(shape=shape)
