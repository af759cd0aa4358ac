"""nmmm.ellipsometry — from measured Ψ and Δ to the optical constants of each compound.

- :func:`psi_delta`, :func:`rho` — forward model of any :class:`nmmm.layers.Stack`
  (convention: Δ = 180° at normal incidence on a dielectric, 0° < Δ < 180° for a bulk
  absorber; see :mod:`nmmm.ellipsometry.forward`).
- :func:`pseudo_dielectric` — direct inversion of a bulk sample, ⟨ε⟩.
- :class:`EllipsometryData`, :func:`read_data`, :func:`read_csv`, :func:`read_woollam`,
  :func:`write_csv`, :func:`write_material_csv` — data files; :class:`DataScan` — what the readers
  found wrong in a file (NaN rows, truncated lines, repeated or unsorted points; ``strict=True`` refuses).
- :func:`thickness_prescan`, :func:`check_fit_quality` — a global scan of each varied thickness
  before the local fit (the interference order), and the warning when the reduced MSE is far above 1.
- :class:`Parameter`, :class:`FitResult`, :func:`fit_psi_delta` — weighted least squares with
  uncertainties and correlations; :class:`FitAtBoundWarning` when a parameter ends on a bound.
- :func:`fit_joint` — one fit over several data sets (films of one resin with different
  thicknesses, several instruments) with shared parameters and per-data-set ones (``name[i]``).
- :class:`EllipsometryModel`, :func:`read_model` — layered models with dispersion laws and a
  surface-roughness layer, from TOML.
- :func:`point_by_point` — wavelength-by-wavelength inversion of one layer's n, k;
  :func:`kk_check` — Kramers–Kronig consistency of the result.
- :func:`uniaxial_from_two_orientations` — ordinary and extraordinary constants of a uniaxial
  crystal from two orthogonal in-plane measurements, and their mean.

Sub-modules are imported on demand.
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "psi_delta": "forward", "rho": "forward", "psi_delta_from_rho": "forward",
    "rho_from_psi_delta": "forward", "bulk_rho": "forward", "uniaxial_bulk_rho": "forward",
    "pseudo_dielectric": "pseudo_dielectric_function", "pseudo_dielectric_material": "pseudo_dielectric_function",
    "EllipsometryData": "data", "read_data": "data", "read_csv": "data", "read_woollam": "data",
    "write_csv": "data", "write_material_csv": "data", "DataScan": "data",
    "thickness_prescan": "fit_start", "check_fit_quality": "fit_start",
    "Parameter": "fitting", "FitResult": "fitting", "fit_psi_delta": "fitting",
    "FitAtBoundWarning": "fitting", "fit_joint": "joint", "joint_parameter_names": "joint",
    "EllipsometryModel": "model", "read_model": "model", "dispersion_material": "model",
    "roughness_material": "model",
    "point_by_point": "point_by_point_inversion", "PointByPointResult": "point_by_point_inversion",
    "kk_check": "point_by_point_inversion",
    "uniaxial_from_two_orientations": "anisotropy", "UniaxialResult": "anisotropy",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name):
    if name in _EXPORTS:
        module = importlib.import_module(f"nmmm.ellipsometry.{_EXPORTS[name]}")
        return getattr(module, name)
    raise AttributeError(f"module 'nmmm.ellipsometry' has no attribute {name!r}")
