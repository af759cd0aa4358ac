"""Plate images of any recipe (issue 19 items 1-2): paints, glass plates, thin-film stacks.

A recipe's ``[image]`` is rendered from the **same** optics that give its colours:

- an ``[effect]`` paint: its flake BRDF (``nmmm.recipes.run._effect_brdf``), with a
  tiled unit cell of discrete flakes (glints) when the renderer is ``"auto"``;
- a solid paint (``[film]`` or ``[[coats]]``): a clear coat of the top binder over the
  Lambertian body whose Saunderson (1942) reading is the recipe's primary 0°/d spectrum
  (:func:`nmmm.layers.paint.body_reflectance_from_reading`, the same body the film's
  multi-angle colours use), so that the plate's diffuse colour is the recipe's colour;
- a ``[plate]`` (glass) or ``[thin_film]`` recipe: its plate optics (:func:`recipe_specular_optics`,
  :mod:`nmmm.appearance.render.transmission`), seen in transmission against a light table and in
  reflection of the scene.

``[image] scene``: ``"point"``, ``"booth"`` / ``"booth-overhead"``, ``"sky"`` (the CIE standard general
sky, :mod:`nmmm.appearance.render.cie_sky`) or ``"light-table"``; ``tilt_deg`` tilts the plate about
its horizontal axis (:mod:`nmmm.appearance.render.plate_tilt`).

:func:`recipe_paint` gives that BRDF, :func:`recipe_plate_images` renders the mono view
or the stereo pair with :mod:`nmmm.appearance.render`, and :func:`recipe_painted_plate`
serves ``nmmm render plate --paint RECIPE.toml`` (:mod:`nmmm.recipes.render_cli`).
"""

from __future__ import annotations

import numpy as np

from nmmm.errors import RecipeError

__all__ = ["recipe_paint", "recipe_specular_optics", "recipe_plate_images", "recipe_painted_plate"]


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
    """Flakes drawn at the expert ``[effect] optical_depth`` (a composition ``[effect]``'s callers pass
    its EffectCoat's own cell instead, :func:`recipe_painted_plate`)."""
    from nmmm.appearance.flakes import FlakeList

    e = recipe.effect
    cell = im.cell_um * 1e3
    d = im.flake_diameter_um * 1e3
    cv = 0.3
    n = max(1, int(round(e.optical_depth * cell * cell / (np.pi * d * d / 4 * (1 + cv**2)))))
    return FlakeList.random(brdf.flakes.optics, brdf.flakes.tilt, n, region_nm=(cell, cell), mean_diameter_nm=d,
                            diameter_cv=cv, depth_range_nm=(2e3, 18e3), n_binder=e.coat_index, rng=im.seed)


#: the eye's angle from the plate normal (degrees, on the viewer's side). With the booth's 45° source the
#: plate then spans about 10–36° aspecular (measured per image: ``metadata["aspecular_deg"]``), so a
#: metallic shows its near-specular face at the back and its flop at the front; at 30° the whole plate lay
#: 5–25° off specular, where a narrow-tilt aluminium is several times the white tile (nearly white).
VIEW_TILT_DEG = 25.0


def _eye_centre_mm(im):
    view_tilt = np.radians(VIEW_TILT_DEG)
    return np.array([0.0, -im.distance_cm * np.sin(view_tilt), im.distance_cm * np.cos(view_tilt)]) * 10.0


def recipe_painted_plate(recipe, brdf, flakes=True, image=None):
    """The :class:`~nmmm.appearance.render.PaintedPlate` of ``[image]`` (``image``, default the
    recipe's, else the defaults: a 15 cm × 10 cm plate); an effect paint carries a flake
    unit cell when ``flakes``: a :class:`~nmmm.appearance.flakes.FlakeList` given here (a composition
    ``[effect]``'s EffectCoat cell, the flakes behind its BRDF), or ``True``: drawn at the expert optical depth."""
    from nmmm.appearance.render import PaintedPlate
    from nmmm.recipes.schema import Image

    im = image or recipe.image or Image()
    if flakes is not None and not isinstance(flakes, bool):
        cell = flakes
    else:
        cell = _flake_cell(recipe, brdf, im) if (flakes and recipe.effect is not None) else None
    return PaintedPlate(brdf, cell, (im.plate_cm[0] * 10.0, im.plate_cm[1] * 10.0))


