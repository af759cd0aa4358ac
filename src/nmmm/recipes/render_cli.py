"""``nmmm render`` with recipes: the group of :mod:`nmmm.appearance.render.cli`, whose
``plate --paint`` also takes a recipe file (``--paint my_paint.toml``) once this module has
registered :func:`plate_from_recipe_file` as its recipe loader (the render package sits
below the recipes and never imports them)."""

from __future__ import annotations

from nmmm.appearance.render.cli import PLATE_LOADERS, render

__all__ = ["render", "plate_from_recipe_file"]


def plate_from_recipe_file(path):
    """``(PaintedPlate, wavelength_nm)`` of the recipe file ``path`` for ``nmmm render plate
    --paint RECIPE.toml``: its paint (:func:`nmmm.recipes.plate_image.recipe_paint` for a solid, after running the recipe's
    physics) on its ``[image]`` plate (the default 15 cm × 10 cm plate without one)."""
    from nmmm.recipes.plate_image import recipe_paint, recipe_painted_plate
    from nmmm.recipes.run import _effect_brdf, build_materials, compute
    from nmmm.recipes.schema import load_recipe

    recipe = load_recipe(path)
    if recipe.image is not None:  # the render command draws the plate itself
        recipe = recipe.model_copy(update={"image": None})
    res = compute(recipe, progress=False)
    w = res.wavelength_nm
    brdf = _effect_brdf(recipe) if recipe.effect is not None else \
        recipe_paint(recipe, build_materials(recipe, w, progress=False), w, res)
    return recipe_painted_plate(recipe, brdf, True, load_recipe(path).image), w


if plate_from_recipe_file not in PLATE_LOADERS:
    PLATE_LOADERS.append(plate_from_recipe_file)
