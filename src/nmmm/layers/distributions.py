"""Pigment size distributions, equivalent spheres, dependent scattering and the optical
coefficients of a pigment per unit volume.

Public functions and classes
----------------------------
- :class:`SizeDistribution` — number-weighted diameter nodes (nm) of a polydisperse pigment.
- :func:`monodisperse`, :func:`lognormal`, :func:`histogram` — build one.
- :func:`equivalent_sphere_diameter` — the sphere standing for a cube (pseudo-cube), a rod
  (cylinder), a spheroid or a rhombohedron; ``method`` = ``"volume"`` (equal volume, the default),
  ``"surface"`` (equal area) or ``"volume_to_surface"`` (equal V/S, Grenfell & Warren 1999).
  Registry: :data:`EQUIVALENT_SPHERE_METHODS`.
- :func:`percus_yevick_structure_factor` — hard-sphere S(q) in the Percus–Yevick
  approximation (Wertheim 1963; closed form of Kinning & Thomas 1984).
- :func:`pigment_optics` — absorption and scattering cross sections per unit pigment volume
  and the asymmetry parameter, averaged over a size distribution, optionally with the
  dependent-scattering (structure factor) correction. Returns :class:`PigmentOptics`.

Cross sections per unit volume: for a number distribution n(D),
c_abs = ∫ C_abs(D) n(D) dD / ∫ V(D) n(D) dD (nm⁻¹), likewise c_sca; g is weighted by
C_sca. For a pigment at volume fraction f the film's coefficients are μ_a = f c_abs,
μ_s = f c_sca (independent scattering). With a structure factor S(q) for the particle
positions (dense pigments), the differential cross section is weighted by S(q),
q = 2k sin(θ/2), k = 2π n_medium/λ, before integration over angles (Ishimaru & Kuga 1982;
Tsang & Kong 1980). For polydisperse pigments the monodisperse S(q) of the hard-sphere
diameter (⟨D³⟩)^{1/3} is applied to every size (a decoupling approximation).

Equivalent spheres. Light scattering by a random orientation of compact non-spherical
particles is represented here by spheres. The equal-volume sphere is the usual choice
(Mishchenko, Travis & Lacis 2002, §10); Grenfell & Warren (1999) showed that spheres with
the particle's volume-to-surface ratio (D = 6V/S), in the number that keeps the total volume,
reproduce absorption and extinction of non-spherical ice better — since nmmm works per unit
pigment volume, that number adjustment is automatic. A pseudo-cube of "large diagonal"
δ (the body diagonal, as for the hematite pseudo-cubes of Manickavasagam et al. 2004) has
edge a = δ/√3.

Rhombohedra. A rhombohedron of edge a whose three edges at a vertex make the angle α with
each other (six congruent rhombic faces) has V = a³ √(1 − 3cos²α + 2cos³α) (the volume of
the parallelepiped spanned by three unit-angle vectors, |det| of their Gram matrix to the
½) and S = 6a² sin α; α = 90° is the cube, 0 < α < 120° (at 120° it flattens).
Hematite's "pseudo-cubes" are rhombohedra bounded by {01-12} faces; with the hexagonal
cell a = 5.0356 Å, c = 13.7489 Å (Blake et al. 1966) the edges of the {01-12} rhombohedron
meet at α = 85.71° (interfacial angle 86.0°) — :data:`HEMATITE_RHOMBOHEDRON_ANGLE_DEG`.

References
----------
- M. I. Mishchenko, L. D. Travis, A. A. Lacis, *Scattering, Absorption, and Emission of
  Light by Small Particles*, Cambridge University Press (2002).
- T. C. Grenfell, S. G. Warren, "Representation of a nonspherical ice particle by a
  collection of independent spheres for scattering and absorption of radiation",
  J. Geophys. Res. 104(D24), 31697 (1999). doi:10.1029/1999JD900496
- M. S. Wertheim, "Exact solution of the Percus–Yevick integral equation for hard spheres",
  Phys. Rev. Lett. 10, 321 (1963). doi:10.1103/PhysRevLett.10.321
- D. J. Kinning, E. L. Thomas, "Hard-sphere interactions between spherical domains in
  diblock copolymers", Macromolecules 17, 1712 (1984), eqs. (5)–(7). doi:10.1021/ma00139a013
- A. Ishimaru, Y. Kuga, "Attenuation constant of a coherent field in a dense distribution of
  particles", J. Opt. Soc. Am. 72, 1317 (1982). doi:10.1364/JOSA.72.001317
- L. Tsang, J. A. Kong, "Multiple scattering of electromagnetic waves by random
  distributions of discrete scatterers with coherent potential and quantum mechanical
  formalism", J. Appl. Phys. 51, 3465 (1980). doi:10.1063/1.328200
- S. Manickavasagam, M. P. Mengüç, M. Saltiel, J. Colloid Interface Sci. 280, 417 (2004)
  (hematite particle shape).
- R. L. Blake, R. E. Hessevick, T. Zoltai, L. W. Finger, "Refinement of the hematite
  structure", Am. Mineral. 51, 123 (1966) (cell a = 5.0356 Å, c = 13.7489 Å).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from nmmm.errors import InvalidInputError
from nmmm.layers.fresnel_equations import medium_nk
from nmmm.layers.mie_scattering import mie
from nmmm.spectra import as_wavelength_nm, check_finite, check_fraction, check_positive

__all__ = [
    "SizeDistribution",
    "monodisperse",
    "lognormal",
    "histogram",
    "EQUIVALENT_SPHERE_METHODS",
    "HEMATITE_RHOMBOHEDRON_ANGLE_DEG",
    "rhombohedron_volume_surface",
    "equivalent_sphere_diameter",
    "percus_yevick_structure_factor",
    "PigmentOptics",
    "pigment_optics",
]


@dataclass(frozen=True)
class SizeDistribution:
    """Number-weighted diameters: ``number_weights`` sum to 1 over ``diameter_nm`` nodes."""

    diameter_nm: np.ndarray
    number_weights: np.ndarray
    name: str = "distribution"

    def __post_init__(self):
        d = check_positive(np.atleast_1d(np.asarray(self.diameter_nm, dtype=float)), "diameter_nm")
        w = check_finite(np.atleast_1d(np.asarray(self.number_weights, dtype=float)), "number_weights")
        if d.ndim != 1 or d.shape != w.shape:
            raise InvalidInputError("diameter_nm and number_weights must be 1-D arrays of equal length")
        if np.any(w < 0) or w.sum() <= 0:
            raise InvalidInputError("number_weights must be >= 0 with a positive sum")
        object.__setattr__(self, "diameter_nm", d)
        object.__setattr__(self, "number_weights", w / w.sum())

    def moment(self, k: float) -> float:
        """⟨D^k⟩ (nm^k) of the number distribution."""
        return float(np.sum(self.number_weights * self.diameter_nm**k))

    @property
    def mean_volume_nm3(self) -> float:
        """⟨V⟩ = π⟨D³⟩/6."""
        return np.pi / 6 * self.moment(3)

    @property
    def volume_weights(self) -> np.ndarray:
        """Volume fraction of the pigment carried by each node."""
        v = self.number_weights * self.diameter_nm**3
        return v / v.sum()

    def scaled(self, factor: float, name: str | None = None) -> "SizeDistribution":
        """The same shape of distribution with every diameter multiplied by ``factor``."""
        return SizeDistribution(self.diameter_nm * float(factor), self.number_weights, name or self.name)


def monodisperse(diameter_nm: float) -> SizeDistribution:
    """A single size."""
    return SizeDistribution(np.array([float(diameter_nm)]), np.array([1.0]), f"D = {float(diameter_nm):g} nm")


def lognormal(median_nm: float, geometric_std: float, n_nodes: int = 48, span: float = 5.0) -> SizeDistribution:
    """Log-normal number distribution of diameters.

    ln D is normal with mean ln(``median_nm``) and standard deviation ln(``geometric_std``)
    (σ_g ≥ 1; σ_g = 1 is monodisperse). Nodes are evenly spaced in ln D over ±``span`` σ,
    weights the density times the node spacing (midpoint rule), so that the volume-weighted
    moments, shifted by 3σ² in ln D, are kept. ⟨D^k⟩ = D_g^k exp(k² σ²/2).
    """
    d_g = float(check_positive(median_nm, "median_nm"))
    s_g = float(check_finite(geometric_std, "geometric_std"))
    if s_g < 1:
        raise InvalidInputError(f"geometric_std must be >= 1 (1 = monodisperse), got {s_g}")
    if s_g == 1 or n_nodes < 2:
        return monodisperse(d_g)
    sigma = np.log(s_g)
    t = np.linspace(-span, span, int(n_nodes))
    w = np.exp(-0.5 * t**2)
    return SizeDistribution(d_g * np.exp(sigma * t), w, f"log-normal D_g = {d_g:g} nm, σ_g = {s_g:g}")


def histogram(bin_edges_nm: ArrayLike, counts: ArrayLike, nodes_per_bin: int = 4) -> SizeDistribution:
    """A user histogram of particle counts (number distribution) over diameter bins.

    The count of each bin is spread evenly over ``nodes_per_bin`` nodes inside it
    (a uniform density within the bin).
    """
    edges = check_positive(np.asarray(bin_edges_nm, dtype=float), "bin_edges_nm")
    c = check_finite(np.asarray(counts, dtype=float), "counts")
    if edges.ndim != 1 or c.ndim != 1 or edges.size != c.size + 1:
        raise InvalidInputError("need len(bin_edges_nm) == len(counts) + 1 (1-D)")
    if np.any(np.diff(edges) <= 0):
        raise InvalidInputError("bin_edges_nm must increase strictly")
    if np.any(c < 0):
        raise InvalidInputError("counts must be >= 0")
    k = max(1, int(nodes_per_bin))
    frac = (np.arange(k) + 0.5) / k
    d = (edges[:-1, None] + np.diff(edges)[:, None] * frac[None, :]).ravel()
    w = np.repeat(c / k, k)
    keep = w > 0
    return SizeDistribution(d[keep], w[keep], "histogram")


# --------------------------------------------------------------------------------------
# equivalent spheres
# --------------------------------------------------------------------------------------
#: Angle (deg) between the edges of hematite's {01-12} ("pseudo-cube") rhombohedron, from
#: the hexagonal cell a = 5.0356 Å, c = 13.7489 Å of Blake et al. (1966).
HEMATITE_RHOMBOHEDRON_ANGLE_DEG = 85.7


def rhombohedron_volume_surface(edge_nm, angle_deg) -> tuple[float, float]:
    """Volume (nm³) and surface area (nm²) of a rhombohedron.

    V = a³ √(1 − 3cos²α + 2cos³α), S = 6a² sin α for edge a and rhombohedral angle α
    (the angle between any two edges at a vertex), 0 < α < 120°; α = 90° is the cube.
    """
    a = float(check_positive(edge_nm, "edge_nm"))
    alpha = float(check_finite(angle_deg, "angle_deg"))
    if not 0.0 < alpha < 120.0:
        raise InvalidInputError(f"angle_deg of a rhombohedron must be in (0, 120) degrees (90 = cube), got {alpha:g}")
    c = np.cos(np.radians(alpha))
    return a**3 * np.sqrt(1 - 3 * c * c + 2 * c**3), 6 * a * a * np.sin(np.radians(alpha))


def _shape_volume_surface(shape: str, dims: dict) -> tuple[float, float]:
    shape = shape.lower()
    if shape in ("cube", "pseudo-cube", "pseudocube"):
        if "edge_nm" in dims:
            a = float(check_positive(dims["edge_nm"], "edge_nm"))
        elif "body_diagonal_nm" in dims:
            a = float(check_positive(dims["body_diagonal_nm"], "body_diagonal_nm")) / np.sqrt(3)
        elif "face_diagonal_nm" in dims:
            a = float(check_positive(dims["face_diagonal_nm"], "face_diagonal_nm")) / np.sqrt(2)
        else:
            raise InvalidInputError("a cube needs edge_nm, body_diagonal_nm or face_diagonal_nm")
        return a**3, 6 * a**2
    if shape in ("rod", "cylinder"):
        try:
            L = float(check_positive(dims["length_nm"], "length_nm"))
            D = float(check_positive(dims["diameter_nm"], "diameter_nm"))
        except KeyError:
            raise InvalidInputError("a rod needs length_nm and diameter_nm") from None
        return np.pi * D**2 / 4 * L, np.pi * D * L + np.pi * D**2 / 2
    if shape == "spheroid":
        try:
            c = float(check_positive(dims["polar_diameter_nm"], "polar_diameter_nm")) / 2
            a = float(check_positive(dims["equatorial_diameter_nm"], "equatorial_diameter_nm")) / 2
        except KeyError:
            raise InvalidInputError("a spheroid needs polar_diameter_nm and equatorial_diameter_nm") from None
        V = 4 / 3 * np.pi * a * a * c
        if np.isclose(a, c):
            S = 4 * np.pi * a * a
        elif c < a:  # oblate
            e = np.sqrt(1 - c * c / (a * a))
            S = 2 * np.pi * a * a * (1 + (1 - e * e) / e * np.arctanh(e))
        else:  # prolate
            e = np.sqrt(1 - a * a / (c * c))
            S = 2 * np.pi * a * a * (1 + c / (a * e) * np.arcsin(e))
        return V, S
    if shape == "rhombohedron":
        missing = [k for k in ("edge_nm", "angle_deg") if k not in dims]
        if missing:
            raise InvalidInputError(f"a rhombohedron needs edge_nm and angle_deg (hematite: "
                                    f"{HEMATITE_RHOMBOHEDRON_ANGLE_DEG}); missing {missing}")
        return rhombohedron_volume_surface(dims["edge_nm"], dims["angle_deg"])
    if shape == "sphere":
        D = float(check_positive(dims.get("diameter_nm", np.nan), "diameter_nm"))
        return np.pi * D**3 / 6, np.pi * D**2
    raise InvalidInputError(f"unknown shape {shape!r}; use 'cube', 'rod', 'spheroid', 'rhombohedron' or 'sphere'")


def _eq_volume(V, S):
    return (6 * V / np.pi) ** (1 / 3)


def _eq_surface(V, S):
    return np.sqrt(S / np.pi)


def _eq_volume_to_surface(V, S):
    return 6 * V / S


#: Equivalent-sphere definitions: name -> function of (volume, surface) giving D (nm).
EQUIVALENT_SPHERE_METHODS = {
    "volume": _eq_volume,
    "surface": _eq_surface,
    "volume_to_surface": _eq_volume_to_surface,
}


def equivalent_sphere_diameter(shape: str, method: str = "volume", **dims: float) -> float:
    """Diameter (nm) of the sphere standing for a non-spherical particle.

    Parameters
    ----------
    shape : {"cube", "rod", "spheroid", "rhombohedron", "sphere"}
        ``cube`` (pseudo-cube): ``edge_nm``, ``body_diagonal_nm`` (the "large diagonal") or
        ``face_diagonal_nm``; ``rod`` (cylinder): ``length_nm``, ``diameter_nm``;
        ``spheroid``: ``polar_diameter_nm``, ``equatorial_diameter_nm``;
        ``rhombohedron``: ``edge_nm``, ``angle_deg`` (rhombohedral angle, hematite
        :data:`HEMATITE_RHOMBOHEDRON_ANGLE_DEG`; see :func:`rhombohedron_volume_surface`).
    method : {"volume", "surface", "volume_to_surface"}
        Equal volume (default; Mishchenko et al. 2002), equal surface area, or equal
        volume-to-surface ratio D = 6V/S (Grenfell & Warren 1999).

    Examples
    --------
    A cube of edge a has the equal-volume sphere D = a (6/π)^{1/3}:

    >>> round(equivalent_sphere_diameter("cube", edge_nm=100.0), 3)
    124.07
    >>> round(equivalent_sphere_diameter("cube", "volume_to_surface", edge_nm=100.0), 3)
    100.0
    """
    try:
        f = EQUIVALENT_SPHERE_METHODS[method]
    except KeyError:
        raise InvalidInputError(f"unknown method {method!r}; choose from {sorted(EQUIVALENT_SPHERE_METHODS)}") from None
    V, S = _shape_volume_surface(shape, dims)
    return float(f(V, S))


# --------------------------------------------------------------------------------------
# structure factor
# --------------------------------------------------------------------------------------
def percus_yevick_structure_factor(q_times_diameter: ArrayLike, volume_fraction: ArrayLike) -> np.ndarray:
    """Hard-sphere structure factor S(q) in the Percus–Yevick approximation.

    S(q) = 1 / (1 + 24 f G(A)/A), A = q d (Kinning & Thomas 1984, eqs. 5–7, after
    Wertheim 1963), with α = (1+2f)²/(1−f)⁴, β = −6f(1+f/2)²/(1−f)⁴, γ = f α/2.
    At A → 0 it tends to the PY compressibility (1−f)⁴/(1+2f)²; a Taylor series is used
    for A < 0.05 to avoid cancellation.
    """
    A = np.abs(check_finite(q_times_diameter, "q_times_diameter").astype(float))
    f = check_fraction(volume_fraction, "volume_fraction")
    if np.any(f >= 0.64):
        raise InvalidInputError("volume_fraction must be below random close packing (0.64) for hard spheres")
    A, f = np.broadcast_arrays(A, f)
    alpha = (1 + 2 * f) ** 2 / (1 - f) ** 4
    beta = -6 * f * (1 + f / 2) ** 2 / (1 - f) ** 4
    gamma = f * alpha / 2
    small = A < 0.05
    As = np.where(small, 1.0, A)
    s, c = np.sin(As), np.cos(As)
    G = (
        alpha / As**2 * (s - As * c)
        + beta / As**3 * (2 * As * s + (2 - As**2) * c - 2)
        + gamma / As**5 * (-(As**4) * c + 4 * ((3 * As**2 - 6) * c + (As**3 - 6 * As) * s + 6))
    )
    # series of G(A)/A: alpha/3 + beta/4 + gamma/6 - A^2 (alpha/30 + beta/36 + gamma/48)
    GoverA_small = alpha / 3 + beta / 4 + gamma / 6 - A**2 * (alpha / 30 + beta / 36 + gamma / 48)
    GoverA = np.where(small, GoverA_small, G / As)
    return 1.0 / (1.0 + 24 * f * GoverA)


# --------------------------------------------------------------------------------------
# pigment optics per unit volume
# --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PigmentOptics:
    """Optical cross sections of a pigment per unit pigment volume (nm⁻¹) over wavelength.

    For a film with pigment volume fraction f: μ_a = f·``absorption_per_nm`` (plus the binder's
    own absorption), μ_s = f·``scattering_per_nm`` (independent scattering; when the pigment
    was computed with a structure factor, these already include it for that fraction).
    """

    wavelength_nm: np.ndarray
    absorption_per_nm: np.ndarray
    scattering_per_nm: np.ndarray
    g: np.ndarray
    backscattering_per_nm: np.ndarray
    distribution: SizeDistribution
    structure_factor_fraction: float | None = None

    @property
    def albedo(self) -> np.ndarray:
        """Single-scattering albedo of the pigment."""
        return self.scattering_per_nm / (self.scattering_per_nm + self.absorption_per_nm)


def pigment_optics(
    n_particle: ArrayLike,
    n_medium: ArrayLike,
    distribution: SizeDistribution,
    wavelength_nm: ArrayLike,
    dependent_scattering_fraction: float | None = None,
    n_angles: int = 96,
) -> PigmentOptics:
    """Cross sections per unit pigment volume, averaged over a size distribution.

    Parameters
    ----------
    n_particle : complex array_like (over wavelength) or Material
        Pigment index n + ik.
    n_medium : float, array_like or Material
        Real binder index (an absorbing binder must be passed as its real part; add the
        binder's absorption to μ_a separately).
    distribution : SizeDistribution
        Equivalent-sphere diameters (see :func:`equivalent_sphere_diameter`).
    wavelength_nm : array_like (1-D)
    dependent_scattering_fraction : float, optional
        If given, the pigment volume fraction used for the Percus–Yevick structure-factor
        correction of the scattering coefficient and of g.
    n_angles : int
        Gauss–Legendre nodes in cos θ for the structure-factor integral.
    """
    w = as_wavelength_nm(np.atleast_1d(wavelength_nm))
    if w.ndim != 1:
        raise InvalidInputError("wavelength_nm must be 1-D")
    nk = np.broadcast_to(medium_nk(n_particle, w, "n_particle"), w.shape)
    nm = n_medium.nk(w) if hasattr(n_medium, "nk") else np.broadcast_to(np.asarray(n_medium), w.shape)
    d = distribution.diameter_nm
    wn = distribution.number_weights
    vol = np.pi / 6 * d**3
    mean_v = float(np.sum(wn * vol))
    geo = np.pi * d**2 / 4

    if dependent_scattering_fraction is None:
        r = mie(nk[:, None], nm[:, None], d[None, :], w[:, None])
        cabs = r.qabs * geo
        csca = r.qsca * geo
        gcs = r.g * csca
        cback = r.qback * geo
        f_sf = None
    else:
        f_sf = float(check_fraction(dependent_scattering_fraction, "dependent_scattering_fraction"))
        mu, wq = np.polynomial.legendre.leggauss(int(n_angles))
        ang = np.degrees(np.arccos(mu))
        r = mie(nk[:, None], nm[:, None], d[None, :], w[:, None], angles_deg=ang)
        dsig = r.differential_cross_section_nm2()  # (W, D, A)
        k = 2 * np.pi * np.real(nm) / w
        q = 2 * k[:, None] * np.sqrt((1 - mu[None, :]) / 2)  # (W, A)
        d_hs = distribution.moment(3) ** (1 / 3)
        S = percus_yevick_structure_factor(q * d_hs, f_sf)[:, None, :]
        csca = 2 * np.pi * np.sum(dsig * S * wq, axis=-1)
        gcs = 2 * np.pi * np.sum(dsig * S * wq * mu, axis=-1)
        cabs = r.qabs * geo
        cback = r.qback * geo * S[..., np.argmin(mu)]
    c_abs = np.sum(cabs * wn, axis=1) / mean_v
    c_sca = np.sum(csca * wn, axis=1) / mean_v
    g = np.sum(gcs * wn, axis=1) / np.maximum(np.sum(csca * wn, axis=1), 1e-300)
    c_back = np.sum(cback * wn, axis=1) / mean_v
    return PigmentOptics(w, c_abs, c_sca, g, c_back, distribution, f_sf)
