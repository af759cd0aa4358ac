"""Size-dependent (surface-scattering) damping of the free electrons of small metal particles.

- :func:`kreibig_damped_eps` — ε(λ, R) of a sphere of radius R from the measured bulk ε(λ):
  the free-electron (Drude) part is re-damped with γ(R) = γ_bulk + A v_F / R, the rest (the
  interband part, and whatever the Drude term does not describe) is kept as measured.
- :func:`size_damped` — the same as a :class:`~nmmm.materials.material.Material`, so that Mie,
  the effective media and the recipes use it like any compound.
- :data:`FREE_ELECTRON_PARAMETERS` — ħω_p, ħγ_bulk, v_F of gold and silver, each cited;
  :class:`FreeElectronParameters`.

Model (Kreibig & von Fragstein 1969; Kreibig & Vollmer 1995, §2.2):

    ε(ω, R) = ε_bulk(ω) + ω_p² / (ω² + iγ_bulk ω) − ω_p² / (ω² + iγ(R) ω),
    γ(R)   = γ_bulk + A v_F / R

with ħ = 6.582119569e-16 eV s (exp(−iωt), Im ε ≥ 0). The correction is a difference of two
Drude terms, so it is causal (Kramers–Kronig consistent) and adds absorption only (Im ε grows
with γ for ω > 0). It leaves ε_bulk unchanged as R → ∞.

The parameter A
---------------
A is of order one and depends on the theory and on the particle's surroundings (chemical
interface damping): Haiss et al. (2007) take the classical collision time τ_c = R / v_F, i.e.
A = 1, which is the default here; Coronado & Schatz (2003) derive the effective mean free
path L_eff = 4V/S (= 4R/3 for a sphere) with A = 1 in γ = γ_bulk + A v_F / L_eff, i.e.
A = 3/4 in the R form used here; Penn & Apell (1983) find the surface-scattering rate
reduced by screening. Kreibig & Vollmer (1995) review measured A from ~0.1 to ~2 (quoted from
the review's summary as commonly cited; not checked against the book here). Against the size
series of Haiss et al. (2007, eq. 11 with their experimental B1 = 3.00, B2 = 2.20, 5–80 nm in
water) nmmm with Johnson & Christy gold recovers the diameter to 30 % mean deviation with A = 1,
17 % with A = 1.5, and 200 % (5 nm reads as 37 nm) without the correction
(tests/materials/test_size_damping.py).

References
----------
- U. Kreibig, C. v. Fragstein, "The limitation of electron mean free path in small silver
  particles", Z. Phys. 224, 307 (1969), doi:10.1007/BF01393059.
- U. Kreibig, M. Vollmer, *Optical Properties of Metal Clusters*, Springer (1995), §2.2.
  doi:10.1007/978-3-662-09109-8
- E. A. Coronado, G. C. Schatz, "Surface plasmon broadening for arbitrary shape nanoparticles:
  A geometrical probability approach", J. Chem. Phys. 119, 3926 (2003), doi:10.1063/1.1587686.
- D. R. Penn, S. P. Apell, "Optical properties of small metal spheres: surface effects",
  Phys. Rev. Lett. 50, 1316 (1983), doi:10.1103/PhysRevLett.50.1316.
- W. Haiss, N. T. K. Thanh, J. Aveyard, D. G. Fernig, "Determination of size and concentration
  of gold nanoparticles from UV-Vis spectra", Anal. Chem. 79, 4215 (2007), doi:10.1021/ac0702084.
- A. D. Rakić, A. B. Djurišić, J. M. Elazar, M. L. Majewski, "Optical properties of metallic films
  for vertical-cavity optoelectronic devices", Appl. Opt. 37, 5271 (1998), doi:10.1364/AO.37.005271
  (Lorentz–Drude fits: Au ħω_p = 9.03 eV, f0 = 0.760, ħΓ0 = 0.053 eV; Ag 9.01 eV, 0.845,
  0.048 eV; free-electron plasma energy √f0 ħω_p, as in the refractiveindex.info script
  ``Rakic 1998 - Au (LD model).py``).
- N. W. Ashcroft, N. D. Mermin, *Solid State Physics*, Saunders (1976), Table 2.1:
  v_F = 1.40e6 m/s (Au), 1.39e6 m/s (Ag).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from nmmm.errors import InvalidInputError
from nmmm.materials.material import DerivedMaterial, Material, as_material
from nmmm.spectra import as_wavelength_nm, check_positive

__all__ = ["FREE_ELECTRON_PARAMETERS", "FreeElectronParameters", "kreibig_damped_eps", "size_damped"]

#: ħ in eV s (CODATA 2018)
HBAR_EV_S = 6.582119569e-16
#: h c in eV nm
_HC_EV_NM = 1239.841984


@dataclass(frozen=True)
class FreeElectronParameters:
    """Free-electron (Drude) part of a metal: plasma energy ħω_p and bulk damping ħγ (eV),
    Fermi velocity v_F (m/s), with the sources."""

    plasma_ev: float
    gamma_bulk_ev: float
    fermi_velocity_m_s: float
    reference: str


FREE_ELECTRON_PARAMETERS: dict[str, FreeElectronParameters] = {
    "gold": FreeElectronParameters(
        plasma_ev=float(np.sqrt(0.760) * 9.03), gamma_bulk_ev=0.053, fermi_velocity_m_s=1.40e6,
        reference="Rakić et al., Appl. Opt. 37, 5271 (1998), LD fit of Au (sqrt(f0) hbar omega_p = "
                  "sqrt(0.760) x 9.03 eV, hbar Gamma0 = 0.053 eV); v_F: Ashcroft & Mermin (1976) Table 2.1"),
    "silver": FreeElectronParameters(
        plasma_ev=float(np.sqrt(0.845) * 9.01), gamma_bulk_ev=0.048, fermi_velocity_m_s=1.39e6,
        reference="Rakić et al., Appl. Opt. 37, 5271 (1998), LD fit of Ag (sqrt(0.845) x 9.01 eV, "
                  "0.048 eV); v_F: Ashcroft & Mermin (1976) Table 2.1"),
}


def _parameters(metal) -> FreeElectronParameters:
    if isinstance(metal, FreeElectronParameters):
        return metal
    try:
        return FREE_ELECTRON_PARAMETERS[str(metal).lower()]
    except KeyError:
        raise InvalidInputError(
            f"no free-electron parameters for metal {metal!r}; choose one of {sorted(FREE_ELECTRON_PARAMETERS)} "
            "or pass FreeElectronParameters(plasma_ev=..., gamma_bulk_ev=..., fermi_velocity_m_s=..., "
            "reference=...)") from None


#: element symbols in a key or name (``main/Au/Johnson``, ``Ag (Palik)``) → FREE_ELECTRON_PARAMETERS key
_SYMBOLS = {"Au": "gold", "Ag": "silver"}


def _metal_of(bulk: Material, metal):
    """The metal named by ``metal`` or read from the material's key/name (see :func:`size_damped`)."""
    import re

    name = str(getattr(bulk, "name", ""))
    found = {_SYMBOLS[t] for t in re.findall(r"(?<![A-Za-z])(Au|Ag)(?![a-z])", name)}
    found |= {m for m in FREE_ELECTRON_PARAMETERS if m in name.lower()}
    if metal is None:
        if len(found) != 1:
            raise InvalidInputError(
                f"size damping of {name!r}: cannot tell which metal it is from its key or name "
                f"({'both ' + ' and '.join(sorted(found)) if found else 'no Au/Ag'}); give metal= one of "
                f"{sorted(FREE_ELECTRON_PARAMETERS)} (or FreeElectronParameters); only free-electron metals are damped")
        return found.pop()
    if isinstance(metal, str) and metal.lower() in FREE_ELECTRON_PARAMETERS and found and metal.lower() not in found:
        raise InvalidInputError(f"size damping of {name!r}: metal={metal!r}, but the key names "
                                f"{' and '.join(sorted(found))}; give the metal the data are of (or leave metal out)")
    return metal


