"""``nmmm render`` — spectral images of painted plates and objects.

Commands
--------
- ``nmmm render plate OUT`` — render a painted plate (default: the seed's grey metallic
  plate, 332 × 240 flake cells) to ``OUT.exr`` (spectral, Fichet et al. 2021 layout) and
  ``OUT.png`` (sRGB); ``--stereo`` writes ``OUT_left.*`` and ``OUT_right.*``.
  ``--paint RECIPE.toml`` renders any paint recipe (solid film, coat stack, effect paint):
  the BRDF that gives the recipe's colours on its ``[image]`` plate and wavelength grid.
- ``nmmm render object OUT`` — a sphere or panel painted with the same paint, through
  Mitsuba 3 (``pip install 'nmmm[mitsuba]'``; a system libLLVM >= 17: ``apt-get install libllvm19``).
  Without them it prints one line saying what to install and exits with status 2.

``OUT`` is a file stem (``out/plate`` writes ``out/plate.exr`` and ``out/plate.png``); a name
ending in ``.exr`` or ``.png`` is taken without that suffix, and a folder (``out/``) gets
``plate.*`` or ``object.*`` inside it. Missing parent folders are created.
"""

from __future__ import annotations

import json
from pathlib import Path

import click

PAINTS = ("grey-metallic", "metallic", "interference", "solid", "white")

#: loaders of ``--paint RECIPE.toml``: callables ``path -> (PaintedPlate, wavelength_nm)``;
#: :mod:`nmmm.recipes.render_cli` registers the recipe one (this package sits below the recipes)
PLATE_LOADERS: list = []
#: functions ``name -> recipe path or None`` for the names of shipped recipes (registered by
#: :mod:`nmmm.recipes.render_cli`, like :data:`PLATE_LOADERS`)
RECIPE_NAMES: list = []


class _PaintParam(click.ParamType):
    """A preset name (:data:`PAINTS`), the path of a recipe file (``*.toml``) or the name of a
    shipped recipe (``red_metallic``, as ``nmmm run`` takes)."""

    name = "PRESET|RECIPE"

    def convert(self, value, param, ctx):
        if value in PAINTS:
            return value
        if str(value).lower().endswith(".toml"):
            if not Path(value).is_file():
                self.fail(f"recipe file {value!r} does not exist; give a recipe path or one of {', '.join(PAINTS)}",
                          param, ctx)
            return str(value)
        for shipped in RECIPE_NAMES:
            path = shipped(value)
            if path is not None:
                return str(path)
        self.fail(f"{value!r} is neither a preset ({', '.join(PAINTS)}), a recipe file (*.toml) nor a shipped "
                  "recipe's name (nmmm run --help lists them)", param, ctx)


def _output_stem(output: str, default_name: str) -> str:
    """The file stem that OUTPUT names (see the module docstring); its folder is created."""
    p = Path(output)
    if output.endswith(("/", "\\")) or p.is_dir() or p.name in ("", ".", ".."):
        p = p / default_name
    elif p.suffix.lower() in (".exr", ".png"):
        p = p.with_suffix("")
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise click.BadParameter(f"cannot create the folder {str(p.parent)!r}: {exc.strerror or exc}; "
                                 "give a writable OUTPUT such as out/plate", param_hint="OUTPUT") from None
    return str(p)


def _plate(paint: str, cells, tilt_deg: float, optical_depth: float, base: float, seed: int):
    from nmmm.appearance import brdf
    from nmmm.appearance.render.plate import LambertianBRDF, PaintedPlate, seed_metallic_plate

    cx, cy = cells
    cell_mm = 0.45
    if paint == "grey-metallic":
        return seed_metallic_plate(cells=(cx, cy), rng=seed)
    if paint == "metallic":
        return seed_metallic_plate(cells=(cx, cy), tilt_deg=tilt_deg, optical_depth=optical_depth,
                                   body_reflectance=base, rng=seed)
    if paint == "interference":
        from nmmm.appearance.flakes import FlakeList
        from nmmm.appearance.render.plate import PaintedPlate as _P

        p = brdf.interference_paint(optical_depth=optical_depth, tilt=tilt_deg, body_reflectance=base)
        n = int(round(optical_depth * 450e3 ** 2 / (3.14159 * 15e3 ** 2 / 4 * 1.09)))
        fl = FlakeList.random(p.flakes.optics, p.flakes.tilt, n, region_nm=(450e3, 450e3), rng=seed)
        return _P(p, fl, (cx * cell_mm, cy * cell_mm))
    if paint == "solid":
        return PaintedPlate(brdf.opaque_paint(base), None, (cx * cell_mm, cy * cell_mm))
    if paint == "white":
        return PaintedPlate(LambertianBRDF(1.0), None, (cx * cell_mm, cy * cell_mm))
    return _recipe_plate(paint)[0]


