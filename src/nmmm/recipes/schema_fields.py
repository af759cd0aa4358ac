"""Field types and the pigment table shared by the recipe schema (:mod:`nmmm.recipes.schema`)
and its effect section (:mod:`nmmm.recipes.effect_schema`).

- ``Fraction``, ``Positive``, ``NonNegative``, ``AngleDeg``, ``AspecularDeg`` — validated floats
  whose messages say what a right value is.
- :class:`Pigment` — one ``[pigment]`` / ``[[pigments]]`` entry (compound, fraction, shape and
  size, mapped to an equivalent sphere for Mie); :data:`PIGMENT_SIZE_KEYS`.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, model_validator

__all__ = ["Fraction", "Positive", "NonNegative", "AngleDeg", "AspecularDeg", "PIGMENT_SIZE_KEYS", "Pigment"]


def _fraction(v: float) -> float:
    if not (isinstance(v, (int, float)) and math.isfinite(v) and 0.0 <= v <= 1.0):
        raise ValueError(f"must be in [0, 1] (a volume fraction, not a percentage: 5 % is 0.05); got {v!r}")
    return float(v)


def _positive(v: float) -> float:
    if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
        raise ValueError(f"must be a finite number > 0; got {v!r}")
    return float(v)


def _non_negative(v: float) -> float:
    if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
        raise ValueError(f"must be a finite number >= 0; got {v!r}")
    return float(v)


def _angle(v: float) -> float:
    if not (math.isfinite(v) and -90.0 < v < 90.0):
        raise ValueError(f"must be an angle in degrees in (-90, 90); got {v!r}")
    return float(v)


def _aspecular(v: float) -> float:
    if not (math.isfinite(v) and -90.0 < v < 180.0 and v != 0.0):
        raise ValueError(f"must be an aspecular angle in degrees in (-90, 180), not 0 (the mirror); got {v!r}")
    return float(v)


Fraction = Annotated[float, AfterValidator(_fraction)]
Positive = Annotated[float, AfterValidator(_positive)]
NonNegative = Annotated[float, AfterValidator(_non_negative)]
AngleDeg = Annotated[float, AfterValidator(_angle)]
AspecularDeg = Annotated[float, AfterValidator(_aspecular)]


class _Strict(BaseModel):
    # strict: no silent coercion of TOML types ("0.05" or true for a fraction, "20" for a
    # thickness are refused naming the key); ints are still accepted for floats
    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)


#: the size keys that define each pigment shape (one set per alternative)
PIGMENT_SIZE_KEYS = {
    "sphere": ({"diameter_nm"},),
    "cube": ({"edge_nm"}, {"body_diagonal_nm"}),
    "rod": ({"length_nm", "diameter_nm"},),
    "spheroid": ({"polar_diameter_nm", "equatorial_diameter_nm"},),
    "rhombohedron": ({"edge_nm", "angle_deg"},),
}


class Pigment(_Strict):
    """Pigment particles of the paint film (equivalent spheres for Mie)."""

    compound: str
    fraction: Fraction
    shape: Literal["sphere", "cube", "rod", "spheroid", "rhombohedron"] = "sphere"
    diameter_nm: Positive | None = None
    body_diagonal_nm: Positive | None = None
    edge_nm: Positive | None = None
    length_nm: Positive | None = None
    polar_diameter_nm: Positive | None = None
    equatorial_diameter_nm: Positive | None = None
    #: rhombohedral angle (deg) of a rhombohedron (with edge_nm); hematite's {01-12} faces: 85.7
    angle_deg: Annotated[float, Field(gt=0.0, lt=120.0, allow_inf_nan=False)] | None = None
    equivalent_sphere: Literal["volume", "surface", "volume_to_surface"] = "volume"
    size_spread: Annotated[float, Field(ge=1.0, le=3.0)] = 1.0
    size_nodes: int = Field(default=24, ge=4, le=200)
    dependent_scattering: bool = False

    def dims(self) -> dict:
        keys = ("diameter_nm", "body_diagonal_nm", "edge_nm", "length_nm", "polar_diameter_nm", "equatorial_diameter_nm",
                "angle_deg")
        return {k: getattr(self, k) for k in keys if getattr(self, k) is not None}

    @model_validator(mode="after")
    def _size(self):
        from nmmm.layers.distributions import equivalent_sphere_diameter

        given = set(self.dims())
        allowed = PIGMENT_SIZE_KEYS[self.shape]
        if given not in allowed:
            want = " or ".join(" + ".join(sorted(a)) for a in allowed)
            raise ValueError(f"a {self.shape} pigment is sized by {want}; got {sorted(given) or 'no size'}")

        try:
            equivalent_sphere_diameter(self.shape, self.equivalent_sphere, **self.dims())
        except Exception as exc:
            raise ValueError(f"size of a {self.shape}: {exc}") from None
        return self

    def equivalent_diameter_nm(self) -> float:
        from nmmm.layers.distributions import equivalent_sphere_diameter

        return equivalent_sphere_diameter(self.shape, self.equivalent_sphere, **self.dims())
