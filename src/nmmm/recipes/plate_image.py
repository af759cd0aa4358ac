"""Plate images of any paint recipe (issue 19 item 1).

A recipe's ``[image]`` is rendered from the **same** optics that give its colours:

- an ``[effect]`` paint: its flake BRDF (``nmmm.recipes.run._effect_brdf``), with a
  tiled unit cell of discrete flakes (glints) when the renderer is ``"auto"``;
- a solid paint (``[film]`` or ``[[coats]]``): a clear coat of the top binder over the
  Lambertian body whose Saunderson (1942) reading is the recipe's primary 0°/d spectrum
  (:func:`nmmm.layers.paint.body_reflectance_from_reading`, the same body the film's
  multi-angle colours use), so that the plate's diffuse colour is the recipe's colour.

:func:`recipe_paint` gives that BRDF, :func:`recipe_plate_images` renders the mono view
or the stereo pair with :mod:`nmmm.appearance.render`, and :func:`recipe_painted_plate`
serves ``nmmm render plate --paint RECIPE.toml`` (:mod:`nmmm.recipes.render_cli`).
"""

from __future__ import annotations

import numpy as np

from nmmm.errors import RecipeError

__all__ = ["recipe_paint", "recipe_plate_images", "recipe_painted_plate"]


def _top_binder(recipe):
    if recipe.coats is not None:
        return recipe.coats[0].binder, "coats[0].binder"
    return recipe.binder.compound, "binder.compound"


def recipe_paint(recipe, mats, w, res):
    """The spectral BRDF of the recipe's solid paint on grid ``w`` (nm), after its macro ran
    into ``res`` (an ``[effect]`` paint's is :func:`nmmm.recipes.run._effect_brdf`).

    Raises :class:`RecipeError` for recipes with no painted surface (``[plate]``, ``[thin_film]``)."""
    if recipe.effect is not None:
        raise RecipeError("effect: the flake BRDF of an [effect] recipe is built by nmmm.recipes.run, not here")
    if recipe.film is None and recipe.coats is None:
        macro = "plate" if recipe.plate is not None else "thin_film"
        raise RecipeError(f"image: a plate image needs a paint ([film], [[coats]] or [effect]); a [{macro}] recipe "
                          "has no painted surface to render — remove [image]")
    from nmmm.appearance.brdf import ClearCoat, PaintBRDF
    from nmmm.layers.paint import body_reflectance_from_reading
    from nmmm.recipes.paint_stack import geometry_of

    name, _ = _top_binder(recipe)
    nb = np.real(np.broadcast_to(np.asarray(mats[name].nk(w)), w.shape)).astype(float)
    specular = "included" if geometry_of(recipe).startswith("di") else "excluded"
    rho = body_reflectance_from_reading(np.asarray(res.spectra[res.primary], float), nb, specular)
    return PaintBRDF(ClearCoat(mats[name]), (w, rho), None, name=recipe.name)


def _flake_cell(recipe, brdf, im):
    from nmmm.appearance.flakes import FlakeList

    e = recipe.effect
    cell = im.cell_um * 1e3
    d = im.flake_diameter_um * 1e3
    cv = 0.3
    n = max(1, int(round(e.optical_depth * cell * cell / (np.pi * d * d / 4 * (1 + cv**2)))))
    return FlakeList.random(brdf.flakes.optics, brdf.flakes.tilt, n, region_nm=(cell, cell), mean_diameter_nm=d,
                            diameter_cv=cv, depth_range_nm=(2e3, 18e3), n_binder=e.coat_index, rng=im.seed)


def _eye_centre_mm(im):
    view_tilt = np.radians(30.0)
    return np.array([0.0, -im.distance_cm * np.sin(view_tilt), im.distance_cm * np.cos(view_tilt)]) * 10.0


def recipe_painted_plate(recipe, brdf, flakes: bool = True, image=None):
    """The :class:`~nmmm.appearance.render.PaintedPlate` of ``[image]`` (``image``, default the
    recipe's, else the defaults: a 15 cm × 10 cm plate); an effect paint carries its flake
    unit cell when ``flakes``."""
    from nmmm.appearance.render import PaintedPlate
    from nmmm.recipes.schema import Image

    im = image or recipe.image or Image()
    cell = _flake_cell(recipe, brdf, im) if (flakes and recipe.effect is not None) else None
    return PaintedPlate(brdf, cell, (im.plate_cm[0] * 10.0, im.plate_cm[1] * 10.0))


def recipe_plate_images(recipe, brdf, w, keep: dict, flakes: bool = True) -> dict:
    """sRGB images (name -> (H, W, 3) in [0, 1]) of the ``[image]`` plate: ``"view"`` (mono)
    or ``"left eye"``/``"right eye"``; the spectral images go into ``keep``."""
    from nmmm.appearance.render import PinholeCamera, PointLight, render_plate, render_stereo_plate

    im = recipe.image
    plate = recipe_painted_plate(recipe, brdf, flakes, im)
    centre = _eye_centre_mm(im)
    if im.scene.startswith("booth"):
        from nmmm.appearance.render import ViewingBooth

        booth = ViewingBooth(source="overhead" if im.scene == "booth-overhead" else "45", wall_reflectance=im.wall_reflectance,
                             floor_reflectance=im.wall_reflectance, illuminant=recipe.lighting.illuminants[0])
        kw = dict(booth.scene(plate, w), wavelength_nm=w)
    else:
        light = PointLight(tuple(np.asarray(im.light_position_cm, float) * 10.0), recipe.lighting.illuminants[0])
        kw = dict(lights=[light], wavelength_nm=w)
    if im.stereo:
        left, right = render_stereo_plate(plate, position_mm=tuple(centre), look_at_mm=(0.0, 0.0, 0.0),
                                          interocular_mm=im.eye_separation_cm * 10.0, fov_deg=im.fov_deg,
                                          resolution=tuple(im.pixels), **kw)
        named = {"left eye": left, "right eye": right}
    else:
        cam = PinholeCamera(position_mm=tuple(centre), look_at_mm=(0.0, 0.0, 0.0), fov_deg=im.fov_deg,
                            resolution=tuple(im.pixels))
        named = {"view": render_plate(plate, cam, **kw)}
    keep.update(named)
    if im.scene.startswith("booth"):  # a calibrated display: the booth's white tile is white, highlights tone-mapped
        return {k: v.to_display("sRGB", im.exposure, "knee")[0] for k, v in named.items()}
    return {k: np.asarray(v.to_srgb(im.exposure), float) for k, v in named.items()}


def add_solid_plate_images(recipe, mats, w, res) -> None:
    """Render ``[image]`` of a solid-paint recipe into ``res`` (after its macro ran)."""
    if recipe.image is None or not recipe.outputs.images or recipe.effect is not None:
        return
    brdf = recipe_paint(recipe, mats, w, res)
    res.images.update(recipe_plate_images(recipe, brdf, w, res.spectral_images))
    res.notes.append("Images: nmmm.appearance.render — the plate of the solid paint (a smooth clear coat of the top "
                     "binder over the Lambertian body whose 0°/d reading is the recipe's primary spectrum) under a "
                     "point light of the first illuminant.")

