"""Uniaxial crystals: ordinary and extraordinary constants from two orthogonal measurements.

Public objects
--------------
- :func:`uniaxial_from_two_orientations` — ε_o and ε_e at every wavelength from Ψ, Δ measured
  with the optic axis (in the surface) parallel and perpendicular to the plane of incidence.
- :class:`UniaxialResult` — both sets of constants with uncertainties, ``ordinary()``,
  ``extraordinary()`` (TabulatedMaterials) and ``mean()`` (:func:`nmmm.materials.uniaxial_mean`,
  ε = (2ε_o + ε_e)/3, the isotropic constants used downstream for randomly oriented grains).
- :func:`synthetic_uniaxial_data` — exact Ψ, Δ of such a crystal (for examples and tests).

Method
------
A crystal cut with its optic axis c in the surface, measured twice: plane of incidence ∥ c
("parallel") and ⊥ c ("perpendicular"). In both orientations the principal axes coincide
with the s, p frame, so the Jones matrix stays diagonal and (Ψ, Δ) are defined; r_s and r_p
follow in closed form (:func:`nmmm.ellipsometry.forward.uniaxial_bulk_rho`, Azzam & Bashara
ch. 4). Each orientation's pseudo-dielectric function is, to first order, the permittivity along
the in-plane direction of the plane of incidence (Aspnes 1980): ⟨ε⟩_∥ ≈ ε_e, ⟨ε⟩_⊥ ≈ ε_o. These
start a Levenberg–Marquardt solution of the exact equations for the four unknowns
(n_o, k_o, n_e, k_e) at every wavelength, vectorised across wavelengths
(:func:`nmmm.ellipsometry.point_by_point_inversion.batched_levenberg_marquardt`), with all angles of both
measurements used together.

References
----------
- D. E. Aspnes, "Approximate solution of ellipsometric equations for optically biaxial
  crystals", J. Opt. Soc. Am. 70, 1275 (1980), doi:10.1364/JOSA.70.001275.
- R. M. A. Azzam, N. M. Bashara, *Ellipsometry and Polarized Light*, North-Holland (1977), ch. 4.
- M. R. Querry, *Optical constants*, US Army CRDEC report CRDC-CR-85034 (1985) — hematite
  ordinary/extraordinary constants (database keys main/Fe2O3/Querry-o, -e).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from nmmm.ellipsometry.forward import psi_delta_from_rho, uniaxial_bulk_rho, wrap_delta
from nmmm.ellipsometry.point_by_point_inversion import (_raise_unconverged, _uncertainties, batched_levenberg_marquardt,
                                               group_wavelengths)
from nmmm.ellipsometry.pseudo_dielectric_function import pseudo_dielectric
from nmmm.errors import InvalidInputError
from nmmm.materials.material import eps_to_nk

__all__ = ["uniaxial_from_two_orientations", "UniaxialResult", "synthetic_uniaxial_data"]


@dataclass(frozen=True, repr=False)
class UniaxialResult:
    """Ordinary and extraordinary n + ik at each wavelength, with standard uncertainties."""

    wavelength_nm: np.ndarray
    nk_ordinary: np.ndarray
    nk_extraordinary: np.ndarray
    sigma_ordinary: np.ndarray  # (G, 2): σn, σk
    sigma_extraordinary: np.ndarray
    chi2: np.ndarray
    converged: np.ndarray
    name: str = "crystal"
    info: dict = field(default_factory=dict)

    def __repr__(self) -> str:
        return (f"<UniaxialResult '{self.name}': {self.wavelength_nm.size} wavelengths "
                f"{self.wavelength_nm.min():g}-{self.wavelength_nm.max():g} nm>")

    def _tab(self, nk, which):
        from nmmm.materials.material import TabulatedMaterial

        return TabulatedMaterial(f"{self.name} ({which})", self.wavelength_nm, nk.real, np.maximum(nk.imag, 0.0),
                                 reference="nmmm.ellipsometry.anisotropy: two-orientation inversion")

    def ordinary(self):
        """Ordinary constants as a TabulatedMaterial."""
        return self._tab(self.nk_ordinary, "ordinary")

    def extraordinary(self):
        """Extraordinary constants as a TabulatedMaterial."""
        return self._tab(self.nk_extraordinary, "extraordinary")

    def mean(self, name: str | None = None):
        """Isotropic mean ε = (2ε_o + ε_e)/3 (:func:`nmmm.materials.uniaxial_mean`)."""
        from nmmm.materials import uniaxial_mean

        return uniaxial_mean(self.ordinary(), self.extraordinary(), name=name or f"{self.name} (mean)")

    def write_csv(self, directory, stem: str | None = None) -> dict:
        """Write ordinary, extraordinary and mean constants as Material CSV files; returns the paths."""
        from pathlib import Path

        from nmmm.ellipsometry.data import write_material_csv

        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        stem = stem or self.name.replace(" ", "_")
        out = {}
        for key, nk, sig in (("ordinary", self.nk_ordinary, self.sigma_ordinary),
                             ("extraordinary", self.nk_extraordinary, self.sigma_extraordinary)):
            out[key] = write_material_csv(d / f"{stem}_{key}.csv", self.wavelength_nm,
                                          nk.real + 1j * np.maximum(nk.imag, 0), name=f"{self.name} ({key})",
                                          reference="nmmm.ellipsometry two-orientation inversion",
                                          sigma_n=sig[:, 0], sigma_k=sig[:, 1])
        mean = self.mean()
        out["mean"] = write_material_csv(d / f"{stem}_mean.csv", self.wavelength_nm, mean.nk(self.wavelength_nm),
                                         name=mean.name, reference="(2 eps_o + eps_e)/3")
        return out


def synthetic_uniaxial_data(ordinary, extraordinary, wavelength_nm, angle_deg, orientation: str,
                            sigma_psi_deg=None, sigma_delta_deg=None, noise_seed=None, name=None):
    """EllipsometryData of a bulk uniaxial crystal (optic axis in the surface) in one orientation."""
    from nmmm.ellipsometry.data import EllipsometryData

    w = np.atleast_1d(np.asarray(wavelength_nm, float))
    a = np.atleast_1d(np.asarray(angle_deg, float))
    W, A = (x.ravel() for x in np.meshgrid(w, a, indexing="ij"))
    psi, delta = psi_delta_from_rho(uniaxial_bulk_rho(ordinary.eps(W), extraordinary.eps(W), A, orientation))
    sp = None if sigma_psi_deg is None else np.full(W.shape, float(sigma_psi_deg))
    sd = None if sigma_delta_deg is None else np.full(W.shape, float(sigma_delta_deg))
    if noise_seed is not None:
        rng = np.random.default_rng(noise_seed)
        psi = np.clip(psi + rng.normal(0, sp), 0, 90)
        delta = delta + rng.normal(0, sd)
    return EllipsometryData(W, A, psi, delta, sp, sd, name=name or f"uniaxial, axis {orientation}",
                            metadata={"orientation": orientation})


def _align(data_par, data_perp):
    """Common wavelengths of the two measurements (each may have several angles)."""
    w1, _ = group_wavelengths(data_par.wavelength_nm)
    w2, _ = group_wavelengths(data_perp.wavelength_nm)
    common = w1[np.isin(np.round(w1, 6), np.round(w2, 6))]
    if common.size == 0:
        raise InvalidInputError("the two orientations share no wavelength; measure both on the same grid")
    return common


def uniaxial_from_two_orientations(data_parallel, data_perpendicular, *, eps_ambient=1.0, name: str = "crystal",
                                   max_iter: int = 100, raise_on_failure: bool = True) -> UniaxialResult:
    """Ordinary and extraordinary constants of a uniaxial crystal from two measurements.

    Parameters
    ----------
    data_parallel : EllipsometryData
        Ψ, Δ with the optic axis in the surface and in the plane of incidence.
    data_perpendicular : EllipsometryData
        Ψ, Δ with the optic axis in the surface, perpendicular to the plane of incidence
        (the sample turned by 90° about its normal).
    eps_ambient : complex
        Ambient permittivity.

    Returns
    -------
    UniaxialResult
        Inverted at the wavelengths common to both data sets (all angles used together).
        Raises :class:`ConvergenceError` if some wavelength does not converge.
    """
    common = _align(data_parallel, data_perpendicular)
    keep1 = np.isin(np.round(data_parallel.wavelength_nm, 6), np.round(common, 6))
    keep2 = np.isin(np.round(data_perpendicular.wavelength_nm, 6), np.round(common, 6))
    d1, d2 = data_parallel.subset(keep1), data_perpendicular.subset(keep2)
    if d1.has_sigma != d2.has_sigma:
        raise InvalidInputError("give sigmas for both orientations or for neither")
    w_pts = np.concatenate([d1.wavelength_nm, d2.wavelength_nm])
    a_pts = np.concatenate([d1.angle_deg, d2.angle_deg])
    psi_m = np.concatenate([d1.psi_deg, d2.psi_deg])
    delta_m = np.concatenate([d1.delta_deg, d2.delta_deg])
    par = np.concatenate([np.ones(len(d1), bool), np.zeros(len(d2), bool)])
    if d1.has_sigma:
        sp = np.concatenate([d1.sigma_psi_deg, d2.sigma_psi_deg])
        sd = np.concatenate([d1.sigma_delta_deg, d2.sigma_delta_deg])
    else:
        sp = sd = 1.0
    wl, gid = group_wavelengths(w_pts)

    # start: pseudo-dielectric functions, <eps>_par ~ eps_e, <eps>_perp ~ eps_o (Aspnes 1980)
    eps_pd = pseudo_dielectric(psi_m, delta_m, a_pts, eps_ambient)
    G = wl.size

    def gmean(mask):
        cnt = np.bincount(gid[mask], minlength=G)
        re = np.bincount(gid[mask], weights=eps_pd[mask].real, minlength=G)
        im = np.bincount(gid[mask], weights=eps_pd[mask].imag, minlength=G)
        return (re + 1j * im) / np.maximum(cnt, 1)

    nk_e0 = eps_to_nk(gmean(par))
    nk_o0 = eps_to_nk(gmean(~par))
    x0 = np.stack([nk_o0.real, np.maximum(nk_o0.imag, 0), nk_e0.real, np.maximum(nk_e0.imag, 0)], axis=-1)

    def residuals(x):
        eo = ((x[:, 0] + 1j * x[:, 1]) ** 2)[gid]
        ee = ((x[:, 2] + 1j * x[:, 3]) ** 2)[gid]
        r = np.where(par, uniaxial_bulk_rho(eo, ee, a_pts, "parallel", eps_ambient),
                     uniaxial_bulk_rho(eo, ee, a_pts, "perpendicular", eps_ambient))
        psi, delta = psi_delta_from_rho(r)
        return np.stack([(psi - psi_m) / sp, wrap_delta(delta - delta_m) / sd], axis=-1)

    x, info = batched_levenberg_marquardt(residuals, x0, gid, lower=np.array([1e-6, 0, 1e-6, 0]),
                                          max_iter=max_iter)
    sig = _uncertainties(info, d1.has_sigma, 2)  # 2 residuals (Ψ, Δ) per point, 4 unknowns
    conv = info["converged"]
    if raise_on_failure:
        _raise_unconverged("two-orientation inversion", wl, info,
                           "; check that the two data sets are the parallel and perpendicular orientations, "
                           "or pass raise_on_failure=False")
    return UniaxialResult(wl, x[:, 0] + 1j * x[:, 1], x[:, 2] + 1j * x[:, 3], sig[:, :2], sig[:, 2:],
                          info["chi2"], conv, name, info)
