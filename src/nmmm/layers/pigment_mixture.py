"""Films with any number of particulate components: pigments, whites, blacks, extenders and
air voids in one binder, combined into the transport coefficients of the film.

Public functions and classes
----------------------------
- :class:`Component` — one particulate component: compound, size distribution, volume
  fraction of the dry film (frozen dataclass).
- :func:`mixture_optics` — μ_a, μ_s (nm⁻¹), the phase function's Legendre moments and g of
  the film over wavelength (:class:`MixtureOptics`).
- :func:`percus_yevick_mixture` — partial structure factors S_ij(q) of a hard-sphere
  mixture in the Percus–Yevick approximation (Lebowitz 1964; Ashcroft & Langreth 1967), by
  Baxter's (1970) factorisation.
- :func:`void_fraction` — air in a film above the critical PVC.
- :func:`check_cpvc` — a CPVC validated against the densest packing of spheres (:data:`MAX_PACKING`).

Model
-----
Independent scattering (Bohren & Huffman 1983, §3.4): absorption and scattering coefficients
add over the components (Duncan's additivity of K and S, Duncan 1949, is the KM form of it),
and the phase function is the scattering-weighted mixture

    μ_a = Σ_i f_i c_abs,i + f_binder 4π k_binder/λ ,  dμ_s/dΩ = Σ_i ρ_i ⟨dC_sca,i/dΩ⟩ ,

ρ_i = f_i / ⟨v⟩_i the number density of component i (Mie in the real binder index, as
:mod:`nmmm.layers.paint`). With ``dependent_scattering`` the mixture's interference between
particles is added with the partial structure factors (decoupling approximation for the
sizes inside one component, Kotlarchyk & Chen 1983):

    dμ_s/dΩ += Σ_ij √(ρ_i ρ_j) Re[⟨S1_i⟩⟨S1_j⟩* + ⟨S2_i⟩⟨S2_j⟩*] / (2k²) · (S_ij(q) − δ_ij)

each component a hard sphere of diameter ⟨D³⟩^{1/3}. For one monodisperse component this is
the Percus–Yevick correction of :func:`nmmm.layers.distributions.pigment_optics`.

Above the critical pigment volume concentration (CPVC) the binder no longer fills the space
between the packed particles: the pigments stay packed at the CPVC and the rest is air.
Per unit film volume, pigment = CPVC, binder = (1 − PVC)·CPVC/PVC, air = 1 − CPVC/PVC
(Asbeck & Van Loo 1949's picture). The voids are modelled as n = 1 spheres of the volume-mean
pigment size, scattering independently (no structure factor) — a crude model: real voids are
irregular and connected, and the film's hiding above CPVC ("dry hiding") depends on their
size spectrum, which is not known from the recipe. The CPVC default 0.64 is random close
packing of equal spheres (Scott & Kilgour 1969); real paints have 0.35–0.65 (from the oil
absorption, ISO 787-5): give it.

References
----------
- J. L. Lebowitz, "Exact solution of generalized Percus–Yevick equation for a mixture of hard
  spheres", Phys. Rev. 133, A895 (1964). doi:10.1103/PhysRev.133.A895
- N. W. Ashcroft, D. C. Langreth, "Structure of binary liquid mixtures. I", Phys. Rev. 156,
  685 (1967). doi:10.1103/PhysRev.156.685
- R. J. Baxter, "Ornstein–Zernike relation and Percus–Yevick approximation for fluid
  mixtures", J. Chem. Phys. 52, 4559 (1970). doi:10.1063/1.1673684
- M. Kotlarchyk, S.-H. Chen, J. Chem. Phys. 79, 2461 (1983). doi:10.1063/1.446055
- D. R. Duncan, "The colour of pigment mixtures", Proc. Phys. Soc. 52, 390 (1940); J. Oil
  Colour Chem. Assoc. 32, 296 (1949).
- W. K. Asbeck, M. Van Loo, "Critical pigment volume relationships", Ind. Eng. Chem. 41, 1470
  (1949). doi:10.1021/ie50475a042
- G. D. Scott, D. M. Kilgour, J. Phys. D 2, 863 (1969) (random close packing 0.64).
- C. F. Bohren, D. R. Huffman, *Absorption and Scattering of Light by Small Particles*, Wiley
  (1983).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from nmmm.errors import InvalidInputError
from nmmm.layers.distributions import SizeDistribution, monodisperse
from nmmm.layers.fresnel_equations import medium_nk
from nmmm.spectra import as_wavelength_nm, check_fraction

__all__ = ["Component", "MixtureOptics", "DEFAULT_CPVC", "MAX_PACKING", "check_cpvc", "mixture_optics", "percus_yevick_mixture",
           "void_fraction"]

#: random close packing of equal spheres (Scott & Kilgour 1969): the CPVC used when none is given
DEFAULT_CPVC = 0.64
#: the densest packing of equal spheres, π/√18 (Kepler; Hales 2005): no CPVC lies above it
MAX_PACKING = float(np.pi / np.sqrt(18.0))


@dataclass(frozen=True)
class Component:
    """One particulate component of a film.

    compound : Material or complex — its index n + ik.
    distribution : SizeDistribution — equivalent-sphere diameters (nm).
    fraction : float — volume fraction of the dry film (pigment + binder), in [0, 1].
    name : str — a label (e.g. "rutile").
    """

    compound: object
    distribution: SizeDistribution
    fraction: float
    name: str = ""

    def __post_init__(self):
        check_fraction(self.fraction, f"fraction of component {self.name!r}")
        if not isinstance(self.distribution, SizeDistribution):
            raise InvalidInputError(f"component {self.name!r}: distribution must be a SizeDistribution")


@dataclass(frozen=True)
class MixtureOptics:
    """Transport coefficients of a multi-component film over wavelength (nm⁻¹)."""

    wavelength_nm: np.ndarray
    mu_a_per_nm: np.ndarray
    mu_s_per_nm: np.ndarray
    phase_moments: np.ndarray  # (W, L), χ_0 = 1
    n_binder: np.ndarray
    binder_absorption_per_nm: np.ndarray
    pvc: float
    void_fraction: float
    #: per component: (name, μ_a, μ_s) contributions (nm⁻¹), voids last when present
    contributions: tuple = ()

    @property
    def g(self) -> np.ndarray:
        return self.phase_moments[:, 1]

    @property
    def albedo(self) -> np.ndarray:
        mu_t = self.mu_a_per_nm + self.mu_s_per_nm
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.clip(np.where(mu_t > 0, self.mu_s_per_nm / mu_t, 0.0), 0.0, 1.0)


def check_cpvc(cpvc, name: str = "cpvc") -> float:
    """A critical PVC in (0, :data:`MAX_PACKING`]: pigment particles cannot fill more of a film
    than the densest packing of spheres (0.7405); real paints have 0.35–0.65."""
    try:
        c = float(cpvc)
    except (TypeError, ValueError):
        c = float("nan")
    if not 0 < c <= MAX_PACKING + 1e-12:
        raise InvalidInputError(f"{name} = {cpvc!r} is not a packing fraction: it must lie in (0, {MAX_PACKING:.4f}] "
                                "(the densest packing of spheres; real paints have 0.35-0.65, from the oil absorption, "
                                "ISO 787-5)")
    return c


def void_fraction(pvc: float, cpvc: float = DEFAULT_CPVC) -> tuple[float, float, float]:
    """(pigment, binder, air) volume fractions of a film of pigment volume concentration
    ``pvc`` (pigment / (pigment + binder)): below the CPVC (pvc, 1 − pvc, 0); above it
    (CPVC, (1 − PVC)·CPVC/PVC, 1 − CPVC/PVC) (module docstring).

    >>> [round(x, 3) for x in void_fraction(0.8, 0.6)]
    [0.6, 0.15, 0.25]
    """
    check_cpvc(cpvc)
    if not 0 <= pvc <= 1:
        raise InvalidInputError(f"the pigment fractions sum to {pvc:g}; it must lie in [0, 1] (a PVC)")
    if pvc <= cpvc:
        return float(pvc), float(1 - pvc), 0.0
    return float(cpvc), float((1 - pvc) * cpvc / pvc), float(1 - cpvc / pvc)


def percus_yevick_mixture(q: ArrayLike, diameters_nm: ArrayLike, number_densities_per_nm3: ArrayLike, n_r: int = 24) -> np.ndarray:
    """Partial structure factors S_ij(q) of a hard-sphere mixture (Percus–Yevick).

    Baxter's (1970) factorisation of the Lebowitz (1964) solution: with
    ξ_n = (π/6) Σ ρ_k σ_k^n, a_i = (1 − ξ3 + 3σ_i ξ2)/(1 − ξ3)², b_i = −(3/2)σ_i² ξ2/(1 − ξ3)²,
    q_ij(r) = a_i (r² − R_ij²)/2 + b_i (r − R_ij) on λ_ij = (σ_i − σ_j)/2 < r < R_ij = (σ_i + σ_j)/2,
    Q̂_ij(q) = δ_ij − 2π √(ρ_i ρ_j) ∫ q_ij(r) e^{iqr} dr, and S(q) = [Q̂(q)ᵀ* Q̂(q)]⁻¹ with
    S_ij = δ_ij + √(ρ_i ρ_j) h̃_ij (Ashcroft & Langreth 1967's normalisation). The r integral
    is done by Gauss–Legendre quadrature (``n_r`` nodes: exact to rounding for qσ ≲ 30).

    Parameters
    ----------
    q : array_like (...,) wavenumber transfer (nm⁻¹)
    diameters_nm, number_densities_per_nm3 : (M,) each

    Returns
    -------
    ndarray (..., M, M), real.
    """
    s = np.asarray(diameters_nm, dtype=float)
    rho = np.asarray(number_densities_per_nm3, dtype=float)
    if s.ndim != 1 or s.shape != rho.shape or np.any(s <= 0) or np.any(rho < 0):
        raise InvalidInputError("diameters_nm (> 0) and number_densities_per_nm3 (>= 0) must be 1-D of equal length")
    xi = [np.pi / 6 * np.sum(rho * s**n) for n in range(4)]
    if xi[3] >= 0.64:
        raise InvalidInputError(f"the particles fill {xi[3]:.3f} of the volume; hard spheres pack randomly to at most 0.64")
    d = 1 - xi[3]
    a = (1 - xi[3] + 3 * s * xi[2]) / d**2
    b = -1.5 * s**2 * xi[2] / d**2
    R = (s[:, None] + s[None, :]) / 2
    lam = (s[:, None] - s[None, :]) / 2
    x, wq = np.polynomial.legendre.leggauss(int(n_r))
    r = lam[..., None] + (R - lam)[..., None] * (x + 1) / 2  # (M, M, n)
    wr = (R - lam)[..., None] * wq / 2
    qij = a[:, None, None] * (r**2 - R[..., None] ** 2) / 2 + b[:, None, None] * (r - R[..., None])
    qq = np.asarray(q, dtype=float)[..., None, None, None]
    integral = np.sum(qij * wr * np.exp(1j * qq * r), axis=-1)  # (..., M, M)
    M = s.size
    Q = np.eye(M) - 2 * np.pi * np.sqrt(rho[:, None] * rho[None, :]) * integral
    A = np.swapaxes(Q.conj(), -1, -2) @ Q
    return np.linalg.inv(A).real


def _gauss_mu(n_host, w, comps, L):
    dmax = max(float(c.distribution.diameter_nm.max()) for c in comps)
    x = float(np.max(np.pi * dmax * n_host / w))
    n = max(64, int(x + 4.05 * x ** (1 / 3) + 2 + L / 2) + 8)
    return _leggauss(n)


@functools.lru_cache(maxsize=32)
def _leggauss(n: int):
    """Gauss–Legendre nodes and weights of order ``n``, cached: NumPy's leggauss (an
    eigenvalue problem) was ~30 % of a film evaluation in matching and calibration loops."""
    mu, wq = np.polynomial.legendre.leggauss(n)
    mu.flags.writeable = False
    wq.flags.writeable = False
    return mu, wq


def mixture_optics(components: Sequence[Component], binder: object, wavelength_nm: ArrayLike, dependent_scattering: bool = False, cpvc: float | None = None,
                   n_moments: int = 97) -> MixtureOptics:
    """μ_a, μ_s, phase moments of a film of several particulate components (module docstring).

    Parameters
    ----------
    components : sequence of :class:`Component`
        Fractions are of the dry film (pigment + binder); their sum is the PVC.
    binder : Material or complex
        Binder index (its real part is the Mie host; its k absorbs in the binder's share).
    wavelength_nm : array_like (1-D)
    dependent_scattering : bool
        Add the multi-component Percus–Yevick interference (:func:`percus_yevick_mixture`).
    cpvc : float, optional
        Critical PVC (default :data:`DEFAULT_CPVC`); above it the film holds air voids.
    n_moments : int
        Legendre moments of the phase function returned (χ_0 … χ_{n_moments−1}).
    """
    from nmmm.layers.mie_scattering import mie

    comps = tuple(components)
    if not comps:
        raise InvalidInputError("a film needs at least one component (pigment, white, extender)")
    w = as_wavelength_nm(np.atleast_1d(wavelength_nm))
    nb = np.broadcast_to(medium_nk(binder, w, "binder"), w.shape)
    n_host = nb.real
    alpha_b = 4 * np.pi * nb.imag / w
    pvc = float(sum(c.fraction for c in comps))
    if pvc > 1 + 1e-12:
        raise InvalidInputError(f"the component fractions sum to {pvc:g} > 1; fractions are of the dry film and sum to the PVC (< 1)")
    f_pig, f_binder, f_air = void_fraction(min(pvc, 1.0), DEFAULT_CPVC if cpvc is None else cpvc)
    scale = f_pig / pvc if pvc > 0 else 1.0
    species = [(c.name or f"component {i}", c.compound, c.distribution, c.fraction * scale) for i, c in enumerate(comps)]
    if f_air > 0:
        mean_d = (sum(c.fraction * c.distribution.moment(3) for c in comps) / pvc) ** (1 / 3)
        species.append(("air voids", 1.0 + 0j, monodisperse(mean_d), f_air))
    L = int(n_moments)
    mu, wq = _gauss_mu(n_host, w, comps, L)
    ang = np.degrees(np.arccos(mu))
    k = 2 * np.pi * n_host / w
    mu_a = f_binder * alpha_b
    dsig = np.zeros((w.size, mu.size))
    contributions = []
    amps, dens, dhs = [], [], []
    for name, compound, dist, f in species:
        nk = np.broadcast_to(medium_nk(compound, w, name), w.shape)
        d = dist.diameter_nm
        wn = dist.number_weights
        mean_v = float(np.sum(wn * np.pi / 6 * d**3))
        rho = f / mean_v
        r = mie(nk[:, None], n_host[:, None], d[None, :], w[:, None], angles_deg=ang)
        cabs = np.maximum(np.sum(r.qabs * np.pi * d**2 / 4 * wn, axis=1), 0.0) * rho
        ds = np.einsum("d,wda->wa", wn, r.differential_cross_section_nm2()) * rho
        mu_a = mu_a + cabs
        dsig = dsig + ds
        contributions.append((name, cabs, 2 * np.pi * ds @ wq))
        if name != "air voids":
            amps.append((np.einsum("d,wda->wa", wn, r.s1), np.einsum("d,wda->wa", wn, r.s2)))
            dens.append(rho)
            dhs.append(dist.moment(3) ** (1 / 3))
    if dependent_scattering and any(x > 0 for x in dens):
        q = 2 * k[:, None] * np.sqrt((1 - mu[None, :]) / 2)  # (W, A)
        S = percus_yevick_mixture(q, dhs, dens)  # (W, A, M, M)
        Mn = len(dens)
        sq = np.sqrt(np.outer(dens, dens))
        for i in range(Mn):
            for j in range(Mn):
                cross = (amps[i][0] * amps[j][0].conj() + amps[i][1] * amps[j][1].conj()).real / (2 * k[:, None] ** 2)
                dsig = dsig + sq[i, j] * cross * (S[..., i, j] - (i == j))
    P = np.polynomial.legendre.legvander(mu, L - 1)
    mom = 2 * np.pi * (dsig * wq) @ P  # (W, L)
    mu_s = np.maximum(mom[:, 0], 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        chi = np.where(mom[:, :1] > 0, mom / np.where(mom[:, :1] > 0, mom[:, :1], 1.0), np.eye(1, L))
    chi = np.clip(chi, -1.0, 1.0)
    chi[:, 0] = 1.0
    return MixtureOptics(w, np.maximum(mu_a, 0.0), mu_s, chi, n_host, alpha_b, pvc, f_air, tuple(contributions))
