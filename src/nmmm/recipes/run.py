"""Run a recipe: compounds -> levels (effective media) -> macro object -> spectra and colours.

- :func:`compute` — a :class:`~nmmm.recipes.schema.Recipe` -> :class:`RunResult` (no files).
- :func:`run_recipe` — load, compute and write everything into a folder: ``spectra.csv``,
  ``results.nc`` (xarray, h5netcdf engine), ``colours.csv``, plots (PNG), images (PNG) and a
  self-contained ``report.html``; returns the :class:`RunResult` with ``files`` filled in.
- :func:`build_materials` — the recipe's compounds and level results as Materials.
- :func:`scalar_results` — the flat numbers of a result (CIELAB per spectrum and
  illuminant, …) used by sweeps and comparisons.

Each physical step calls the public API of its package: :mod:`nmmm.materials` for the
compounds, :func:`nmmm.ema.mixtures` or :func:`nmmm.homogenize.homogenize` for each level,
:mod:`nmmm.layers.paint` (Mie + Kubelka–Munk / adding–doubling) for a paint film,
:class:`nmmm.layers.Stack` for thin films, :func:`nmmm.layers.thick_plate.plate_transmittance` for
a plate, :class:`nmmm.appearance.brdf.PaintBRDF` for flake paints, and
:mod:`nmmm.colour` for CIELAB and sRGB.
"""

from __future__ import annotations

import csv
import json
import re
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from nmmm.errors import NmmmError, RecipeError
from nmmm.recipes.schema import Recipe, parse_recipe, read_toml

__all__ = ["RunResult", "compute", "run_recipe", "build_materials", "scalar_results", "write_outputs"]


@dataclass
class RunResult:
    """Everything a run produced. Spectra are dimensionless (reflectance, transmittance or
    reflectance factor), on ``wavelength_nm``."""

    recipe: Recipe
    recipe_text: str
    wavelength_nm: np.ndarray
    spectra: dict = field(default_factory=dict)        # label -> (L,) values, unit 1
    primary: str = ""                                    # label of the main spectrum
    materials: dict = field(default_factory=dict)      # compound -> (L,) complex n + ik
    colours: list = field(default_factory=list)        # rows: spectrum, illuminant, L, a, b, C, h_deg, srgb
    multiangle: list = field(default_factory=list)     # rows: aspecular_deg, L, a, b, C, h_deg
    images: dict = field(default_factory=dict)         # name -> (H, W, 3) sRGB in [0, 1]
    scalars: dict = field(default_factory=dict)        # name_with_unit -> float
    notes: list = field(default_factory=list)
    timings_s: dict = field(default_factory=dict)
    files: dict = field(default_factory=dict)          # kind -> path (after write_outputs)
    spectral_images: dict = field(default_factory=dict)  # name -> nmmm.appearance.render.SpectralImage
    summary: dict = field(default_factory=dict)        # formulator numbers for the report's summary box

    def to_xarray(self):
        """The run as a labelled xarray Dataset (:func:`nmmm.recipes.labelled.run_to_xarray`)."""
        from nmmm.recipes.labelled import run_to_xarray

        return run_to_xarray(self)

    def _repr_html_(self) -> str:
        from nmmm.recipes.labelled import run_result_html

        return run_result_html(self)


# --------------------------------------------------------------------------------------
# compounds and levels


def _compound_material(name, spec, base_dir):
    from nmmm import materials as M

    label = spec.label or name
    if spec.database is not None:
        return M.get(spec.database)
    if spec.uniaxial is not None:
        return M.uniaxial_mean(M.get(spec.uniaxial[0]), M.get(spec.uniaxial[1]), name=label)
    if spec.model is not None:
        try:  # explicit-unit keys (B_um2, B_nm2, ...) -> the model's own units
            params = M.models.canonical_parameters(spec.model, dict(spec.params))
        except NmmmError as exc:
            raise RecipeError(f"compounds.{name}.params: {exc}") from None
        params.setdefault("name", label)
        try:
            return M.MODELS[spec.model](**params)
        except TypeError as exc:
            raise RecipeError(f"compounds.{name}.params: {exc}") from None
    if spec.file is not None:
        from nmmm.recipes.schema import compound_file

        p = compound_file(name, spec.file, base_dir)  # confined to the recipe's folder
        if p.suffix.lower() in (".yml", ".yaml"):
            return M.read_yaml(p, name=label)
        return M.read_csv(p, name=label)
    return M.Constant(nk=complex(spec.n, spec.k), name=label)


def _shape(inc):
    from nmmm.ema.shapes import Shape

    if inc.shape == "sphere":
        return Shape.sphere()
    if inc.shape == "cube":
        return Shape.cube()
    if inc.shape == "spheroid":
        return Shape.spheroid(inc.aspect_ratio)
    return Shape.ellipsoid(*inc.semi_axes_nm)