def _check_free_electron_metal(bulk: Material) -> None:
    """Refuse a material whose Re ε is not < 0 over the visible part of its range (not a metal)."""
    lo, hi = bulk.range_nm
    w = np.linspace(max(lo, 400.0), min(hi, 700.0), 31) if lo < 700 and hi > 400 else np.array([lo, hi])
    e1 = bulk.eps(w[np.isfinite(w)]).real
    if np.any(e1 >= 0):
        i = int(np.argmax(e1 >= 0))
        raise InvalidInputError(
            f"size damping of {bulk.name!r}: Re eps = {e1[i]:.3g} >= 0 at {w[i]:g} nm; the Kreibig damping is for "
            "free-electron metals (Re eps < 0 over the visible, e.g. gold, silver); a dielectric would get a false "
            "absorption — remove size_damping for this material")


def kreibig_damped_eps(eps_bulk: ArrayLike, wavelength_nm: ArrayLike, radius_nm: ArrayLike, *, A: float = 1.0,
                       metal: str = "gold") -> np.ndarray:
    """ε of a metal sphere of radius R with surface-scattering damping (Kreibig model).

    Parameters
    ----------
    eps_bulk : complex array_like
        Measured bulk permittivity at ``wavelength_nm`` (e.g. Johnson & Christy gold).
    wavelength_nm : array_like
        Vacuum wavelengths (nm).
    radius_nm : array_like
        Sphere radius R (nm), > 0; broadcasts with the wavelengths.
    A : float
        Surface-scattering parameter (≥ 0; 1 = classical τ_c = R / v_F, the default).
    metal : str or FreeElectronParameters
        ``"gold"`` or ``"silver"`` (:data:`FREE_ELECTRON_PARAMETERS`) or explicit parameters.

    Returns
    -------
    ndarray
        ε(λ, R) = ε_bulk + ω_p²/(ω² + iγ_bulk ω) − ω_p²/(ω² + iγ(R) ω), γ(R) = γ_bulk + A v_F/R.

    Examples
    --------
    A pure Drude metal stays a Drude metal with the damping γ(R) (here ħ v_F / R at R = 5 nm
    adds 0.184 eV to ħγ_bulk = 0.053 eV):

    >>> from nmmm.materials.models import Drude
    >>> p = FREE_ELECTRON_PARAMETERS["gold"]
    >>> bulk = Drude(plasma_ev=p.plasma_ev, gamma_ev=p.gamma_bulk_ev)
    >>> small = Drude(plasma_ev=p.plasma_ev, gamma_ev=p.gamma_bulk_ev + HBAR_EV_S * p.fermi_velocity_m_s / 5e-9)
    >>> bool(abs(kreibig_damped_eps(bulk.eps(520.0), 520.0, 5.0) - small.eps(520.0)) < 1e-12)
    True
    """
    p = _parameters(metal)
    w = as_wavelength_nm(wavelength_nm)
    R = check_positive(radius_nm, "radius_nm")
    if not np.isfinite(A) or A < 0:
        raise InvalidInputError(f"A must be a finite number >= 0 (of order 1; 1 = classical R/v_F), got {A!r}")
    E = _HC_EV_NM / w
    gamma_r = p.gamma_bulk_ev + A * HBAR_EV_S * p.fermi_velocity_m_s / (R * 1e-9)
    wp2 = p.plasma_ev**2
    return np.asarray(eps_bulk, dtype=complex) + wp2 / (E * E + 1j * p.gamma_bulk_ev * E) - wp2 / (E * E + 1j * gamma_r * E)


