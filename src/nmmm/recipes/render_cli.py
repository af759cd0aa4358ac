"""``nmmm render`` with recipes: the group of :mod:`nmmm.appearance.render.cli`, whose
``plate --paint`` also takes a recipe file (``--paint my_paint.toml``) once this module has
registered :func:`plate_from_recipe_file` as its recipe loader (the render package sits
below the recipes and never imports them). A ``[plate]`` (glass) or ``[thin_film]`` recipe
gives a :class:`RecipeSpecularPlate`, which the command renders through
:func:`nmmm.appearance.render.transmission.render_specular_plate`."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from nmmm.appearance.render.cli import PLATE_LOADERS, RECIPE_NAMES, render

__all__ = ["render", "plate_from_recipe_file", "RecipeSpecularPlate"]


@dataclass(frozen=True)
class RecipeSpecularPlate:
    """A recipe's glass or thin-film plate (``optics``) of ``size_mm``, in front of ``back_radiance``
    (L,) — a light table under it — or, when None, of the scene behind it."""

    optics: object
    size_mm: tuple
    back_radiance: object = None

    def __repr__(self):
        table = ", on a light table" if self.back_radiance is not None else ""
        return f"<RecipeSpecularPlate {self.optics.name} {self.size_mm[0]:g} x {self.size_mm[1]:g} mm{table}>"

    def render_view(self, camera, lights, environment, max_memory_gb=None):
        """The :class:`~nmmm.appearance.render.SpectralImage` seen by ``camera``."""
        from nmmm.appearance.render.transmission import render_specular_plate

        return render_specular_plate(self.optics, camera, self.size_mm, lights, environment, self.back_radiance,
                                     self.optics.wavelength_nm, max_memory_gb)


def _specular_plate(recipe, res, w):
    from nmmm.appearance.render.lights import spd
    from nmmm.appearance.render.plate.environment import _KM, _luminance_weight
    from nmmm.recipes.plate_image import recipe_specular_optics
    from nmmm.recipes.run import build_materials
    from nmmm.recipes.schema import Image

    im = recipe.image or Image()
    optics = recipe_specular_optics(recipe, build_materials(recipe, w, progress=False), w)
    back = None
    if recipe.plate is not None and im.scene in ("point", "light-table"):  # a glass plate is seen against a light table
        S = spd(recipe.lighting.illuminants[0]).on(w)
        back = im.light_table_cd_m2 * S / (_KM * float(_luminance_weight(w) @ S))
    return RecipeSpecularPlate(optics, (im.plate_cm[0] * 10.0, im.plate_cm[1] * 10.0), back)


def plate_from_recipe_file(path):
    """``(PaintedPlate, wavelength_nm)`` of the recipe file ``path`` for ``nmmm render plate
    --paint RECIPE.toml``: its paint (:func:`nmmm.recipes.plate_image.recipe_paint` for a solid, after running the recipe's
    physics) on its ``[image]`` plate (the default 15 cm × 10 cm plate without one); for a ``[plate]`` or
    ``[thin_film]`` recipe a :class:`RecipeSpecularPlate` (a glass plate on a light table of the first illuminant
    unless its ``[image] scene`` says otherwise)."""
    from nmmm.recipes.plate_image import recipe_paint, recipe_painted_plate
    from nmmm.recipes.run import _effect_brdf, _effect_coat, build_materials, compute
    from nmmm.recipes.schema import load_recipe

    recipe = load_recipe(path)
    if recipe.image is not None:  # the render command draws the plate itself
        recipe = recipe.model_copy(update={"image": None})
    res = compute(recipe, progress=False)
    w = np.asarray(res.wavelength_nm, float)
    if recipe.plate is not None or recipe.thin_film is not None:
        return _specular_plate(load_recipe(path), res, w), w
    brdf = _effect_brdf(recipe) if recipe.effect is not None else \
        recipe_paint(recipe, build_materials(recipe, w, progress=False), w, res)
    own = recipe.effect is not None and recipe.effect.by_composition  # a composition coat's own flake cell
    cell = _effect_coat(recipe).flake_list() if own else True
    return recipe_painted_plate(recipe, brdf, cell, load_recipe(path).image), w


def _shipped_recipe_path(name: str) -> "Path | None":
    """Path of the shipped recipe ``name`` (``red_metallic``), or None."""
    from nmmm.recipes.schema import example_recipes

    return example_recipes().get(name[:-5] if name.endswith(".toml") else name)


if plate_from_recipe_file not in PLATE_LOADERS:
    PLATE_LOADERS.append(plate_from_recipe_file)
if _shipped_recipe_path not in RECIPE_NAMES:
    RECIPE_NAMES.append(_shipped_recipe_path)
