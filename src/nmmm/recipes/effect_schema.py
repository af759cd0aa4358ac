"""The ``[effect]`` table of a recipe: a flake (metallic / interference) paint.

- :class:`Effect` — validated ``[effect]`` (see :mod:`nmmm.recipes.schema` for the whole recipe).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from nmmm.recipes.schema_fields import Fraction, Positive, _Strict

__all__ = ["Effect"]


class Effect(_Strict):
    """A flake paint: metallic (aluminium) or interference (TiO2-coated mica) flakes."""

    flakes: Literal["aluminium", "mica"] = "aluminium"
    aluminium_key: str = "main/Al/Rakic"
    tio2_thickness_nm: Positive = 120.0
    mica_thickness_nm: Positive = 350.0
    optical_depth: Positive = 2.0
    tilt_deg: Positive = 12.0
    body_reflectance: Fraction = 0.3
    coat_index: Annotated[float, Field(gt=1.0, lt=3.0)] = 1.5
    roughness: Annotated[float, Field(ge=0.0, le=1.0)] = 0.0