def _fft_level(lev, host, inc_mat, w, progress=None, index: int = 0):
    from nmmm.homogenize import homogenize
    from nmmm.microstructure import boolean_spheres, hardcore_spheres

    ms = lev.microstructure
    inc = lev.inclusions[0]
    shape = (ms.size_px,) * ms.ndim
    if ms.model == "hardcore":
        cell = hardcore_spheres(shape, ms.voxel_nm, inc.radius_nm, inc.fraction, seed=ms.seed)
    else:
        cell = boolean_spheres(shape, ms.voxel_nm, inc.radius_nm, fraction=inc.fraction, seed=ms.seed)
    lo, hi = float(w[0]), float(w[-1])
    nodes = np.unique(np.r_[np.arange(lo, hi, lev.fft_step_nm), hi])
    key = f"levels[{index}]"
    advice = (f"Lower {key}.microstructure.size_px (now {ms.size_px}; the work grows as its cube in 3-D) or "
              f"raise {key}.fft_step_nm (now {lev.fft_step_nm:g} nm: {nodes.size} wavelengths solved)")
    return homogenize(cell, {0: host, 1: inc_mat}, wavelength_nm=nodes, name=lev.name, progress=progress,
                      work_advice=advice)


def build_materials(recipe: Recipe, wavelength_nm=None, progress: bool | None = None) -> dict:
    """Compounds and level results as :class:`~nmmm.materials.Material` objects, in
    recipe order; a database key, file or model error is a :class:`RecipeError` naming the
    compound's key. ``progress``: the FFT levels' progress bar (None: shown for long solves)."""
    from nmmm.ema.mixtures import Inclusion, mix
    from nmmm.materials import size_damped

    w = _grid(recipe) if wavelength_nm is None else wavelength_nm
    mats = {}
    for name, spec in recipe.compounds.items():
        try:
            mats[name] = _compound_material(name, spec, recipe.base_dir)
            if spec.size_damping is not None:  # Kreibig damping of a metal's free electrons
                mats[name] = size_damped(mats[name], **spec.size_damping.model_dump())
            mats[name].nk(w)
        except RecipeError:
            raise
        except NmmmError as exc:
            raise RecipeError(f"compounds.{name}: {exc}") from None
    for i, lev in enumerate(recipe.levels):
        try:
            if lev.method == "fft":
                mats[lev.name] = _fft_level(lev, mats[lev.host], mats[lev.inclusions[0].compound], w, progress, i)
            else:
                incs = [Inclusion(mats[inc.compound], inc.fraction, _shape(inc), inc.radius_nm) for inc in lev.inclusions]
                mats[lev.name] = mix(mats[lev.host], incs, method=lev.method, name=lev.name)
            mats[lev.name].nk(w)
        except NmmmError as exc:
            raise RecipeError(f"levels[{i}] ({lev.name}): {exc}") from None
    return mats


def _grid(recipe):
    s = recipe.spectral
    n = int(round((s.stop_nm - s.start_nm) / s.step_nm))
    w = s.start_nm + s.step_nm * np.arange(n + 1)
    return w[w <= s.stop_nm + 1e-9]


# --------------------------------------------------------------------------------------
# macro objects


def _film(recipe, mats, w, res):
    from nmmm.layers.distributions import lognormal, monodisperse
    from nmmm.layers.paint import PaintFilm, paint_reflectance
    from nmmm.recipes.paint_stack import add_formulator, paint_system

    if recipe.pigments is not None or recipe.substrate is not None or recipe.measurement.geometry is not None:
        return paint_system(recipe, mats, w, res)  # several pigments / a substrate / a geometry: the stack path
    pg, f = recipe.pigment, recipe.film
    d = pg.equivalent_diameter_nm()
    dist = monodisperse(d) if pg.size_spread == 1.0 else lognormal(d, pg.size_spread, n_nodes=pg.size_nodes)
    res.scalars["equivalent_diameter_nm"] = d

    def film(rho):
        try:
            return PaintFilm(pigment=mats[pg.compound], binder=mats[recipe.binder.compound], distribution=dist,
                             volume_fraction=pg.fraction, thickness_nm=f.thickness_nm, substrate_reflectance=rho,
                             clear_coat_thickness_nm=f.clear_coat_nm, dependent_scattering=pg.dependent_scattering)
        except NmmmError as exc:
            raise RecipeError(f"film: {exc}") from None

    r = paint_reflectance(film(f.substrate_reflectance), w, solver=f.solver, specular=f.specular, quad_pts=f.quad_pts)
    if f.solver == "km":  # say where Kubelka-Munk is off against adding-doubling (issue 24 item 5)
        from nmmm.layers.km_validity import check_km_film

        res.scalars["km_vs_ad_delta_e00"] = check_km_film(film(f.substrate_reflectance), w, stacklevel=3)
    label = f"reflectance (substrate {f.substrate_reflectance:g})"
    res.spectra[label] = r.reflectance
    res.primary = label
    if f.substrate_reflectance > 0:
        rb = paint_reflectance(film(0.0), w, solver=f.solver, specular=f.specular, quad_pts=f.quad_pts)
        res.spectra["reflectance (black substrate)"] = rb.reflectance
    if recipe.viewing.multiangle:
        from nmmm.appearance.brdf import opaque_paint_from_film

        paint = opaque_paint_from_film(film(f.substrate_reflectance), w, name=recipe.name)
        body = "Kubelka–Munk body"
        if f.solver == "ad":  # the Lambertian body that reads the adding-doubling 0°/d spectrum (issue 16)
            from nmmm.appearance.brdf import PaintBRDF
            from nmmm.layers.paint import body_reflectance_from_reading

            nb = np.real(np.broadcast_to(mats[recipe.binder.compound].nk(w), w.shape))
            rho = body_reflectance_from_reading(r.reflectance, nb, f.specular)
            paint = PaintBRDF(paint.coat, (w, rho), None, name=paint.name)
            body = "Lambertian body whose Saunderson reading is the adding–doubling 0°/d spectrum"
        _multiangle(recipe, paint, w, res, add_spectra=False)
        res.notes.append("Multi-angle colour: the same film as the base of a solid paint BRDF "
                         f"(nmmm.appearance.brdf.opaque_paint_from_film: {body} under a smooth coat of the binder).")
    res.notes.append(f"Paint film: {pg.compound} {pg.shape}s (equal-{pg.equivalent_sphere} sphere D = {d:.1f} nm, "
                     f"geometric spread {pg.size_spread:g}) at volume fraction {pg.fraction:g} in {recipe.binder.compound}; "
                     f"film {f.thickness_nm / 1e3:g} µm, clear coat {f.clear_coat_nm / 1e3:g} µm, solver {f.solver}, "
                     f"0°/d, specular {f.specular}.")
    add_formulator(recipe, mats, w, res)


