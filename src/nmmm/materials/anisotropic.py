"""Anisotropic compounds: diagonal dielectric tensors and uniaxial crystals.

- :class:`DiagonalTensorMaterial` — ε = diag(εx, εy, εz), each principal value a Material.
- :func:`uniaxial` — the uniaxial crystal (ordinary: x, y; extraordinary: z).
- :func:`uniaxial_mean` — the isotropic Material of randomly oriented crystallites,
  ε = (2ε_o + ε_e)/3 (hematite: main/Fe2O3/Querry-o and Querry-e).

The orientation average of a diagonal tensor over uniformly random orientations is
its trace/3 (Born & Wolf, Principles of Optics, §15.3; for polycrystalline aggregates of
small crystallites this is the first-order, dilute-contrast estimate).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.materials.material import DerivedMaterial, Material, _intersect_ranges, as_material


def _as_axis_material(value, axis: str) -> Material:
    """A principal value given as a Material, a database key or a constant n + ik."""
    if isinstance(value, Material):
        return value
    if isinstance(value, str):
        from nmmm.materials.database import get

        return get(value)
    try:
        return as_material(value)
    except InvalidInputError as e:
        raise InvalidInputError(
            f"principal value {axis}: give a Material, a database key such as 'main/Fe2O3/Querry-o' "
            f"or a constant n + ik; got {value!r} ({e})") from None


@dataclass(frozen=True, repr=False)
class DiagonalTensorMaterial:
    """A compound with a diagonal permittivity tensor diag(εx, εy, εz) in its own frame.

    ``eps_tensor(wavelength_nm)`` returns an array of shape ``(..., 3)``; ``axis(i)`` the
    principal Material i; ``mean()`` the isotropic orientation average (trace / 3).
    """

    x: Material
    y: Material
    z: Material
    name: str = "anisotropic"
    reference: str = ""

    def __post_init__(self):
        for attr in ("x", "y", "z"):
            object.__setattr__(self, attr, _as_axis_material(getattr(self, attr), attr))

    @property
    def range_nm(self):
        return _intersect_ranges((self.x, self.y, self.z))

    @property
    def axes(self) -> tuple[Material, Material, Material]:
        return (self.x, self.y, self.z)

    def axis(self, i: int) -> Material:
        return self.axes[i]

    def eps_tensor(self, wavelength_nm, extrapolate: bool = False) -> np.ndarray:
        return np.stack([m.eps(wavelength_nm, extrapolate) for m in self.axes], axis=-1)

    def nk_tensor(self, wavelength_nm, extrapolate: bool = False) -> np.ndarray:
        return np.stack([m.nk(wavelength_nm, extrapolate) for m in self.axes], axis=-1)

    def mean(self, name: str | None = None) -> Material:
        """Isotropic average over random orientations: ε = (εx + εy + εz)/3."""
        x, y, z = self.axes

        def eps(w):
            return (x._eps(w) + y._eps(w) + z._eps(w)) / 3.0

        return DerivedMaterial(
            name=name or f"mean of {self.name}",
            eps_function=eps,
            components=(x, y, z),
            reference=f"orientation average (trace/3) of {self.name}",
        )


def uniaxial(ordinary: Material, extraordinary: Material, name: str | None = None) -> DiagonalTensorMaterial:
    """Uniaxial crystal with optic axis along z: diag(ε_o, ε_o, ε_e)."""
    ordinary = _as_axis_material(ordinary, "ordinary")
    extraordinary = _as_axis_material(extraordinary, "extraordinary")
    return DiagonalTensorMaterial(
        ordinary, ordinary, extraordinary,
        name=name or f"uniaxial({ordinary.name}, {extraordinary.name})",
        reference="; ".join(sorted({ordinary.reference, extraordinary.reference} - {""})),
    )


def uniaxial_mean(ordinary: Material, extraordinary: Material, name: str | None = None) -> Material:
    """Isotropic Material of randomly oriented uniaxial crystallites, ε = (2ε_o + ε_e)/3.

    >>> from nmmm.materials import get
    >>> hematite = uniaxial_mean(get("main/Fe2O3/Querry-o"), get("main/Fe2O3/Querry-e"))
    >>> tuple(round(x, 1) for x in hematite.range_nm)  # Querry-o's k < 0 beyond 45 µm is cut
    (210.0, 45454.5)
    """
    ordinary = _as_axis_material(ordinary, "ordinary")
    extraordinary = _as_axis_material(extraordinary, "extraordinary")
    crystal = uniaxial(ordinary, extraordinary, name)
    return crystal.mean(name or f"mean of {ordinary.name} and {extraordinary.name}")