def _recipe_plate(path: str):
    """``(PaintedPlate, wavelength_nm)`` of a recipe file through the registered loader."""
    if not PLATE_LOADERS:
        raise click.UsageError("--paint RECIPE.toml needs the recipes (run it as `nmmm render plate`)")
    return PLATE_LOADERS[-1](path)


def _lights(light: str, zenith: float, azimuth: float, irradiance: float, env: str | None, env_radiance: float):
    from nmmm.appearance.render.lights import DirectionalLight, UniformEnvironment

    lights = [DirectionalLight.from_angles(zenith, azimuth, light, irradiance)] if irradiance > 0 else []
    environment = UniformEnvironment(env, env_radiance) if env else None
    return lights, environment


class _MissingDependency(click.ClickException):
    """A missing optional dependency (Mitsuba 3, libLLVM): one line on stderr, exit status 2."""

    exit_code = 2

    def show(self, file=None):
        click.echo(self.format_message(), err=True)


class _DataError(click.ClickException):
    """Bad input (an :class:`~nmmm.errors.NmmmError`): the CLI's one voice, one ``error:`` line on
    stderr and exit status 2 (as :func:`nmmm.cli.main` gives every data error)."""

    exit_code = 2

    def __init__(self, exc):
        text = " ".join(str(exc).split()).replace("render_plate(..., max_memory_gb=)", "--max-memory-gb")
        super().__init__(text)

    def show(self, file=None):
        click.echo("error: " + self.format_message(), err=True)


@click.group(name="render")
def render():
    """Spectral rendering of painted plates and objects (spectral EXR + sRGB PNG)."""


def _common(f):
    opts = [
        click.option("--paint", type=_PaintParam(), default="grey-metallic", show_default=True,
                     help=f"A preset ({', '.join(PAINTS)}) or a recipe file: its paint on its [image] plate."),
        click.option("--tilt-deg", type=float, default=12.0, show_default=True, help="Flake tilt sigma."),
        click.option("--optical-depth", type=float, default=2.0, show_default=True, help="Flake area per area."),
        click.option("--base", type=float, default=0.3, show_default=True, help="Base internal reflectance."),
        click.option("--light", default="D65", show_default=True,
                     help="CIE illuminant name (colour-science) or CSV 'wavelength_nm,power'."),
        click.option("--light-zenith-deg", type=float, default=35.0, show_default=True),
        click.option("--light-azimuth-deg", type=float, default=90.0, show_default=True),
        click.option("--irradiance", type=float, default=1.0, show_default=True, help="Scale of the light SPD."),
        click.option("--environment", default=None, help="SPD of a uniform sky (name or CSV); none by default."),
        click.option("--env-radiance", type=float, default=0.01, show_default=True),
        click.option("--width", type=int, default=1024, show_default=True),
        click.option("--height", type=int, default=683, show_default=True),
        click.option("--exposure", type=float, default=1.0, show_default=True,
                     help="1: a white diffuser under the light is display white."),
        click.option("--colourspace", type=click.Choice(("sRGB", "Display P3")), default="sRGB", show_default=True,
                     help="Display encoding of the PNG."),
    ]
    for o in reversed(opts):
        f = o(f)
    return f


@render.command("plate")
@click.argument("output")
@_common
@click.option("--cells", nargs=2, type=int, default=(332, 240), show_default=True, help="Unit cells (450 um).")
@click.option("--camera-mm", nargs=3, type=float, default=(0.0, -180.0, 420.0), show_default=True)
@click.option("--look-at-mm", nargs=3, type=float, default=(0.0, 0.0, 0.0), show_default=True)
@click.option("--fov-deg", type=float, default=24.0, show_default=True)
@click.option("--stereo", is_flag=True, help="Render the left and right eye images.")
@click.option("--interocular-mm", type=float, default=65.0, show_default=True)
@click.option("--glint-spread-deg", type=float, default=1.0, show_default=True)
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the flake unit cell.")
@click.option("--booth", type=click.Choice(("none", "45", "overhead")), default="none", show_default=True,
              help="Put the plate in a grey viewing booth lit by a D65 source at 45 deg or overhead "
                   "(replaces --light and --environment; ViewingBooth).")
@click.option("--wall-reflectance", type=float, default=0.2, show_default=True, help="Booth walls and floor.")
@click.option("--sky", "sky_type", type=click.IntRange(1, 16), default=None,
              help="Light the plate by a CIE standard general sky of this type (1-15, CIE S 011; 12 clear, 16 the CIE "
                   "overcast sky), D65, 10000 lx, the sun 45 deg high behind the plate (nmmm.appearance.render.cie_sky).")