def _plate(recipe, mats, w, res):
    from nmmm.layers.thick_plate import plate_transmittance

    p = recipe.plate
    for name in (p.compound, p.reference_compound):
        if name is None:
            continue
        nk = mats[name].nk(w)
        for t in p.thickness_nm:
            label = f"transmittance {name} ({t / 1e6:g} mm)"
            res.spectra[label] = plate_transmittance(nk, w, t)
            if not res.primary:
                res.primary = label
    res.notes.append("Plate in air, normal incidence, Beer–Lambert absorption (α = 4πk/λ) with incoherent "
                     "Fresnel reflections at both faces.")


def _thin_film(recipe, mats, w, res):
    from nmmm.layers.thinfilm import Layer, Stack

    tf = recipe.thin_film
    med = (lambda n: 1.0 if n is None else mats[n])
    stack = Stack([Layer(mats[l.compound], l.thickness_nm, coherent=l.coherent) for l in tf.layers],
                  ambient=med(tf.ambient), substrate=med(tf.substrate))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        R = np.asarray(stack.rt(w, np.asarray(tf.angles_deg, float)).R).reshape(w.size, len(tf.angles_deg))
    for c in caught:  # Stack's advice in the recipe's terms: the key that makes a layer incoherent
        text = str(c.message)
        m = re.match(r"layer (\d+) .* is coherent but .*; a layer this thick should be incoherent", text)
        if m:
            text = text[:m.end()] + f": set thin_film.layers[{m.group(1)}].coherent = false in the recipe"
        warnings.warn(text, c.category, stacklevel=2)
    for j, a in enumerate(tf.angles_deg):
        label = f"reflectance ({a:g}° incidence)"
        res.spectra[label] = R[:, j]
        if not res.primary:
            res.primary = label
    res.notes.append("Layer stack by transfer matrices (coherent layers interfere; incoherent ones add "
                     "intensities), unpolarized specular reflectance: "
                     + " | ".join(f"{l.compound} {l.thickness_nm:g} nm{'' if l.coherent else ' (incoherent)'}"
                                  for l in tf.layers) + ".")


def _effect_coat(recipe, mats=None, w=None):
    """The recipe's [effect] by its composition as an nmmm.appearance EffectCoat (issue 18)."""
    from nmmm.recipes.effect_schema import build_effect_coat

    return build_effect_coat(recipe.effect, build_materials(recipe, w) if mats is None else mats, name=recipe.name)


def _effect_brdf(recipe, mats=None, w=None):
    from nmmm.appearance.brdf import ClearCoat, PaintBRDF
    from nmmm.appearance.flakes import FlakeLayer, aluminium_flakes, gaussian_tilt, mica_pigment

    e = recipe.effect
    if e.by_composition:
        w = _grid(recipe) if w is None else w
        return _effect_coat(recipe, mats, w).brdf(w)[0]
    optics = aluminium_flakes(e.aluminium_key) if e.flakes == "aluminium" else mica_pigment(e.tio2_thickness_nm, e.mica_thickness_nm)
    return PaintBRDF(ClearCoat(e.coat_index, e.roughness), e.body_reflectance,
                     FlakeLayer(optics, gaussian_tilt(e.tilt_deg), e.optical_depth), name=recipe.name)


