"""Stimulus pairs for the 2AFC validation experiment, produced from recipes.

The experiment (:mod:`nmmm.experiment`) shows a computed image of a plate beside a
photograph of the real plate. This module makes the computed half from a recipe, so that a
whole ``pairs.toml`` comes from one call (or ``nmmm run RECIPE --pair-with PHOTO``).

- :func:`recipe_image` — the sRGB image of a computed recipe that stands for the plate: the
  rendered view (a recipe with ``[image]``; the left eye of a stereo pair unless another view
  is named), otherwise a uniform swatch of the primary spectrum's colour.
- :func:`make_experiment_pairs` — ``[(recipe, photo_path[, label]), ...]`` -> ``pairs.toml``
  via :func:`nmmm.experiment.pairs.make_pairs_file` (validated with
  :func:`nmmm.experiment.pairs.load_pairs`).

Data flow: recipes import experiment, never the reverse.

References
----------
- Macmillan, N. A., Creelman, C. D. (2005). *Detection Theory: A User's Guide*, 2nd ed.,
  ch. 7 (two-alternative forced choice).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nmmm.errors import RecipeError

__all__ = ["recipe_image", "make_experiment_pairs"]

#: longest side (px) of a uniform swatch made for a recipe without an ``[image]`` table
SWATCH_MAX_PX = 512


def _photo_size(photo) -> tuple[int, int]:
    from nmmm.experiment.pairs import check_image

    return check_image(photo, what="photograph")


def recipe_image(res, *, view: str | None = None, size_px: tuple[int, int] | None = None) -> np.ndarray:
    """The (H, W, 3) sRGB image in [0, 1] of a computed recipe (:class:`~nmmm.recipes.run.RunResult`).

    With rendered images (``[image]`` in the recipe), ``view`` names one of them
    (``"left eye"``, ``"right eye"``, ``"view"``); default: ``"view"``, else ``"left eye"``.
    Without, the image is a uniform swatch of the primary spectrum's sRGB colour under the
    first illuminant, ``size_px = (width, height)`` pixels (default 256 x 256).
    """
    if res.images:
        if view is None:
            view = "view" if "view" in res.images else ("left eye" if "left eye" in res.images else next(iter(res.images)))
        if view not in res.images:
            raise RecipeError(f"image: no rendered view {view!r}; this recipe renders {sorted(res.images)}")
        return np.clip(np.asarray(res.images[view], float), 0.0, 1.0)
    if view is not None:
        raise RecipeError(f"image: view {view!r} asked for, but the recipe {res.recipe.name!r} renders no image "
                          "(add an [image] table to an [effect] recipe)")
    ill = res.recipe.lighting.illuminants[0]
    row = next((c for c in res.colours if c["spectrum"] == res.primary and c["illuminant"] == ill), None)
    if row is None:
        raise RecipeError(f"image: the recipe {res.recipe.name!r} has no colour of its primary spectrum to show")
    w, h = size_px or (256, 256)
    return np.broadcast_to(np.asarray(row["srgb"], float), (int(h), int(w), 3)).copy()


def _swatch_size(photo_wh) -> tuple[int, int]:
    w, h = photo_wh
    s = min(1.0, SWATCH_MAX_PX / max(w, h))
    return max(1, round(w * s)), max(1, round(h * s))


def _computed(recipe, progress):
    """A RunResult: given, or computed from a path / TOML text / raw dict."""
    from nmmm.recipes.run import RunResult, compute
    from nmmm.recipes.schema import parse_recipe, read_toml

    if isinstance(recipe, RunResult):
        return recipe
    if isinstance(recipe, Path):
        recipe = str(recipe)
    raw, source, base = read_toml(recipe)
    return compute(parse_recipe(raw, source, base), source or "", progress=progress)


def make_experiment_pairs(items, out_toml, *, view: str | None = None, progress: bool = True,
                          check_images: bool = True, **settings) -> Path:
    """Compute each recipe's image and write a ``pairs.toml`` of (computed image, photograph).

    Parameters
    ----------
    items : iterable of (recipe, photo_path) or (recipe, photo_path, label)
        ``recipe``: a recipe file path, TOML text, raw dict or an already computed
        :class:`~nmmm.recipes.run.RunResult`; ``photo_path``: the photograph of the real plate;
        ``label`` (default: the recipe's name) becomes the pair id.
    out_toml : path
        The pairs file; the computed images go to ``<its folder>/rendered/<pair id>.png``.
    view : str, optional
        Which rendered view to use (see :func:`recipe_image`).
    **settings
        ``[experiment]`` keys (:class:`nmmm.experiment.pairs.ExperimentSettings`), e.g.
        ``repetitions=2``.

    A rendered image must have the photograph's aspect ratio (within 1 %, as
    :func:`~nmmm.experiment.pairs.load_pairs` requires); a mismatch is a :class:`RecipeError`
    naming ``image.pixels``. A recipe without ``[image]`` gives a uniform swatch in the
    photograph's aspect ratio. Stereo pairs are not made here (use ``make_pairs_file``'s
    ``stereo_pairs`` with the left/right views of :attr:`RunResult.images`).
    """
    from nmmm.experiment.pairs import make_pairs_file

    triples = []
    for i, item in enumerate(items, start=1):
        if not isinstance(item, (tuple, list)) or len(item) not in (2, 3):
            raise RecipeError(f"pairs[{i}]: expected (recipe, photo_path) or (recipe, photo_path, label), got {item!r}")
        recipe, photo = item[0], item[1]
        photo_wh = _photo_size(photo)
        res = _computed(recipe, progress)
        label = item[2] if len(item) == 3 else res.recipe.name
        img = recipe_image(res, view=view, size_px=_swatch_size(photo_wh))
        h, w = img.shape[:2]
        if abs((w / h) / (photo_wh[0] / photo_wh[1]) - 1) > 0.01:
            raise RecipeError(f"image.pixels: pair {i} ({label!r}): the rendered image is {w}x{h} px but the "
                              f"photograph {str(photo)!r} is {photo_wh[0]}x{photo_wh[1]} px; set image.pixels to "
                              f"the photograph's aspect ratio (or crop the photograph), or the shape gives it away")
        triples.append((img, photo, label))
    if not triples:
        raise RecipeError("pairs: no (recipe, photo_path) given")
    return make_pairs_file(triples, out_toml, check_images=check_images, **settings)