def size_damped(material: Material | str, radius_nm: float, *, A: float = 1.0,
                metal: str | FreeElectronParameters | None = None) -> Material:
    """``material`` (bulk metal: Material or database key) with the Kreibig damping of a sphere of
    radius ``radius_nm``, as a Material over the same wavelength range.

    ``metal`` (whose free-electron parameters, :data:`FREE_ELECTRON_PARAMETERS`) is read from the
    key or name when not given (``Au`` → gold, ``Ag`` → silver, e.g. ``main/Au/Johnson``); a
    material it cannot be read from needs ``metal=``, and a ``metal`` that contradicts the key is
    refused. A material whose Re ε is not negative over the visible part (400–700 nm) of its
    range is not a free-electron metal and is refused (the Drude correction would give a
    dielectric a false absorption). All refusals are :class:`~nmmm.errors.InvalidInputError`.

    >>> m = size_damped("main/Au/Johnson", 5.0)
    >>> from nmmm.materials.database import get
    >>> bool(m.eps(520.0).imag > get("main/Au/Johnson").eps(520.0).imag)
    True
    """
    if isinstance(material, str):
        from nmmm.materials.database import get

        material = get(material)
    bulk = as_material(material)
    R = float(check_positive(radius_nm, "radius_nm"))
    _check_free_electron_metal(bulk)
    metal = _metal_of(bulk, metal)
    p = _parameters(metal)
    kreibig_damped_eps(0j, 500.0, R, A=A, metal=p)  # validate A now, not at the first evaluation

    def eps(w_nm):
        return kreibig_damped_eps(bulk.eps(w_nm), w_nm, R, A=A, metal=p)

    return DerivedMaterial(
        name=f"{bulk.name}, R = {R:g} nm (Kreibig A = {A:g})", eps_function=eps, components=(bulk,),
        reference=f"{bulk.reference}; size damping gamma(R) = gamma_bulk + A v_F/R (Kreibig & Vollmer 1995) "
                  f"with {p.reference}",
        metadata={"radius_nm": R, "A": float(A), "metal": metal.lower() if isinstance(metal, str) else "custom"})