def _multiangle(recipe, brdf, w, res, add_spectra: bool):
    """Reflectance factors π f at the aspecular angles of ``[viewing]`` and their CIELAB."""
    from nmmm.colour import spectra_to_lab

    v = recipe.viewing
    g = np.asarray(v.aspecular_deg, float)
    th_i = np.radians(v.illumination_deg)
    th_v = np.radians(v.illumination_deg - g)
    if np.any(np.abs(th_v) >= np.pi / 2):
        raise RecipeError("viewing.aspecular_deg: a detector angle lies below the horizon "
                          f"(illumination {v.illumination_deg:g}° − aspecular must be in (−90°, 90°))")
    wi = np.stack([np.full_like(g, -np.sin(th_i)), np.zeros_like(g), np.full_like(g, np.cos(th_i))], axis=-1)
    wo = np.stack([np.sin(th_v), np.zeros_like(g), np.cos(th_v)], axis=-1)
    Rf = np.pi * np.asarray(brdf(w, wi, wo), float)
    if add_spectra:
        for j, a in enumerate(g):
            res.spectra[f"reflectance factor (aspecular {a:g}°)"] = Rf[j]
    ill = recipe.lighting.illuminants[0]
    lab = spectra_to_lab(w, Rf, illuminant=ill, observer=recipe.lighting.observer)
    for a, (L, A, B) in zip(g, lab):
        res.multiangle.append(dict(aspecular_deg=float(a), illuminant=ill, L=float(L), a=float(A), b=float(B),
                                   C=float(np.hypot(A, B)), h_deg=float(np.degrees(np.arctan2(B, A)) % 360)))
    Ls = {float(a): float(L) for a, L in zip(g, lab[:, 0])}
    if all(k in Ls for k in (15.0, 45.0, 110.0)):
        try:
            from nmmm.appearance.multiangle import flop_index_alman1987

            res.scalars["flop_index"] = float(flop_index_alman1987(Ls[15.0], Ls[45.0], Ls[110.0]))
        except ImportError:  # pragma: no cover - Alman (1987) as in nmmm.appearance.multiangle
            res.scalars["flop_index"] = float(2.69 * (Ls[15.0] - Ls[110.0]) ** 1.11 / Ls[45.0] ** 0.86)
    return g


def _realisation_note(r: dict) -> str:
    """The deposit cell's own statistics (± SE) beside the ensemble values the colour uses."""
    if "optical_depth_cell" not in r:
        return ""
    full = r.get("band_realisations_refused", 0)
    full = f", {full} more overflowing the coat: it is near full" if full else ""
    return (f" (band top ± {r['band_top_se']:.2g}, mean of {r['band_realisations']} deposits{full}); the cell's "
            f"{r['n_flakes_in_cell']} flakes: τ = {r['optical_depth_cell']:.3g} ± {r['optical_depth_cell_se']:.2g}, "
            f"rms tilt {r['tilt_rms_deg_cell']:.3g}° ± {r['tilt_rms_deg_cell_se']:.2g}° (law {r['tilt_rms_deg_law']:.3g}°)")


def _effect(recipe, mats, w, res):
    coat = _effect_coat(recipe, mats, w) if recipe.effect.by_composition else None
    brdf = _effect_brdf(recipe) if coat is None else coat.brdf(w)[0]
    v = recipe.viewing
    g = _multiangle(recipe, brdf, w, res, add_spectra=True)
    res.primary = f"reflectance factor (aspecular {g[np.argmin(np.abs(g - 45))]:g}°)"
    if coat is not None:
        d = coat.derived()
        res.scalars.update(flake_optical_depth=d.optical_depth, flakes_per_mm2=d.number_density_per_mm2,
                           flake_mean_tilt_deg=d.mean_tilt_deg)
        res.notes.append(f"Effect coat by its composition (nmmm.appearance.effect_coat, derive = {d.source}): "
                         f"{d.number_density_per_mm2:.4g} flakes/mm², optical depth τ = {d.optical_depth:.3g} "
                         f"(projected {d.projected_optical_depth:.3g}), mean tilt {d.mean_tilt_deg:.2f}°, flakes in "
                         f"{d.depth_range[0]:.2f}–{d.depth_range[1]:.2f} of the basecoat"
                         + _realisation_note(getattr(d, "realisation", {}))
                         + (f"; expert override: {', '.join(d.overridden)}" if d.overridden else "") + ".")
    else:
        res.notes.append(f"Flake paint BRDF ({recipe.effect.flakes} flakes, optical depth {recipe.effect.optical_depth:g}, "
                         f"Gaussian tilt σ = {recipe.effect.tilt_deg:g}°, base reflectance {recipe.effect.body_reflectance:g}); "
                         f"reflectance factors π f at {v.illumination_deg:g}° illumination, in the plane of incidence.")
    if recipe.image is not None and recipe.outputs.images:
        images = None
        if recipe.image.scene != "point" or recipe.image.tilt_deg:  # booth, CIE sky, tilt (issue 19): plate_image
            from nmmm.recipes.plate_image import recipe_plate_images

            images = recipe_plate_images(recipe, brdf, w, res.spectral_images, flakes=(  # the coat's own flake cell
                coat.flake_list() if coat is not None else True) if recipe.image.renderer == "auto" else False)
            res.notes.append(f"Images: nmmm.appearance.render — the plate (tilt {recipe.image.tilt_deg:g}°) in the scene "
                             f"'{recipe.image.scene}' (walls/ground {recipe.image.wall_reflectance:g}), tone-mapped.")
        elif recipe.image.renderer == "auto":
            try:
                images = _stereo_rendered(recipe, brdf, w, res.spectral_images, coat=coat)
                cell_um, dia_um = ((coat.cell_nm[0] / 1e3, coat.flakes.diameter_um) if coat is not None
                                   else (recipe.image.cell_um, recipe.image.flake_diameter_um))
                res.notes.append(
                    "Images: nmmm.appearance.render — the plate tiled with a "
                    f"{cell_um:g} µm unit cell of discrete flakes (mean diameter "
                    f"{dia_um:g} µm) whose glints differ between the eyes, under a point light.")
            except ImportError:
                images = None
        if images is None:
            images = _stereo(recipe, brdf, w)
            res.notes.append("Images: the statistical BRDF evaluated per pixel under a point light (no discrete-flake "
                             "glints; install/enable nmmm.appearance.render for them).")
        res.images.update(images)