def recipe_specular_optics(recipe, mats, w):
    """The plate optics of a ``[plate]`` (a :class:`~nmmm.appearance.render.transmission.GlassPlate`
    of ``plate.compound`` and the first of ``plate.thickness_nm``: the recipe's primary spectrum is its
    normal transmittance) or ``[thin_film]`` recipe (a
    :class:`~nmmm.appearance.render.transmission.ThinFilmPlate` of its stack)."""
    from nmmm.appearance.render.transmission import GlassPlate, ThinFilmPlate

    if recipe.plate is not None:
        p = recipe.plate
        nk = np.broadcast_to(np.asarray(mats[p.compound].nk(w)), w.shape)
        return GlassPlate(w, nk, p.thickness_nm[0], name=f"{p.compound} plate {p.thickness_nm[0] / 1e6:g} mm")
    from nmmm.layers.thinfilm import Layer, Stack

    tf = recipe.thin_film
    med = (lambda n: 1.0 if n is None else mats[n])
    stack = Stack([Layer(mats[la.compound], la.thickness_nm, coherent=la.coherent) for la in tf.layers],
                  ambient=med(tf.ambient), substrate=med(tf.substrate))
    return ThinFilmPlate.from_stack(stack, w, name=f"thin-film stack ({len(tf.layers)} layers)")


def _specular(recipe) -> bool:
    return recipe.plate is not None or recipe.thin_film is not None


def _scene_of(recipe, w, size_mm):
    """``(lights, environment, back_radiance, tone_mapped)`` of ``[image] scene`` in the world frame.

    ``"point"`` is the recipe's point light (for a glass plate: the light table; for a thin film:
    the 45° booth, since a mirror-like plate shows only what it mirrors); ``"booth"`` /
    ``"booth-overhead"`` the grey viewing booth; ``"sky"`` the CIE standard general sky
    ``sky_type`` (the sun behind the plate, at ``sky_sun_elevation_deg``; its disc when ``sky_sun_lux`` > 0;
    ground of ``wall_reflectance``); ``"light-table"`` the 45° booth with a light table of
    ``light_table_cd_m2`` (the first illuminant's spectrum) under the plate."""
    from nmmm.appearance.render import PointLight, ViewingBooth

    im = recipe.image
    illum = recipe.lighting.illuminants[0]
    scene = im.scene
    if scene == "point" and _specular(recipe):
        scene = "light-table" if recipe.plate is not None else "booth"
    if scene == "sky":
        from nmmm.appearance.render.cie_sky import cie_sky_environment

        from nmmm.appearance.render.cie_sky import cie_sun

        env = cie_sky_environment(w, im.sky_type, im.sky_sun_elevation_deg, 90.0, im.sky_cct_k,
                                  im.sky_illuminance_lux, im.wall_reflectance, sun_normal_illuminance_lux=im.sky_sun_lux)
        sun = [cie_sun(w, im.sky_sun_elevation_deg, 90.0, im.sky_sun_lux, im.sky_cct_k)] if im.sky_sun_lux > 0 else []
        return sun, env, None, True
    if scene == "point":
        return [PointLight(tuple(np.asarray(im.light_position_cm, float) * 10.0), illum)], None, None, False
    booth = ViewingBooth(source="overhead" if scene == "booth-overhead" else "45", wall_reflectance=im.wall_reflectance,
                         floor_reflectance=im.wall_reflectance, illuminant=illum)
    booth.check_plate(type("P", (), {"size_mm": size_mm})())
    lights, env = booth.lights(), booth.environment(w, 256, 512)
    back = None
    if scene == "light-table":
        from nmmm.appearance.render.lights import spd
        from nmmm.appearance.render.plate.environment import _KM, _luminance_weight

        S = spd(illum).on(w)
        back = im.light_table_cd_m2 * S / (_KM * float(_luminance_weight(w) @ S))
    return lights, env, back, True


def _flat_white(lights, env, back, w):
    """Radiance (L,) of the scene's white reference in the world frame — the light table, or a
    white diffuser lying flat at the plate centre under ``lights`` and ``env`` (as the renderers
    compute it for an untilted plate) — so that tilting the plate does not move the exposure."""
    from nmmm.appearance.render.lights import LatLongEnvironment, UniformEnvironment
    from nmmm.appearance.render.plate.renderer import _light_at

    if back is not None:
        return np.asarray(back, float).copy()
    white = np.zeros(w.size)
    for lt in lights:
        _, s = _light_at(lt, np.zeros((1, 3)))
        white += s[0] * lt.spectral(w) / np.pi
    if isinstance(env, UniformEnvironment):
        white += env.spectral(w)
    elif isinstance(env, LatLongEnvironment):
        qd, qs, qr = env.upper_quadrature(w)
        white += (qs * qd[:, 2]) @ qr / np.pi
    return white


def _aspecular_range(cam, lights):
    """Aspecular angle (degrees, per pixel) of the first light with a
    position or direction (the booth's source, the sun) — the angle between the view ray mirrored
    at the plate (plate frame) and the direction to the light; None without such a light."""
    from nmmm.appearance.sparkle_prediction import plate_light_geometry

    lt = next((x for x in lights if hasattr(x, "position_mm") or hasattr(x, "direction")), None)
    if lt is None:
        return None
    _, _, wi, wo, _ = plate_light_geometry(cam, lt)
    m = wo * np.array([-1.0, -1.0, 1.0])  # the mirror direction of the view ray
    return np.degrees(np.arccos(np.clip(np.sum(m * wi, axis=-1), -1.0, 1.0)))


