"""The painted plate as a scene object: its paint (a spectral BRDF, or the ideal diffuser
:class:`LambertianBRDF`), its flake unit cell tiled periodically, and its size; the seed
paper's grey metallic plate with Poisson flakes (:func:`seed_metallic_plate`) or with the
deposit model's cell (:func:`deposit_metallic_plate`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.spectra import as_wavelength_nm, check_finite

__all__ = ["LambertianBRDF", "PaintedPlate", "seed_metallic_plate", "deposit_metallic_plate"]


@dataclass(frozen=True)
class LambertianBRDF:
    """Ideal diffuse reflector, f = ρ(λ)/π (ρ a constant or ``(wavelength_nm, values)``)."""

    reflectance: object = 1.0
    name: str = "Lambertian"

    def _rho(self, w):
        r = self.reflectance
        if isinstance(r, tuple) and len(r) == 2:
            rho = np.interp(w, np.asarray(r[0], float), np.asarray(r[1], float))
        else:
            rho = np.broadcast_to(np.asarray(check_finite(r, "reflectance"), float), w.shape)
        if np.any(rho < 0) or np.any(rho > 1):
            raise InvalidInputError("Lambertian reflectance must lie in [0, 1]")
        return rho

    def evaluate(self, wavelength_nm, wi, wo, components=None, dtype=np.float64, **_):
        w = as_wavelength_nm(wavelength_nm).ravel()
        shape = np.broadcast_shapes(np.shape(wi), np.shape(wo))[:-1]
        return np.broadcast_to(self._rho(w) / np.pi, shape + (w.size,)).astype(dtype)

    __call__ = evaluate

    def albedo(self, wavelength_nm, wi):
        w = as_wavelength_nm(wavelength_nm).ravel()
        return np.broadcast_to(self._rho(w), np.shape(wi)[:-1] + (w.size,)).copy()


@dataclass(frozen=True, repr=False)
class PaintedPlate:
    """A flat painted plate ``size_mm`` = (width, height) centred on the origin, normal +z.

    ``brdf`` is a :class:`~nmmm.appearance.brdf.PaintBRDF` (or :class:`LambertianBRDF`);
    ``flakes`` an optional :class:`~nmmm.appearance.flakes.FlakeList` unit cell tiled
    periodically (its ``region_nm`` is the cell). With flakes, the paint's statistical
    flake layer is replaced by the cell's (same optics, τ and tilt) so that the smooth
    terms (base seen through the flakes, multiple scattering) match the discrete flakes.
    """

    brdf: object
    flakes: object = None
    size_mm: tuple = (150.0, 100.0)
    _smooth: object = field(default=None, compare=False, repr=False)

    def __post_init__(self):
        s = np.asarray(check_finite(self.size_mm, "size_mm"), float).ravel()
        if s.shape != (2,) or np.any(s <= 0):
            raise InvalidInputError(f"size_mm must be (width, height) > 0 in mm, got {self.size_mm!r}")
        object.__setattr__(self, "size_mm", (float(s[0]), float(s[1])))
        if not hasattr(self.brdf, "evaluate") or not hasattr(self.brdf, "albedo"):
            raise InvalidInputError("brdf must provide evaluate(wavelength_nm, wi, wo) and albedo(wavelength_nm, wi)")
        smooth = self.brdf
        if self.flakes is not None:
            from nmmm.appearance.brdf import PaintBRDF
            from nmmm.appearance.flakes import FlakeList

            if not isinstance(self.flakes, FlakeList):
                raise InvalidInputError("flakes must be a FlakeList (the unit cell tiled over the plate) or None")
            if not isinstance(self.brdf, PaintBRDF):
                raise InvalidInputError("discrete flakes need a PaintBRDF (its clear coat refracts light to them)")
            layer = self.flakes.to_flake_layer()
            if self.brdf.flakes is not None:  # keep the paint's depth band, face roughness and edges
                pf = self.brdf.flakes
                layer = dataclasses.replace(layer, depth_range=pf.depth_range,
                                            surface_roughness=pf.surface_roughness, edge_fraction=pf.edge_fraction)
            smooth = self.brdf.with_(flakes=layer)
        object.__setattr__(self, "_smooth", smooth)

    def __repr__(self):
        fl = "no flakes" if self.flakes is None else f"{len(self.flakes)} flakes per cell, {self.cells[0]}x{self.cells[1]} cells"
        return f"<PaintedPlate {self.size_mm[0]:g}x{self.size_mm[1]:g} mm, {getattr(self.brdf, 'name', 'brdf')}, {fl}>"

    @property
    def cell_mm(self) -> tuple[float, float]:
        if self.flakes is None:
            return self.size_mm
        return self.flakes.region_nm[0] * 1e-6, self.flakes.region_nm[1] * 1e-6

    @property
    def cells(self) -> tuple[int, int]:
        """Number of unit cells along x and y (the last ones possibly cut by the edge)."""
        cw, ch = self.cell_mm
        return int(math.ceil(self.size_mm[0] / cw - 1e-9)), int(math.ceil(self.size_mm[1] / ch - 1e-9))

    @property
    def smooth_brdf(self):
        """The BRDF used for the smooth part of the image (flake layer from the cell)."""
        return self._smooth


def seed_metallic_plate(cells=(332, 240), cell_um: float = 450.0, optical_depth: float = 2.0,
                        tilt_deg: float = 12.0, mean_diameter_um: float = 15.0, diameter_cv: float = 0.3,
                        body_reflectance=0.3, rng=0) -> PaintedPlate:
    """The seed paper's grey metallic plate (example 3): Al flakes (Rakić n, k) with a
    Gaussian tilt in a resin binder (n = 1.5) over a light-grey base, smooth clear coat;
    a 450 µm × 450 µm × 20 µm unit cell tiled 332 × 240 times (14.9 cm × 10.8 cm).
    The number of flakes per cell follows from τ = N ⟨π d²/4⟩ / A."""
    from nmmm.appearance.brdf import metallic_paint
    from nmmm.appearance.flakes import FlakeList

    paint = metallic_paint(optical_depth=optical_depth, tilt=tilt_deg, body_reflectance=body_reflectance,
                           name="grey metallic paint")
    cell = float(cell_um) * 1e3
    mean_area = np.pi * (mean_diameter_um * 1e3) ** 2 / 4 * (1 + diameter_cv ** 2)
    n = int(round(optical_depth * cell * cell / mean_area))
    fl = FlakeList.random(paint.flakes.optics, paint.flakes.tilt, n, region_nm=(cell, cell),
                          mean_diameter_nm=mean_diameter_um * 1e3, diameter_cv=diameter_cv,
                          depth_range_nm=(2e3, 18e3), n_binder=1.5, rng=rng)
    cx, cy = (int(c) for c in cells)
    if cx < 1 or cy < 1:
        raise InvalidInputError(f"cells must be positive counts, got {cells!r}")
    return PaintedPlate(paint, fl, (cx * cell * 1e-6, cy * cell * 1e-6))


def deposit_metallic_plate(cells=(332, 240), seed: int = 1, **kwargs) -> PaintedPlate:
    """The grey metallic plate with its unit cell drawn by the deposit model of
    :func:`nmmm.microstructure.flake_deposit` (Couka, Willot & Jeulin 2012; periodic
    450 × 450 × 20 µm cell, exclusion between flakes), through
    :func:`nmmm.appearance.deposit.grey_metallic_from_deposit` (``kwargs`` go there)."""
    from nmmm.appearance.deposit import grey_metallic_from_deposit

    paint, flakes = grey_metallic_from_deposit(seed=seed, **kwargs)
    cw, ch = flakes.region_nm[0] * 1e-6, flakes.region_nm[1] * 1e-6
    cx, cy = (int(c) for c in cells)
    if cx < 1 or cy < 1:
        raise InvalidInputError(f"cells must be positive counts, got {cells!r}")
    return PaintedPlate(paint, flakes, (cx * cw, cy * ch))