@click.option("--illuminance-lux", type=float, default=2000.0, show_default=True, help="Booth: at the plate centre.")
@click.option("--tone-map", type=click.Choice(("auto", "knee", "none")), default="auto", show_default=True,
              help="PNG highlights above display white: 'knee' compresses them (SpectralImage.to_display), 'none' "
                   "clips; 'auto' is knee in a booth, none otherwise.")
@click.option("--max-memory-gb", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Memory limit of one render (default: half the physical memory); a larger render is refused.")
@click.option("--stokes", is_flag=True, help="Polarized render: also write OUTPUT_stokes.exr (spectral S0..S3, "
              "Stokes frame x = image right, y = image up; nmmm.appearance.render.plate.stokes).")
@click.option("--polarizer", "polarizer_deg", type=float, default=None,
              help="Polarized render seen through a linear polarizer whose axis is DEG from the image's right axis "
                   "(counter-clockwise; 90 = vertical removes the coat's reflection near Brewster's angle).")
def plate_cmd(output, paint, tilt_deg, optical_depth, base, light, light_zenith_deg, light_azimuth_deg, irradiance,
              environment, env_radiance, width, height, exposure, colourspace, cells, camera_mm, look_at_mm, fov_deg, stereo,
              interocular_mm, glint_spread_deg, seed, booth, wall_reflectance, illuminance_lux, tone_map,
              max_memory_gb, stokes, polarizer_deg, sky_type=None):
    """Render a painted plate to OUTPUT.exr and OUTPUT.png."""
    from nmmm.appearance.render.camera import PinholeCamera
    from nmmm.appearance.render.plate import render_plate, render_stereo_plate
    from nmmm.errors import NmmmError

    output = _output_stem(output, "plate")
    if booth != "none" and sky_type is not None:
        raise click.UsageError(f"--sky {sky_type} and --booth {booth} are two scenes; give one of them")
    try:
        grid = None
        if paint in PAINTS:
            plate = _plate(paint, cells, tilt_deg, optical_depth, base, seed)
        else:  # a recipe: its own paint, plate size and wavelength grid
            plate, grid = _recipe_plate(paint)
        if booth != "none":
            from nmmm.appearance.render.lights import default_wavelengths
            from nmmm.appearance.render.plate import ViewingBooth

            vb = ViewingBooth(source=booth, wall_reflectance=wall_reflectance, floor_reflectance=wall_reflectance,
                              illuminant=light, illuminance_lux=illuminance_lux)
            scene = vb.scene(plate, default_wavelengths() if grid is None else grid)
            lights, env = scene["lights"], scene["environment"]
        elif sky_type is not None:
            from nmmm.appearance.render.cie_sky import cie_sky_environment
            from nmmm.appearance.render.lights import default_wavelengths

            lights, env = [], cie_sky_environment(default_wavelengths() if grid is None else grid, sky_type,
                                                  ground_reflectance=wall_reflectance)
        else:
            lights, env = _lights(light, light_zenith_deg, light_azimuth_deg, irradiance, environment, env_radiance)
        kw = dict(lights=lights, environment=env, glint_spread_deg=glint_spread_deg, wavelength_nm=grid,
                  max_memory_gb=max_memory_gb)
        polarized = {}
        if hasattr(plate, "render_view"):  # a recipe's glass / thin-film plate (nmmm.recipes.render_cli) renders itself
            from nmmm.appearance.render.camera import stereo_pair

            if stokes or polarizer_deg is not None:
                raise click.UsageError("--stokes / --polarizer render paints; a glass or thin-film recipe has no "
                                       "polarized render yet")
            cams = (dict(zip(("_left", "_right"), stereo_pair(camera_mm, look_at_mm, interocular_mm, (0.0, 1.0, 0.0),
                                                              fov_deg, (width, height)))) if stereo else
                    {"": PinholeCamera(camera_mm, look_at_mm, fov_deg=fov_deg, resolution=(width, height))})
            named = {k: plate.render_view(c, lights, env, max_memory_gb) for k, c in cams.items()}
        elif stokes or polarizer_deg is not None:
            from nmmm.appearance.render.camera import stereo_pair
            from nmmm.appearance.render.plate.stokes import render_plate_stokes

            cams = (dict(zip(("_left", "_right"), stereo_pair(camera_mm, look_at_mm, interocular_mm, (0.0, 1.0, 0.0),
                                                              fov_deg, (width, height)))) if stereo else
                    {"": PinholeCamera(camera_mm, look_at_mm, fov_deg=fov_deg, resolution=(width, height))})
            polarized = {k: render_plate_stokes(plate, c, **kw) for k, c in cams.items()}
            named = {k: v.s0 if polarizer_deg is None else v.through_polarizer(polarizer_deg) for k, v in polarized.items()}
        elif stereo:
            imgs = render_stereo_plate(plate, camera_mm, look_at_mm, interocular_mm, fov_deg, (width, height), **kw)
            named = dict(zip(("_left", "_right"), imgs))
        else:
            named = {"": render_plate(plate, PinholeCamera(camera_mm, look_at_mm, fov_deg=fov_deg,
                                                           resolution=(width, height)), **kw)}
    except NmmmError as exc:
        raise _DataError(exc) from None
    files = []
    tm = ("knee" if booth != "none" else None) if tone_map == "auto" else tone_map
    display = {}
    for suffix, img in named.items():
        files.append(str(img.write_exr(f"{output}{suffix}.exr")))
        files.append(str(img.write_png(f"{output}{suffix}.png", exposure=exposure, colourspace=colourspace,
                                       tone_map=tm)))
        display[suffix.lstrip("_") or "mono"] = img.to_display(colourspace, exposure, tm or "none")[1]
    pol = {}
    for suffix, st in polarized.items():
        if stokes:
            files.append(str(st.write_exr(f"{output}{suffix}_stokes.exr")))
        pol[suffix.lstrip("_") or "mono"] = {"polarizer_deg": polarizer_deg, "plate_mean_dolp": round(float(
            st.degree_of_polarization()[st.on_plate].mean()), 5), "glints_polarized": st.metadata["glints_polarized"]}
    click.echo(json.dumps({"plate": repr(plate), "files": files,
                           "glints": {k or "mono": v.metadata["n_glints"] for k, v in named.items()},
                           "display": display, **({"polarization": pol} if pol else {})}, indent=1))


@render.command("object")
@click.argument("output")
@_common
@click.option("--shape", type=click.Choice(("sphere", "panel")), default="sphere", show_default=True)
@click.option("--distance-mm", type=float, default=400.0, show_default=True)
@click.option("--fov-deg", type=float, default=30.0, show_default=True)
@click.option("--spp", type=int, default=64, show_default=True, help="Samples per pixel.")
@click.option("--stereo", is_flag=True)
@click.option("--interocular-mm", type=float, default=65.0, show_default=True)
@click.option("--variant", type=click.Choice(("llvm_ad_spectral", "scalar_spectral", "cuda_ad_spectral")),
              default="llvm_ad_spectral", show_default=True,
              help="Mitsuba variant: scalar_spectral needs no libLLVM but is much slower.")
def object_cmd(output, paint, tilt_deg, optical_depth, base, light, light_zenith_deg, light_azimuth_deg, irradiance,
               environment, env_radiance, width, height, exposure, colourspace, shape, distance_mm, fov_deg, spp, stereo,
               interocular_mm, variant):
    """Render a painted 3-D object with Mitsuba 3 to OUTPUT.exr and OUTPUT.png.

    Needs Mitsuba 3 and, for its LLVM variant, libLLVM >= 17; without them: one line saying
    what to install, exit status 2."""
    from nmmm.appearance.render.mitsuba_paint import MitsubaUnavailableError
    from nmmm.errors import NmmmError

    output = _output_stem(output, "object")
    try:
        from nmmm.appearance.render.mitsuba_scene import render_object

        plate = _plate(paint, (2, 2), tilt_deg, optical_depth, base, 0)
        lights, env = _lights(light, light_zenith_deg, light_azimuth_deg, irradiance, environment or "D65",
                              env_radiance)
        imgs = render_object(plate.smooth_brdf, shape=shape, lights=lights, environment=env,
                             distance_mm=distance_mm, fov_deg=fov_deg, resolution=(width, height), spp=spp,
                             stereo=stereo, interocular_mm=interocular_mm, variant=variant)
    except MitsubaUnavailableError as exc:  # a missing system library: one line, exit 2
        raise _MissingDependency(f"nmmm render object: {exc}") from None
    except NmmmError as exc:
        raise _DataError(exc) from None
    named = dict(zip(("_left", "_right"), imgs)) if stereo else {"": imgs[0]}
    files = []
    for suffix, img in named.items():
        files.append(str(img.write_exr(f"{output}{suffix}.exr")))
        files.append(str(img.write_png(f"{output}{suffix}.png", exposure=exposure, colourspace=colourspace)))
    click.echo(json.dumps({"files": files}, indent=1))