def _eye_positions_cm(im):
    view_tilt = np.radians(30.0)
    centre = np.array([0.0, -im.distance_cm * np.sin(view_tilt), im.distance_cm * np.cos(view_tilt)])
    return centre


def _stereo_rendered(recipe, brdf, w, keep: dict, coat=None):
    """Stereo pair by :func:`nmmm.appearance.render.render_stereo_plate` with a tiled cell of
    discrete flakes (the seed paper's plate of unit cells): an effect coat's own flakes (its
    deposit) when given by composition, else flakes drawn at the BRDF's optical depth."""
    from nmmm.appearance.flakes import FlakeList
    from nmmm.appearance.render import PaintedPlate, PointLight, render_plate, render_stereo_plate

    im = recipe.image
    e = recipe.effect
    cell = im.cell_um * 1e3
    d = im.flake_diameter_um * 1e3
    cv = 0.3
    n = max(1, int(round(brdf.flakes.optical_depth * cell * cell / (np.pi * d * d / 4 * (1 + cv**2)))))
    fl = coat.flake_list() if coat is not None else FlakeList.random(
        brdf.flakes.optics, brdf.flakes.tilt, n, region_nm=(cell, cell), mean_diameter_nm=d, diameter_cv=cv,
        depth_range_nm=(2e3, 18e3), n_binder=e.coat_index, rng=im.seed)
    plate = PaintedPlate(brdf, fl, (im.plate_cm[0] * 10.0, im.plate_cm[1] * 10.0))
    centre = _eye_positions_cm(im) * 10.0
    light = PointLight(tuple(np.asarray(im.light_position_cm, float) * 10.0), recipe.lighting.illuminants[0])
    kw = dict(lights=[light], wavelength_nm=w)
    if im.stereo:
        left, right = render_stereo_plate(plate, position_mm=tuple(centre), look_at_mm=(0.0, 0.0, 0.0),
                                          interocular_mm=im.eye_separation_cm * 10.0, fov_deg=im.fov_deg,
                                          resolution=tuple(im.pixels), **kw)
        keep.update({"left eye": left, "right eye": right})
        return {"left eye": np.asarray(left.to_srgb(im.exposure), float),
                "right eye": np.asarray(right.to_srgb(im.exposure), float)}
    from nmmm.appearance.render import PinholeCamera

    cam = PinholeCamera(position_mm=tuple(centre), look_at_mm=(0.0, 0.0, 0.0), fov_deg=im.fov_deg,
                        resolution=tuple(im.pixels))
    keep["view"] = render_plate(plate, cam, **kw)
    return {"view": np.asarray(keep["view"].to_srgb(im.exposure), float)}


