"""The ``[effect]`` table of a recipe: a flake (metallic / interference) paint.

- :class:`Effect` — validated ``[effect]`` (see :mod:`nmmm.recipes.schema` for the whole recipe).
- :class:`EffectFlakes`, :class:`FlakeLayerSpec` — ``[effect.flakes]`` and its ``layers``.
- :func:`check_effect_references` — the compounds an ``[effect]`` names exist.
- :func:`build_effect_coat` — ``[effect]`` -> :class:`nmmm.appearance.effect_coat.EffectCoat`.

An effect coat **by its composition** (issue 18)::

    [effect]
    binder = "resin"                 # a compound (its index is the clear coat's too); default n = 1.5
    coat_thickness_um = 20           # basecoat holding the flakes and pigments
    clear_coat_um = 30
    substrate_reflectance = 0.35     # primer under the basecoat (internal diffuse reflectance)
    derive = "deposit"               # or "volume" (no deposit: tau = fraction * H / t, flakes through the coat)
    [effect.flakes]
    material = "aluminium"           # "aluminium", "mica" or a compound; or layers = [{compound, thickness_nm}, ...]
    diameter_um = 20                 # log-normal mean, with diameter_std_um
    thickness_nm = 300
    fraction = 0.008                 # volume fraction of the basecoat
    tilt_std_deg = 6                 # orientation spread (deposit law); or tilt_density = {tilt_deg, density_per_sr}
    face_roughness = 0.05            # GGX alpha of the flake faces (default 0 = mirror flakes; ~0.05 assumed)
    edge_width_nm = 500              # scattering rim of each flake, f_e = 4 w / D (default 0 = none; 500 nm assumed)
    [[effect.pigments]]              # the [[pigments]] of a film: compound, fraction, size, shape
    compound = "hematite"
    fraction = 0.03
    diameter_nm = 250

The flakes' optical depth, tilt distribution and depth band are derived from these numbers.
**Expert override** (and the older form of the table): ``optical_depth`` and ``tilt_deg``
(Gaussian σ per steradian) replace the derived values when given. With ``flakes = "aluminium"``
or ``"mica"`` (a string, the older form) the paint is the statistical one of those two keys over
a base of internal reflectance ``body_reflectance``, as before.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from nmmm.recipes.schema_fields import Fraction, NonNegative, Pigment, Positive, _Strict

__all__ = ["Effect", "EffectFlakes", "FlakeLayerSpec", "TiltDensity", "check_effect_references", "build_effect_coat"]

_BUILTIN_FLAKES = ("aluminium", "mica")


class FlakeLayerSpec(_Strict):
    """One layer of a layered flake (top to bottom)."""

    compound: str
    thickness_nm: Positive
    coherent: bool = True


class TiltDensity(_Strict):
    """A tabulated density of flake normals per steradian at tilt angles (deg)."""

    tilt_deg: list[float] = Field(min_length=2)
    density_per_sr: list[float] = Field(min_length=2)


class EffectFlakes(_Strict):
    """``[effect.flakes]``: the flakes as made (see the module docstring)."""

    material: str | None = None
    layers: list[FlakeLayerSpec] | None = None
    diameter_um: Positive = 20.0
    diameter_std_um: NonNegative = 6.0
    thickness_nm: Positive | None = None
    fraction: Annotated[float, Field(ge=0.0, lt=1.0, allow_inf_nan=False)]
    tilt_std_deg: Annotated[float, Field(gt=0.0, le=90.0, allow_inf_nan=False)] = 6.0
    tilt_density: TiltDensity | None = None
    face_roughness: Annotated[float, Field(ge=0.0, le=1.0, allow_inf_nan=False)] = 0.0
    edge_width_nm: NonNegative = 0.0

    @model_validator(mode="after")
    def _one_material(self):
        if (self.material is None) == (self.layers is None):
            raise ValueError("give exactly one of 'material' (aluminium, mica or a compound) or 'layers' (a layered "
                             "flake: [{compound, thickness_nm}, ...] top to bottom)")
        if self.material is not None and self.thickness_nm is None and self.material != "aluminium":
            raise ValueError("thickness_nm: required for a flake of one material (nm)")
        return self


class Effect(_Strict):
    """A flake paint: an effect coat by its composition (``[effect.flakes]``), or the older
    statistical form ``flakes = "aluminium" | "mica"`` with ``optical_depth`` and ``tilt_deg``."""

    flakes: Literal["aluminium", "mica"] | EffectFlakes = "aluminium"
    aluminium_key: str = "main/Al/Rakic"
    tio2_thickness_nm: Positive = 120.0
    mica_thickness_nm: Positive = 350.0
    optical_depth: Positive = 2.0
    tilt_deg: Positive = 12.0
    body_reflectance: Fraction = 0.3
    coat_index: Annotated[float, Field(gt=1.0, lt=3.0)] = 1.5
    roughness: Annotated[float, Field(ge=0.0, le=1.0)] = 0.0
    # -- the coat by its composition -----------------------------------------------------
    pigments: list[Pigment] = Field(default_factory=list)
    binder: str | None = None
    coat_thickness_um: Positive = 20.0
    clear_coat_um: NonNegative = 30.0
    substrate_reflectance: Fraction | None = None
    derive: Literal["deposit", "volume"] = "deposit"
    seed: int = 1
    cell_um: Positive = 450.0

    @property
    def by_composition(self) -> bool:
        return isinstance(self.flakes, EffectFlakes)

    @model_validator(mode="after")
    def _composition_keys(self):
        if not self.by_composition:
            used = sorted(k for k in ("pigments", "binder", "coat_thickness_um", "clear_coat_um", "substrate_reflectance",
                                      "derive", "seed", "cell_um") if k in self.model_fields_set)
            if used:
                raise ValueError(f"{', '.join(used)}: describe the flakes as a [effect.flakes] table (material, "
                                 f"diameter_um, thickness_nm, fraction, tilt_std_deg) to use these keys; "
                                 f"flakes = {self.flakes!r} is the older statistical form")
        else:
            total = sum(p.fraction for p in self.pigments) + self.flakes.fraction
            if total >= 1.0:
                raise ValueError(f"pigments: pigments and flakes fill {total:g} of the basecoat (>= 1); fractions are "
                                 "of the dry basecoat")
            if "body_reflectance" in self.model_fields_set and self.substrate_reflectance is not None:
                raise ValueError("body_reflectance: give substrate_reflectance (the primer under the basecoat) only")
        return self


def check_effect_references(e: Effect, need) -> None:
    """Raise (through ``need(path, name)``) for compounds an ``[effect]`` names but the recipe lacks."""
    if not e.by_composition:
        return
    need("effect.binder", e.binder)
    f = e.flakes
    if f.material is not None and f.material not in _BUILTIN_FLAKES:
        need("effect.flakes.material", f.material)
    for j, la in enumerate(f.layers or []):
        need(f"effect.flakes.layers[{j}].compound", la.compound)
    for j, p in enumerate(e.pigments):
        need(f"effect.pigments[{j}].compound", p.compound)


def build_effect_coat(e: Effect, mats: dict, name: str = "effect coat"):
    """The :class:`~nmmm.appearance.effect_coat.EffectCoat` of a composition ``[effect]``;
    an error of the coat is a :class:`RecipeError` naming the ``effect.`` key."""
    from nmmm.appearance.effect_coat import EffectCoat, FlakeSpec
    from nmmm.errors import InvalidInputError, RecipeError
    from nmmm.layers import Layer, Stack
    from nmmm.recipes.paint_stack import components

    f = e.flakes
    nb = mats[e.binder] if e.binder is not None else e.coat_index
    try:
        if f.layers is not None:
            layers = []
            for j, la in enumerate(f.layers):
                try:
                    layers.append(Layer(mats[la.compound], la.thickness_nm, la.coherent))
                except InvalidInputError as exc:
                    raise InvalidInputError(f"flakes.layers[{j}]: {exc}") from None
            material = Stack(layers, ambient=1.5, substrate=1.5)
        else:
            material = f.material if f.material in _BUILTIN_FLAKES else mats[f.material]
        thickness = f.thickness_nm if (f.thickness_nm is not None or f.layers is not None) else 300.0
        dens = None if f.tilt_density is None else (f.tilt_density.tilt_deg, f.tilt_density.density_per_sr)
        spec = FlakeSpec(material, f.diameter_um, f.diameter_std_um, thickness, f.fraction, f.tilt_std_deg, dens,
                         name=f.material or "layered flake", face_roughness=f.face_roughness,
                         edge_width_nm=f.edge_width_nm)
        sub = e.substrate_reflectance if e.substrate_reflectance is not None else e.body_reflectance
        given = e.model_fields_set
        coat = EffectCoat(spec, components(e.pigments, mats), nb, e.coat_thickness_um * 1e3, e.clear_coat_um * 1e3,
                          e.roughness, sub, e.derive, (e.cell_um * 1e3, e.cell_um * 1e3), e.seed,
                          e.optical_depth if "optical_depth" in given else None,
                          e.tilt_deg if "tilt_deg" in given else None, name=name)
        coat.derived()  # the deposit's own refusals surface here, with their key
    except InvalidInputError as exc:
        raise RecipeError(f"effect.{exc}") from None
    return coat
