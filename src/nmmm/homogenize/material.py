"""From a microstructure and its compounds to a Material of the next scale.

- :func:`homogenize` — ``homogenize(microstructure, {phase: Material}, wavelength_nm)`` runs
  :func:`~nmmm.homogenize.fft_permittivity` over the spectrum and returns a
  :class:`HomogenizedMaterial`.
- :class:`HomogenizedMaterial` — a :class:`~nmmm.materials.material.DerivedMaterial` whose
  ``eps``/``nk`` are the **orientation average** (trace / d) of the effective tensor, linearly
  interpolated in wavelength between the computed nodes (its range is that of the nodes:
  nothing is extrapolated). The anisotropy stays available: ``tensor(wavelength_nm)``, one
  Material per principal axis (``principal(axis)``), and for layered cells with the z axis
  normal to the substrate (flakes lying flat) ``ordinary`` (mean of xx, yy) and
  ``extraordinary`` (zz) Materials for uniaxial layer optics and ellipsometry.
- :func:`apparent_property` — a scalar property of one realisation for the RVE study of
  :func:`nmmm.microstructure.rve_study` (Kanit et al. 2003).

References
----------
- Kanit, T., Forest, S., Galliet, I., Mounoury, V., Jeulin, D. (2003). Int. J. Solids Struct.
  40, 3647-3679. doi:10.1016/S0020-7683(03)00143-4
- Couka, E., Willot, F., Jeulin, D., et al. (2015). J. Nanosci. Nanotechnol. 15(5), 3515
  (FFT homogenization of hematite coatings).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.materials.material import DerivedMaterial, Material, as_material
from nmmm.spectra import as_wavelength_nm, wavelength_grid


def _interp_complex(w, nodes, values):
    """Linear interpolation in wavelength of complex ``values`` (node axis first); shape w.shape + rest."""
    w = np.asarray(w, dtype=float)
    values = np.asarray(values)
    flat = values.reshape(values.shape[0], -1)
    out = np.empty((w.size, flat.shape[1]), dtype=complex)
    for c in range(flat.shape[1]):
        out[:, c] = np.interp(w.ravel(), nodes, flat[:, c].real) + 1j * np.interp(w.ravel(), nodes, flat[:, c].imag)
    return out.reshape(w.shape + values.shape[1:])


@dataclass(frozen=True, repr=False)
class HomogenizedMaterial(DerivedMaterial):
    """The effective medium of a microstructure computed by FFT homogenization.

    ``eps(w)`` returns the orientation average trace(ε_eff)/d; see :meth:`tensor`,
    :meth:`principal`, :attr:`ordinary` and :attr:`extraordinary` for the anisotropy.
    """

    wavelength_nodes_nm: np.ndarray | None = None
    tensor_nodes: np.ndarray | None = None  # (n_nodes, d, d)
    result: object = None

    def tensor(self, wavelength_nm, extrapolate: bool = False) -> np.ndarray:
        """Effective tensor at ``wavelength_nm`` (shape ``w.shape + (d, d)``), interpolated linearly."""
        w = self.check_range(wavelength_nm, extrapolate)
        return _interp_complex(w, self.wavelength_nodes_nm, self.tensor_nodes)

    @property
    def ndim(self) -> int:
        return int(self.tensor_nodes.shape[-1])

    def principal(self, axis: int) -> DerivedMaterial:
        """ε_{axis,axis} as a Material (e.g. ``principal(2)``: across a layer lying in x, y)."""
        if not 0 <= axis < self.ndim:
            raise InvalidInputError(f"axis must be in 0..{self.ndim - 1}, got {axis}")
        nodes, values = self.wavelength_nodes_nm, self.tensor_nodes[:, axis, axis]
        return DerivedMaterial(
            name=f"{self.name} [{'xyz'[axis]}{'xyz'[axis]}]",
            eps_function=lambda w: _interp_complex(w, nodes, values),
            components=self.components,
            reference=self.reference,
            range_override_nm=self.range_nm,
        )

    @property
    def ordinary(self) -> DerivedMaterial:
        """In-plane Material: mean of ε_xx and ε_yy (z normal to the layer, 3-D cells)."""
        nodes = self.wavelength_nodes_nm
        values = 0.5 * (self.tensor_nodes[:, 0, 0] + self.tensor_nodes[:, 1, 1])
        return DerivedMaterial(f"{self.name} [ordinary]", lambda w: _interp_complex(w, nodes, values),
                               self.components, self.reference, self.range_nm)

    @property
    def extraordinary(self) -> DerivedMaterial:
        """Out-of-plane Material ε_zz (3-D cells; the layer normal along the last axis)."""
        return self.principal(self.ndim - 1)


def _resolve_materials(materials, phases, labels_present):
    """Map {label or phase name: Material or constant ε} to {label: Material}."""
    names = {}
    if isinstance(phases, dict):
        names = {str(v): int(k) for k, v in phases.items()}
    elif phases is not None:
        names = {str(v): i for i, v in enumerate(phases)}
    out = {}
    for key, mat in materials.items():
        if isinstance(key, (int, np.integer)):
            lab = int(key)
        elif str(key) in names:
            lab = names[str(key)]
        else:
            raise InvalidInputError(
                f"phase {key!r} is neither a label nor a phase name of the microstructure "
                f"(phases: {phases!r})"
            )
        if isinstance(mat, Material):
            out[lab] = mat
        else:
            eps = complex(np.asarray(mat))
            from nmmm.materials.material import eps_to_nk

            out[lab] = as_material(complex(eps_to_nk(eps)), name=f"eps={eps:g}")
    missing = [int(v) for v in labels_present if int(v) not in out]
    if missing:
        raise InvalidInputError(
            f"labels {missing} of the microstructure have no Material; give one for every phase "
            f"(phases: {phases!r}, given: {list(materials)})"
        )
    return out


def homogenize(microstructure, materials: dict, wavelength_nm=None, name: str | None = None,
               **kwargs) -> HomogenizedMaterial:
    """Effective Material of a periodic microstructure, by FFT homogenization over a spectrum.

    Parameters
    ----------
    microstructure : Microstructure or int array
        Cell with ``labels`` (and ``voxel_nm``, ``phases``, ``periodic`` when a Microstructure).
    materials : dict
        ``{label or phase name: Material or constant ε}`` for every phase present.
    wavelength_nm : array_like, optional
        Wavelength nodes (nm); default 380-780 nm every 20 nm. The returned Material is
        interpolated linearly between them and refuses wavelengths outside them.
    name : str, optional
    **kwargs
        Passed to :func:`~nmmm.homogenize.fft_permittivity` (``green``, ``solver``, ``tol``,
        ``dtype``, ...). ``voxel_nm`` of the microstructure enables the quasi-static validity
        warning.

    Returns
    -------
    HomogenizedMaterial
        ``eps(w)`` is trace(ε_eff)/d; ``tensor(w)``, ``principal(axis)``, ``ordinary``,
        ``extraordinary`` give the anisotropic response; ``result`` keeps iteration counts and
        residual histories.
    """
    from nmmm.homogenize.fft import _as_label_array, fft_permittivity

    w = wavelength_grid(380.0, 780.0, 20.0) if wavelength_nm is None else as_wavelength_nm(wavelength_nm)
    w = np.atleast_1d(w).astype(float)
    if np.any(np.diff(w) <= 0):
        raise InvalidInputError("wavelength_nm must increase strictly")
    arr, meta = _as_label_array(microstructure)
    mats = _resolve_materials(materials, meta.get("phases"), np.unique(arr))
    eps = {lab: m.eps(w) for lab, m in mats.items()}
    res = fft_permittivity(microstructure, eps, wavelength_nm=w, **kwargs)
    tensor = np.asarray(res.tensor).reshape((w.size,) + res.tensor.shape[-2:])
    if res.directions != tuple(range(arr.ndim)):
        raise InvalidInputError("homogenize needs every loading; do not pass directions")
    nodes = w.copy()
    mean = np.trace(tensor, axis1=-2, axis2=-1) / arr.ndim
    comps = tuple(mats[k] for k in sorted(mats))
    label = name or "FFT(" + ", ".join(f"{m.name} {res.fractions.get(k, 0):.3g}" for k, m in sorted(mats.items())) + ")"
    return HomogenizedMaterial(
        name=label,
        eps_function=lambda x: _interp_complex(x, nodes, mean),
        components=comps,
        reference="FFT homogenization (nmmm.homogenize, Galerkin/COCG, Green operator "
        f"{res.green}); eps = trace/d of the effective tensor",
        range_override_nm=(float(nodes[0]), float(nodes[-1])),
        metadata={"fractions": res.fractions, "iterations": res.iterations, "green": res.green},
        wavelength_nodes_nm=nodes,
        tensor_nodes=tensor,
        result=res,
    )


def apparent_property(eps: dict, part: str = "real", component: str | int = "mean", **kwargs):
    """A callable ``prop(microstructure) -> float`` for :func:`nmmm.microstructure.rve_study`.

    ``component`` is ``"mean"`` (trace/d) or an axis index; ``part`` ``"real"``, ``"imag"`` or
    ``"abs"``. ``eps`` maps labels to scalar permittivities.
    """
    from nmmm.homogenize.fft import fft_permittivity

    if part not in ("real", "imag", "abs"):
        raise InvalidInputError(f"part must be 'real', 'imag' or 'abs', got {part!r}")

    def prop(microstructure) -> float:
        kw = dict(kwargs)
        if component != "mean":
            kw["directions"] = [int(component)]
        r = fft_permittivity(microstructure, eps, **kw)
        z = r.mean if component == "mean" else r.tensor[int(component), int(component)]
        return float({"real": np.real, "imag": np.imag, "abs": np.abs}[part](z))

    return prop


__all__ = ["homogenize", "HomogenizedMaterial", "apparent_property"]