def _stereo(recipe, brdf, w):
    """Images of a flat plate seen by the left and right eye under a point light.

    Each pixel is a point of the plate (z = 0); the eye and the light are points above
    it. The pixel's value is the reflectance factor π f(λ, ωi, ωo) cos θi (r0/r)², r the
    light's distance (r0 at the plate's centre), encoded in sRGB under the first
    illuminant; the clear coat's mirror image of the point light is not drawn.
    """
    from nmmm.colour import spectra_to_srgb

    im = recipe.image
    W, H = im.pixels
    x = (np.arange(W) + 0.5) / W * im.plate_cm[0] - im.plate_cm[0] / 2
    y = (np.arange(H) + 0.5) / H * im.plate_cm[1] - im.plate_cm[1] / 2
    X, Y = np.meshgrid(x, y[::-1])
    P = np.stack([X, Y, np.zeros_like(X)], axis=-1).reshape(-1, 3)
    light = np.asarray(im.light_position_cm, float)
    centre = _eye_positions_cm(im)
    eyes = {"left eye": centre + [-im.eye_separation_cm / 2, 0, 0], "right eye": centre + [im.eye_separation_cm / 2, 0, 0]}
    if not im.stereo:
        eyes = {"view": centre}
    li = light - P
    r = np.linalg.norm(li, axis=-1, keepdims=True)
    wi = li / r
    r0 = np.linalg.norm(light)
    out = {}
    ill = recipe.lighting.illuminants[0]
    for name, eye in eyes.items():
        vo = eye - P
        wo = vo / np.linalg.norm(vo, axis=-1, keepdims=True)
        f = np.asarray(brdf(w, wi, wo), float)
        val = np.pi * f * wi[:, 2:3] * (r0 / r) ** 2 * im.exposure
        rgb = spectra_to_srgb(w, val, illuminant=ill)
        out[name] = np.clip(np.asarray(rgb, float).reshape(H, W, 3), 0, 1)
    return out


def _coats(recipe, mats, w, res):
    from nmmm.recipes.paint_stack import paint_system

    paint_system(recipe, mats, w, res)


_MACRO = {"film": _film, "plate": _plate, "thin_film": _thin_film, "effect": _effect, "coats": _coats}


# --------------------------------------------------------------------------------------
# compute


def _colours(recipe, res):
    from nmmm.colour import spectra_to_lab, spectra_to_srgb

    w = res.wavelength_nm
    labels = list(res.spectra)
    S = np.stack([res.spectra[k] for k in labels])
    for ill in recipe.lighting.illuminants:
        lab = spectra_to_lab(w, S, illuminant=ill, observer=recipe.lighting.observer)
        rgb = np.clip(np.asarray(spectra_to_srgb(w, np.clip(S, 0, None), illuminant=ill, observer=recipe.lighting.observer)), 0, 1)
        for k, (L, a, b), c in zip(labels, lab, rgb):
            res.colours.append(dict(spectrum=k, illuminant=ill, L=float(L), a=float(a), b=float(b),
                                    C=float(np.hypot(a, b)), h_deg=float(np.degrees(np.arctan2(b, a)) % 360),
                                    srgb=[float(v) for v in c]))


def compute(recipe: Recipe, recipe_text: str = "", progress: bool = True) -> RunResult:
    """Run the physics of a validated recipe (no files written)."""
    from tqdm import tqdm

    from nmmm.recipes.sanity import warn_if_unusual

    warn_if_unusual(recipe)  # a 20 nm "paint film" is said, not run silently
    w = _grid(recipe)
    res = RunResult(recipe=recipe, recipe_text=recipe_text, wavelength_nm=w)
    steps = ["compounds and levels", recipe.macro, "colours"]
    bar = tqdm(steps, desc=recipe.name[:30], disable=not progress, leave=False, unit="step")
    mats = None
    for step in bar:
        bar.set_postfix_str(step)
        t0 = time.perf_counter()
        if step == "compounds and levels":
            mats = build_materials(recipe, w, progress=None if progress else False)
            for k, m in mats.items():
                res.materials[k] = np.asarray(m.nk(w))
        elif step == "colours":
            _colours(recipe, res)
        else:
            try:
                _MACRO[step](recipe, mats, w, res)
                if recipe.image is not None and recipe.effect is None:  # a solid paint's plate (issue 19)
                    from nmmm.recipes.plate_image import add_solid_plate_images

                    add_solid_plate_images(recipe, mats, w, res)
            except RecipeError:
                raise
            except NmmmError as exc:
                raise RecipeError(f"{step}: {exc}") from None
        res.timings_s[step] = time.perf_counter() - t0
    res.scalars.update(scalar_results(res))
    return res


def scalar_results(res: RunResult) -> dict:
    """Flat numbers: ``L``, ``a``, ``b`` of the primary spectrum under each illuminant
    (``L_D65`` …), and the mean of the primary spectrum."""
    out = {}
    for row in res.colours:
        if row["spectrum"] == res.primary:
            for q in ("L", "a", "b"):
                out[f"{q}_{row['illuminant']}"] = row[q]
    if res.primary:
        out["mean_primary"] = float(np.mean(res.spectra[res.primary]))
    for k in ("contrast_ratio", "hiding_thickness_um", "hiding_spreading_rate_m2_per_L", "masstone_L", "masstone_a",
              "masstone_b", "km_minus_ad_max_abs"):
        if k in res.scalars:
            out[k] = res.scalars[k]
    if "contrast_ratio" in out:
        from nmmm.recipes.paint_stack import geometry_of

        res.summary.update({"contrast_ratio": out["contrast_ratio"], "geometry": geometry_of(res.recipe)})
        if "hiding_thickness_um" in out:
            res.summary.update({"hiding_thickness_um": out["hiding_thickness_um"],
                                "spreading_rate_m2_per_L": out["hiding_spreading_rate_m2_per_L"]})
        if "masstone_L" in out:
            res.summary["masstone_lab"] = [out["masstone_L"], out["masstone_a"], out["masstone_b"]]
    return out