def recipe_plate_images(recipe, brdf, w, keep: dict, flakes=True) -> dict:
    """sRGB images (name -> (H, W, 3) in [0, 1]) of the ``[image]`` plate: ``"view"`` (mono)
    or ``"left eye"``/``"right eye"``; the spectral images go into ``keep``.

    ``brdf`` is the paint's BRDF, or for ``[plate]`` / ``[thin_film]`` recipes the plate optics of
    :func:`recipe_specular_optics` (rendered by :func:`~nmmm.appearance.render.transmission.render_specular_plate`).
    The plate is tilted by ``[image] tilt_deg`` about its horizontal axis (the scene is turned into
    the plate's frame, :func:`~nmmm.appearance.render.plate_tilt.tilted_scene`); the exposure stays
    the white tile lying flat in the scene (a tilted plate turned away from the source looks darker
    against an unchanged booth)."""
    from nmmm.appearance.render import PinholeCamera, render_plate
    from nmmm.appearance.render.camera import stereo_pair
    from nmmm.appearance.render.plate_tilt import tilted_scene

    im = recipe.image
    size_mm = (im.plate_cm[0] * 10.0, im.plate_cm[1] * 10.0)
    lights, env, back, tone_mapped = _scene_of(recipe, w, size_mm)
    centre = _eye_centre_mm(im)
    if im.stereo:
        cams = dict(zip(("left eye", "right eye"), stereo_pair(tuple(centre), (0.0, 0.0, 0.0), im.eye_separation_cm * 10.0,
                                                                (0.0, 1.0, 0.0), im.fov_deg, tuple(im.pixels))))
    else:
        cams = {"view": PinholeCamera(position_mm=tuple(centre), look_at_mm=(0.0, 0.0, 0.0), fov_deg=im.fov_deg,
                                      resolution=tuple(im.pixels))}
    named = {}
    white = _flat_white(lights, env, back, w) if im.tilt_deg != 0 else None
    plate = None if _specular(recipe) else recipe_painted_plate(recipe, brdf, flakes, im)
    for k, cam in cams.items():
        c, lt, e = tilted_scene(im.tilt_deg, cam, lights, env)
        if plate is None:
            from nmmm.appearance.render.transmission import render_specular_plate

            img = render_specular_plate(brdf, c, size_mm, lt, e, back, w)
        else:
            img = render_plate(plate, c, lights=lt, environment=e, wavelength_nm=w)
        a = _aspecular_range(c, lt)
        if a is not None and img.on_plate.any():  # what part of the face-to-flop range the plate shows
            a = a[img.on_plate]
            img.metadata.update(view_deg_from_normal=VIEW_TILT_DEG, aspecular_deg=(
                round(float(a.min()), 1), round(float(np.median(a)), 1), round(float(a.max()), 1)))
        named[k] = img
    if white is not None:  # the exposure is the booth's white tile lying flat, not a tile tilted with the plate
        from dataclasses import replace

        named = {k: replace(v, white_radiance=white) for k, v in named.items()}
    keep.update(named)
    if tone_mapped:  # a calibrated display: the booth's white tile (or the light table) is white, highlights tone-mapped
        return {k: v.to_display("sRGB", im.exposure, "knee")[0] for k, v in named.items()}
    return {k: np.asarray(v.to_srgb(im.exposure), float) for k, v in named.items()}


def add_solid_plate_images(recipe, mats, w, res) -> None:
    """Render ``[image]`` of a solid-paint recipe into ``res`` (after its macro ran)."""
    if recipe.image is None or not recipe.outputs.images or recipe.effect is not None:
        return
    if _specular(recipe):
        optics = recipe_specular_optics(recipe, mats, w)
        res.images.update(recipe_plate_images(recipe, optics, w, res.spectral_images))
        res.notes.append(f"Images: nmmm.appearance.render.transmission — the {optics.name} (reflectance R(θ, λ) and "
                         "transmittance T(θ, λ) of the same optics as the recipe's spectra) in the scene "
                         f"'{recipe.image.scene}', tilted {recipe.image.tilt_deg:g}°.")
        return
    brdf = recipe_paint(recipe, mats, w, res)
    res.images.update(recipe_plate_images(recipe, brdf, w, res.spectral_images))
    res.notes.append("Images: nmmm.appearance.render — the plate of the solid paint (a smooth clear coat of the top "
                     "binder over the Lambertian body whose 0°/d reading is the recipe's primary spectrum) in the scene "
                     f"'{recipe.image.scene}' (the first illuminant), tilted {recipe.image.tilt_deg:g}°.")

