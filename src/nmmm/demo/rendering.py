"""Worked example: the seed's grey metallic plate in a viewing booth (mono, near/far, stereo),
and the plate image of every shipped paint recipe, on a calibrated display.

- :func:`grey_metallic_recipe_plate` — the plate of the shipped ``grey_metallic`` recipe: the
  :class:`~nmmm.appearance.effect_coat.EffectCoat` its ``[effect]`` builds (the recipe loader's
  :func:`~nmmm.recipes.effect_schema.build_effect_coat`), whose statistical BRDF and deposit
  :class:`~nmmm.appearance.flakes.FlakeList` (glints) are the recipe's multi-angle colour and flakes:
  the demo's grey metallic and the recipe are one paint.
- :func:`demo` — the demo hook (``nmmm demo``): renders that 15 cm × 10 cm grey metallic
  plate (334 × 223 flake unit cells of 450 µm) in a grey booth lit by a D65 source at 45° behind the
  plate, seen from 40 cm at 25° from the normal (the recipes' eye,
  :data:`nmmm.recipes.plate_image.VIEW_TILT_DEG`), so that the source's mirror point falls beyond the
  back edge: the plate runs from the near-specular "face" at the back (aspecular ≈ 10°) to the
  "flop" at the front (≈ 36°). The same view at
  8 cm (individual glints) and at 150 cm (glints merged), the stereo pair at reading
  distance, and every shipped paint recipe in the same booth, all written at 1:1 (one
  image pixel per PNG pixel) through the knee tone map (the booth's white tile is display
  white, 120 cd/m²). Its tables give, per image, the mean luminance of four bands of the
  plate from front to back (the gradient), the clipped fraction, and for the metallic views
  the measured vs predicted per-pixel relative variance of the glints
  (:mod:`nmmm.appearance.sparkle_prediction`).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

__all__ = ["demo", "grey_metallic_recipe_plate", "source_spread_deg"]

#: the eye: 25° from the plate normal, on the viewer's side (−y), as in the recipes' plate images
#: (nmmm.recipes.plate_image.VIEW_TILT_DEG): with the booth's 45° source the plate spans ~10–36°
#: aspecular, face at the back, flop at the front (at 35° the coat mirrored the source on the back edge
#: and the recipe's narrow-tilt grey metallic read near white, 91 -> 417 cd/m², at 150 cm 141 -> 302)
VIEW_TILT_DEG = 25.0
#: distances of the grey metallic views (mm): reading distance, close-up, far
DISTANCES_MM = {"view": 400.0, "near": 80.0, "far": 1500.0}
#: a what-if view: flakes with a surface waviness that widens each glint's lobe to this σ (degrees)
ROUGH_FLAKE_SPREAD_DEG = 4.0


def _eye(distance_mm, tilt_deg=None):
    t = np.radians(VIEW_TILT_DEG if tilt_deg is None else tilt_deg)
    return (0.0, -distance_mm * np.sin(t), distance_mm * np.cos(t))


def source_spread_deg(booth) -> float:
    """The glint lobe width σ_g that matches the booth source: a flat flake mirrors the
    sphere (angular radius a = asin(r/d)) as a uniform disc of solid angle π a²; the
    Gaussian lobe with the same effective solid angle 1/∫g² = 4π σ² has σ = a/2."""
    return float(np.degrees(np.arcsin(booth.source_radius_mm / booth.source_distance_mm)) / 2)


def grey_metallic_recipe_plate(wavelength_nm=None, recipe: str = "grey_metallic"):
    """``(PaintedPlate, EffectCoat)`` of the shipped effect recipe ``recipe``: the coat its ``[effect]``
    builds through the recipe loader, its statistical BRDF on ``wavelength_nm`` (default the
    renderer's grid) and the flakes of its deposit cell tiled over the recipe's ``[image] plate_cm``."""
    from nmmm.appearance.render import PaintedPlate, default_wavelengths
    from nmmm.recipes.effect_schema import build_effect_coat
    from nmmm.recipes.run import build_materials
    from nmmm.recipes.schema import example_path, load_recipe

    w = default_wavelengths() if wavelength_nm is None else np.asarray(wavelength_nm, float)
    rec = load_recipe(example_path(recipe))
    coat = build_effect_coat(rec.effect, build_materials(rec, w, progress=False), name=rec.name)
    paint, flakes = coat.brdf(w)
    size = (150.0, 100.0) if rec.image is None else (rec.image.plate_cm[0] * 10.0, rec.image.plate_cm[1] * 10.0)
    return PaintedPlate(paint, flakes, size), coat


def _band_stats(img, exposure=1.0, bands=4):
    """Mean displayed luminance (cd/m², before the knee) of ``bands`` bands of the plate from
    its front (−y, towards the viewer) to its back, and the display statistics."""
    from nmmm.appearance.sparkle_prediction import pixel_footprint_mm2

    _, disp = img.to_display("sRGB", exposure, "knee")
    x = img.to_xyz()[..., 1] / 100.0 * img.exposure_scale(exposure) * disp["display_white_cd_m2"]
    _, P = pixel_footprint_mm2(img.camera)
    on = img.on_plate
    y = P[..., 1]
    lo, hi = y[on].min(), y[on].max()
    edges = np.linspace(lo, hi, bands + 1)
    means = [float(x[on & (y >= a) & (y <= b)].mean()) for a, b in zip(edges[:-1], edges[1:])]
    row = {f"band {i + 1} cd/m2": round(m, 1) for i, m in enumerate(means)}
    return {**row, "clipped_fraction": round(disp["clipped_fraction"], 4),
            "over_white_fraction": round(disp["over_white_fraction"], 4),
            "plate_mean_cd_m2": round(disp["plate_mean_cd_m2"], 1)}


def _variance_check(plate, cam, light, spread=1.0, bands=4):
    """Measured vs predicted per-pixel relative variance of the glints (550 nm, the point
    light alone), in ``bands`` bands of the plate front to back, with the predicted
    standard error of the measured variance."""
    from nmmm.appearance.render import render_plate
    from nmmm.appearance.sparkle_prediction import (
        glint_footprint_statistics,
        plate_light_geometry,
        variance_standard_error,
    )

    w = np.array([550.0])
    img = render_plate(plate, cam, light, wavelength_nm=w, glint_spread_deg=spread)
    A, P, wi, wo, E = plate_light_geometry(cam, light)
    H, W = A.shape
    E = E * float(light.spectral(w)[0])  # plane irradiance at 550 nm
    brdf = plate.smooth_brdf

    def ev(comps):
        return brdf.evaluate(w, wi.reshape(-1, 3), wo.reshape(-1, 3), components=comps)[:, 0].reshape(H, W) * E

    z = (img.radiance[..., 0] - ev(("specular", "base", "multiple"))) / ev(("flakes",))
    st = glint_footprint_statistics(brdf, plate.flakes, wi, wo, A, glint_spread_deg=spread)
    # leave out the coat's mirror image of the source (its Dirac is not in brdf.evaluate)
    m = -wo * np.array([1.0, 1.0, -1.0])  # the view ray mirrored at the plate, towards the source
    oc = np.asarray(light.position_mm) - P
    t = np.sum(oc * m, axis=-1)
    lamp = (t > 0) & (np.sum(oc * oc, axis=-1) - t * t <= (1.05 * light.radius_mm) ** 2)
    on = img.on_plate & ~lamp
    y = P[..., 1]
    edges = np.linspace(y[on].min(), y[on].max(), bands + 1)
    rows = []
    f2 = np.asarray(st.lobe_mean_factor) ** 2  # z is relative to the BRDF, the variance to the glints' mean
    for a, b in zip(edges[:-1], edges[1:]):
        m = on & (y >= a) & (y <= b)
        s2, _ = variance_standard_error(z[m])
        rows.append({"glinting_flakes_per_pixel": round(float(st.glinting_flakes[m].mean()), 3),
                     "measured": round(s2, 3), "predicted": round(float((st.relative_variance * f2)[m].mean()), 3),
                     "standard_error": round(float((st.variance_error(int(m.sum())) * f2)[m].mean()), 3),
                     "mean_over_brdf": round(float(z[m].mean()), 3),
                     "predicted_mean_over_brdf": round(float(np.asarray(st.lobe_mean_factor)[m].mean()), 3)})
    return rows


def _recipe_images(out, resolution, names=None):
    """Every shipped recipe's plate (mono, ``resolution``) in the booth, or in its own scene
    (light table, sky): PNG + stats — paints, ``[effect]`` coats, and the ``[plate]`` (glass) and
    ``[thin_film]`` recipes (:mod:`nmmm.recipes.plate_image`); ``names`` (stems) picks some of them."""
    from nmmm.recipes.run import compute
    from nmmm.recipes.schema import parse_recipe, read_toml

    examples = Path(__file__).resolve().parents[1] / "recipes" / "examples"
    figures, table, skipped, failed = [], {}, [], []
    paths = sorted(examples.glob("*.toml"))
    if names is not None:
        paths = [p for p in paths if p.stem in set(names)]
    for path in paths:
        data, _, base = read_toml(path)
        data = dict(data)
        im = dict(data.get("image", {}))
        scene = im.get("scene", "point")  # a recipe's own scene (light table, sky, overhead booth) is kept
        im.update(scene="booth" if scene == "point" else scene, stereo=False, pixels=list(resolution), fov_deg=25.0,
                  distance_cm=40.0, exposure=1.0)
        data["image"] = im
        try:
            res = compute(parse_recipe(data, base_dir=base), progress=False)
        except Exception as exc:  # noqa: BLE001 - one recipe that fails must not lose the others' images
            failed.append(f"{path.stem} ({type(exc).__name__}: {str(exc)[:120]})")
            continue
        if "view" not in res.spectral_images:
            skipped.append(path.stem)
            continue
        img = res.spectral_images["view"]
        png = img.write_png(out / f"render_recipe_{path.stem}.png", 1.0, tone_map="knee")
        figures.append(str(png))
        a = img.metadata.get("aspecular_deg")
        table[path.stem] = {"kind": ("glass plate" if res.recipe.plate is not None else "thin film"
                                     if res.recipe.thin_film is not None else "effect" if res.recipe.effect is not None
                                     else "solid paint"), "scene": im["scene"], **_band_stats(img),
                            **({"aspecular deg (min/median/max)": "/".join(f"{x:g}" for x in a)} if a else {})}
    return figures, table, skipped, failed


def demo(output_dir, resolution=(960, 640), small_resolution=(480, 320), recipes: bool = True) -> dict:
    """Render the grey metallic plate (booth view at ``resolution``: 0.16 mm pixels on the
    plate, 1.6 arcmin at 40 cm, near the eye's acuity; near, far and stereo views and the
    recipes at ``small_resolution``) and the shipped paint recipes into ``output_dir``.

    Returns ``{"title", "figures", "tables", "text", "files"}``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from nmmm.appearance.render import (
        PinholeCamera,
        ViewingBooth,
        default_wavelengths,
        render_plate,
        render_stereo_plate,
    )

    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    w = default_wavelengths()
    plate, coat = grey_metallic_recipe_plate(w)  # the recipe's own paint (issue 18 item 2: one model everywhere)
    derived = coat.derived()
    booth = ViewingBooth(source="45")
    scene = dict(booth.scene(plate, w), wavelength_nm=w)
    light = scene["lights"][0]
    spread = source_spread_deg(booth)
    files, figures, tables = [], [], {}
    variance = {}
    imgs = {}
    views = {k: (d, resolution if k == "view" else small_resolution, spread) for k, d in DISTANCES_MM.items()}
    views["view_wavy_flakes"] = (DISTANCES_MM["view"], small_resolution, ROUGH_FLAKE_SPREAD_DEG)
    for name, (dist, res, sig) in views.items():
        cam = PinholeCamera(_eye(dist), (0.0, 0.0, 0.0), fov_deg=25.0, resolution=res)
        img = render_plate(plate, cam, glint_spread_deg=sig, **scene)
        imgs[name] = img
        files.append(img.write_exr(out / f"render_plate_{name}.exr"))
        png = img.write_png(out / f"render_plate_{name}.png", 1.0, tone_map="knee")
        files.append(png)
        figures.append(str(png))
        tables[f"grey metallic, {name} ({dist / 10:g} cm)"] = _band_stats(img)
        variance[name] = _variance_check(plate, cam, light, sig)
    t_mono = time.perf_counter() - t0
    # stereo at reading distance (400 mm), a 40 mm x 27 mm window of the plate
    left, right = render_stereo_plate(plate, position_mm=_eye(400.0), interocular_mm=65.0, fov_deg=6.0,
                                      resolution=small_resolution, glint_spread_deg=spread, **scene)
    for eye, img in (("left", left), ("right", right)):
        files.append(img.write_exr(out / f"render_stereo_{eye}.exr"))
        png = img.write_png(out / f"render_stereo_{eye}.png", 1.0, tone_map="knee")
        files.append(png)
        figures.append(str(png))
    y_l = left.to_xyz()[..., 1]
    y_r = right.to_xyz()[..., 1]

    def glints(y):
        return y > 3 * np.median(y)

    gl, gr = glints(y_l), glints(y_r)
    jacc = float((gl & gr).sum() / max((gl | gr).sum(), 1))
    fig, ax = plt.subplots(1, 3, figsize=(13, 3.4))
    ax[0].imshow(left.to_display("sRGB", 1.0, "knee")[0])
    ax[0].set_title("left eye")
    ax[1].imshow(right.to_display("sRGB", 1.0, "knee")[0])
    ax[1].set_title("right eye")
    rgb = np.zeros(gl.shape + (3,))
    rgb[..., 0] = gl
    rgb[..., 1] = gr
    rgb[..., 2] = gl & gr
    ax[2].imshow(rgb)
    ax[2].set_title(f"glints: left (red), right (green), both (white)\nshared fraction {jacc:.2f}")
    for a in ax:
        a.axis("off")
    fig.tight_layout()
    fig_path = out / "render_stereo_glints.png"
    fig.savefig(fig_path, dpi=110)
    plt.close(fig)
    figures.append(str(fig_path))
    recipe_note = ""
    if recipes:
        rfig, rtab, skipped, failed = _recipe_images(out, small_resolution)
        figures += rfig
        files += [Path(f) for f in rfig]
        tables.update({f"recipe {k}": v for k, v in rtab.items()})
        recipe_note = (f" Every shipped recipe ({', '.join(rtab)}) is shown in the same booth (or its own scene)"
                       + (f"; not rendered: {', '.join(skipped)}." if skipped else ".")
                       + (f" Failed: {'; '.join(failed)}." if failed else ""))
    # a painted sphere through Mitsuba 3, when the optional extra is usable
    try:
        from nmmm.appearance.render import DirectionalLight, UniformEnvironment
        from nmmm.appearance.render.mitsuba_scene import render_object

        (sphere,) = render_object(plate.smooth_brdf, "sphere", DirectionalLight.from_angles(35.0, 90.0, "D65", 1.0),
                                  UniformEnvironment("D65", radiance=0.02 / np.pi), distance_mm=400.0, fov_deg=20.0,
                                  resolution=(200, 200), spp=32)
        files.append(sphere.write_exr(out / "render_sphere_mitsuba.exr"))
        sphere_png = sphere.write_png(out / "render_sphere_mitsuba.png", exposure=0.6)
        files.append(sphere_png)
        figures.append(str(sphere_png))
        recipe_note += " A sphere with the same (statistical) paint was rendered spectrally by Mitsuba 3 (nmmm_paint)."
    except Exception as exc:  # noqa: BLE001 - optional extra
        recipe_note += f" Mitsuba sphere skipped ({type(exc).__name__}: {str(exc)[:120]})."
    var_rows = [{"view": name, "band (front to back)": i + 1, **r}
                for name, rows in variance.items() for i, r in enumerate(rows)]
    # sparkle and graininess from the composition (issue 18 item 5): camera along the normal,
    # light at 15/45/75 deg, 40 um pixels, no rendering
    from nmmm.appearance.sparkle_prediction import sparkle_from_composition

    sp = sparkle_from_composition(plate.smooth_brdf, plate.flakes, (15.0, 45.0, 75.0), n_images=4)
    sparkle_rows = [{"illumination (deg)": a, "sparkles per mm2": round(r["density_per_mm2"], 2),
                     "area fraction": round(r["area_fraction"], 4), "mean contrast": round(r["mean_contrast"], 1),
                     "sparkle intensity": round(r["sparkle_intensity"], 4), "graininess": round(r["graininess"], 2),
                     "glinting flakes per 40 um pixel": round(r["glinting_flakes_per_pixel"], 4)}
                    for a, r in sp.items()]
    elapsed = time.perf_counter() - t0
    v = {k: rows[len(rows) // 2] for k, rows in variance.items()}
    text = (
        f"Grey metallic plate of the shipped recipe grey_metallic.toml (the same EffectCoat, statistical BRDF and deposit "
        f"flakes as the recipe's multi-angle colour: optical depth {derived.optical_depth:.3g}, mean tilt "
        f"{derived.mean_tilt_deg:.2f} deg), {plate.size_mm[0]:.1f} x {plate.size_mm[1]:.1f} mm, {plate.cells[0]} x "
        f"{plate.cells[1]} unit cells of {plate.cell_mm[0] * 1e3:.0f} um with {len(plate.flakes)} Al flakes each, in a grey booth (walls 0.2) under a D65 "
        f"source at 45 deg, 2000 lx, seen at {VIEW_TILT_DEG:g} deg from 40 cm ({resolution[0]}x{resolution[1]}, "
        f"{t_mono:.1f} s for the three views; glint lobe sigma {spread:.2f} deg, the source's solid angle): the clear "
        "coat mirrors the source just beyond the back edge of the plate, the plate is brightest at the back "
        "(near-specular face) and darker towards the front (flop); the band luminances are in the tables. Per-pixel glint variance relative to the statistical BRDF, measured vs "
        "predicted from the flake statistics (compound Poisson, nmmm.appearance.sparkle_prediction), a middle band: "
        + "; ".join(f"{k} {r['measured']:.3g} vs {r['predicted']:.3g} (se {r['standard_error']:.2g}, "
                    f"{r['glinting_flakes_per_pixel']:.2g} glinting flakes per pixel)" for k, r in v.items())
        + f". The glints' mean over the statistical BRDF runs {variance['view'][0]['mean_over_brdf']:.2f} (front) to "
        f"{variance['view'][-1]['mean_over_brdf']:.2f} (back, near specular) at 40 cm, where the prediction from the "
        "tilt pdf is 1.00"
        + ("" if variance["view"][-1]["mean_over_brdf"] < 1.1 else
           ": the coat's tilt pdf is a kernel estimate ("
           f"{derived.tilt.name.split('(')[-1].rstrip(')')}) of the {len(plate.flakes)} deposit normals that the "
           "plate tiles, and it holds less of the near-zero tilts than those flakes do, so near specular the discrete "
           "flakes are brighter than the statistical paint (an open inconsistency of the effect coat, not of the "
           "renderer)")
        + f". Close up the glints are single bright points; far away they merge into a smooth metallic grey. "
        f"What if the flakes were wavy (each glint's lobe widened to sigma {ROUGH_FLAKE_SPREAD_DEG:g} deg, "
        f"render_plate_view_wavy_flakes.png, {small_resolution[0]}x{small_resolution[1]}): about 8x more, 8x dimmer "
        "glints per pixel than with flat flakes at the same resolution, a finer, silkier grain. "
        f"Stereo pair at 400 mm, interocular 65 mm: only {jacc:.0%} of the glinting pixels are shared by both eyes."
        + recipe_note
    )
    return {
        "title": "Spectral rendering: the grey metallic plate in a viewing booth, and every paint recipe",
        "figures": figures,
        "tables": {"render": {"glints_view": int(imgs["view"].metadata["n_glints"]),
                              "glints_left": int(left.metadata["n_glints"]),
                              "glints_right": int(right.metadata["n_glints"]), "shared_glint_fraction": jacc,
                              "seconds": round(elapsed, 2)},
                   "Plate images: mean displayed luminance of 4 bands of the plate, front (1) to back (4), "
                   "before the knee; clipped fraction after it": [{"image": k, **v} for k, v in tables.items()],
                   "Sparkle predicted from the composition (nmmm.appearance.sparkle_prediction; camera along "
                   "the normal, 40 um pixels, the definitions of nmmm.appearance.sparkle)": sparkle_rows,
                   "Glint variance per pixel relative to the statistical BRDF: measured vs predicted "
                   "(compound Poisson from the flake statistics, 550 nm, the booth's source)": var_rows},
        "text": text,
        "files": [str(f) for f in files],
    }