# --------------------------------------------------------------------------------------
# files


def _safe(label: str) -> str:
    import re

    return re.sub(r"[^A-Za-z0-9]+", "_", label).strip("_")


def write_outputs(res: RunResult, out_dir, report: bool = True, lock: bool = True) -> dict:
    """Write CSV, NetCDF, plots, images and the HTML report of a result into ``out_dir``.

    Atomic (:func:`nmmm.atomic_io.atomic_output_dir`): everything is written into a temporary
    folder beside ``out_dir`` that takes its place only when complete; a second run into a
    folder in use is refused (``lock=False`` when the caller already holds the folder's lock).
    """
    from nmmm.atomic_io import atomic_output_dir

    final = Path(out_dir)
    with atomic_output_dir(final, lock=lock) as tmp:
        files = _write_outputs_into(res, Path(tmp), report, final)
    res.files = files
    return res.files


def _write_outputs_into(res: RunResult, out: Path, report: bool, final: Path) -> dict:
    def moved(v):
        return str(final / Path(v).relative_to(out))

    o = res.recipe.outputs
    files = {}
    w = res.wavelength_nm
    labels = list(res.spectra)
    if o.csv:
        p = out / "spectra.csv"
        with open(p, "w", newline="") as fh:
            wr = csv.writer(fh)
            wr.writerow(["wavelength_nm"] + [f"{k} [1]" for k in labels]
                        + [f"{q} {m} [1]" for m in res.materials for q in ("n", "k")])
            cols = [res.spectra[k] for k in labels] + [c for m in res.materials.values() for c in (m.real, m.imag)]
            for i, wl in enumerate(w):
                wr.writerow([f"{wl:g}"] + [f"{c[i]:.6g}" for c in cols])
        files["spectra_csv"] = p
        p = out / "colours.csv"
        with open(p, "w", newline="") as fh:
            wr = csv.writer(fh)
            wr.writerow(["spectrum", "illuminant", "observer_deg", "L*", "a*", "b*", "C*ab", "h_ab_deg", "sRGB_R", "sRGB_G", "sRGB_B"])
            for r in res.colours:
                wr.writerow([r["spectrum"], r["illuminant"], res.recipe.lighting.observer] +
                            [f"{r[q]:.4f}" for q in ("L", "a", "b", "C", "h_deg")] + [f"{v:.4f}" for v in r["srgb"]])
            for r in res.multiangle:
                wr.writerow([f"aspecular {r['aspecular_deg']:g} deg", r["illuminant"], res.recipe.lighting.observer] +
                            [f"{r[q]:.4f}" for q in ("L", "a", "b", "C", "h_deg")] + ["", "", ""])
        files["colours_csv"] = p
    if o.netcdf:
        from nmmm.recipes.labelled import write_run_netcdf

        files["netcdf"] = write_run_netcdf(res, out / "results.nc")
    if o.plots:
        files.update(_plots(res, out))
    if o.images and res.images:
        from PIL import Image

        for name, img in res.images.items():
            p = out / f"image_{_safe(name)}.png"
            Image.fromarray((np.clip(img, 0, 1) * 255 + 0.5).astype(np.uint8)).save(p)
            files[f"image {name}"] = p
        for name, simg in res.spectral_images.items():
            try:  # spectral radiance (Fichet et al. 2021 OpenEXR layout)
                p = out / f"image_{_safe(name)}.exr"
                simg.write_exr(p, half=True)
                files[f"spectral image {name}"] = p
            except Exception as exc:  # noqa: BLE001 - the PNGs remain
                res.notes.append(f"Spectral EXR of {name} not written: {exc}")
        if len(res.images) == 2:
            a, b = res.images.values()
            gap = np.ones((a.shape[0], 8, 3))
            p = out / "image_stereo_pair.png"
            Image.fromarray((np.concatenate([a, gap, b], axis=1) * 255 + 0.5).astype(np.uint8)).save(p)
            files["stereo pair"] = p
    (out / "recipe.toml").write_text(res.recipe_text or "", encoding="utf-8")
    files["recipe"] = out / "recipe.toml"
    (out / "scalars.json").write_text(json.dumps(res.scalars, indent=2), encoding="utf-8")
    res.files = {k: str(v) for k, v in files.items()}
    final_files = {k: moved(v) for k, v in res.files.items()}
    if report and o.report:
        from nmmm.recipes.report import result_section, write_report

        section = result_section(res)  # figures read from the temporary folder, paths told as final
        section["files"] = dict(final_files)
        p = write_report([section], out / "report.html", title=res.recipe.name)
        final_files["report"] = moved(p)
    return final_files


def _finish(fig, path):
    """Lay out, check the axis labels, save (110 dpi PNG) and close a figure; return its path
    (:func:`nmmm.recipes.figures.save_figure`)."""
    from nmmm.recipes.figures import save_figure

    return save_figure(fig, path, dpi=110)


def _spectrum_axes(ax, labels):
    """Wavelength axis, a y label naming the kinds of spectra plotted (unit 1), grid, legend."""
    def kind(label):
        label = str(label).split(" — ")[-1]
        return next((q for q in ("reflectance factor", "reflectance", "transmittance") if label.startswith(q)), label)

    kinds = list(dict.fromkeys(kind(k) for k in labels))
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel(" / ".join(kinds) + " (1)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)


def _plots(res, out):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    files = {}
    w = res.wavelength_nm
    from nmmm.recipes.figures import curve_styles

    fig, ax = plt.subplots(figsize=(7, 4))
    for (k, v), style in zip(res.spectra.items(), curve_styles(len(res.spectra))):
        ax.plot(w, v, lw=2 if k == res.primary else 1.2, label=k, **style)
    _spectrum_axes(ax, list(res.spectra))
    ax.set_title(res.recipe.name)
    files["spectra plot"] = _finish(fig, out / "spectra.png")
    if res.materials:
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.6))
        for (k, nk), style in zip(res.materials.items(), curve_styles(len(res.materials))):
            a1.plot(w, nk.real, label=k, **style)
            a2.plot(w, nk.imag, label=k, **style)
        a1.set_ylabel("n (1)")
        a2.set_ylabel("k (1)")
        a2.set_yscale("symlog", linthresh=1e-6)
        a2.set_ylim(bottom=0.0)  # k >= 0: no negative decades below a lossless compound's k = 0
        for a in (a1, a2):
            a.set_xlabel("wavelength (nm)")
            a.grid(alpha=0.3)
        a1.legend(fontsize=7)
        fig.suptitle("Optical constants of the compounds and levels")
        files["nk plot"] = _finish(fig, out / "nk.png")
    if res.multiangle:
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.6))
        g = [r["aspecular_deg"] for r in res.multiangle]
        a1.plot(g, [r["L"] for r in res.multiangle], "o-")
        a1.set_xlabel("aspecular angle (°)")
        a1.set_ylabel("L* (1)")
        a2.plot([r["a"] for r in res.multiangle], [r["b"] for r in res.multiangle], "o-")
        for r in res.multiangle:
            a2.annotate(f"{r['aspecular_deg']:g}°", (r["a"], r["b"]), fontsize=7)
        a2.set_xlabel("a* (1)")
        a2.set_ylabel("b* (1)")
        for a in (a1, a2):
            a.grid(alpha=0.3)
        fig.suptitle(f"Multi-angle colour ({res.multiangle[0]['illuminant']})")
        files["multiangle plot"] = _finish(fig, out / "multiangle.png")
    return files


def run_recipe(path_or_text, out_dir, progress: bool = True, report: bool = True, base_dir=None) -> RunResult:
    """Load a recipe (TOML path or text), compute it and write all outputs into ``out_dir``.

    ``base_dir``: the folder relative ``file`` paths are read from (and confined to) when the
    recipe is given as text or a dict (default: the current folder)."""
    raw, source, base = read_toml(path_or_text)
    base = base if base is not None else base_dir
    recipe = parse_recipe(raw, source, base)
    text = Path(path_or_text).read_text(encoding="utf-8") if source else (
        path_or_text if isinstance(path_or_text, str) else _dump_toml(raw))
    from nmmm.atomic_io import folder_lock

    with folder_lock(out_dir):  # a second run into this folder is refused before any physics
        res = compute(recipe, text, progress=progress)
        write_outputs(res, out_dir, report=report, lock=False)
    return res


def _dump_toml(raw: dict) -> str:
    """A readable TOML-like echo of a raw recipe dict (for recipes built in code)."""
    lines = []

    def val(v):
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(val(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {val(x)}" for k, x in v.items()) + " }"
        return repr(v)

    def table(prefix, d):
        scal = {k: v for k, v in d.items() if not isinstance(v, dict) and not (isinstance(v, list) and v and isinstance(v[0], dict))}
        if prefix:
            lines.append(f"\n[{prefix}]")
        for k, v in scal.items():
            lines.append(f"{k} = {val(v)}")
        for k, v in d.items():
            name = f"{prefix}.{k}" if prefix else k
            if isinstance(v, dict):
                table(name, v)
            elif isinstance(v, list) and v and isinstance(v[0], dict):
                for item in v:
                    lines.append(f"\n[[{name}]]")
                    for kk, vv in item.items():
                        lines.append(f"{kk} = {val(vv)}")

    table("", raw)
    return "\n".join(lines).strip() + "\n"
