"""The TOML recipe of a whole material, from its compounds to its images, and its validation.

- :class:`Recipe` — the validated recipe (pydantic v2 models, unknown keys refused).
- :func:`load_recipe` — a TOML file (or text, or dict) -> :class:`Recipe`; every problem is
  an :class:`nmmm.errors.RecipeError` whose message starts with the offending key path,
  e.g. ``pigment.fraction: must be in [0, 1] ...``.
- :func:`example_recipes`, :func:`example_path` — the recipes shipped with the package
  (the seed paper's worked examples).
- :func:`set_key`, :func:`get_key` — read and write a dotted key in a raw recipe dict (used
  by ``nmmm sweep --vary pigment.fraction=...``).

A recipe has these tables (units in the key names; lengths nm, angles degrees, fractions in
[0, 1]):

``name``, ``description``
``[spectral]``   ``start_nm``, ``stop_nm``, ``step_nm`` — the wavelength grid.
``[compounds.NAME]`` exactly one source each: ``database`` (refractiveindex.info key),
    ``uniaxial = [ordinary_key, extraordinary_key]`` (mean index), ``model`` (a name of
    :data:`nmmm.materials.MODELS`) with ``params``, ``file`` (CSV or refractiveindex.info
    YAML, relative to the recipe), or a constant ``n`` (and ``k``). Model coefficients keep
    their literature units, the exceptions to nm: Cauchy ``B`` in µm², ``C`` in µm⁴, Sellmeier
    ``C`` in µm² — write ``B_um2``, ``C_um4``, ``C_um2`` to say so, or ``B_nm2``, ``C_nm4``,
    ``C_nm2`` for nm-based values (:data:`nmmm.materials.models.EXPLICIT_UNIT_KEYS`); energies
    in eV.
``[[levels]]``   nano -> micro: each level mixes ``inclusions`` (compound, fraction, shape,
    radius_nm) in a ``host`` by an effective-medium ``method`` (:mod:`nmmm.ema`) or by FFT
    homogenization of a random ``microstructure`` (``method = "fft"``); its result is a new
    compound named ``name``, usable by the next levels.
``[pigment]`` + ``[binder]`` + ``[film]``   a pigmented paint film (Mie + radiative transfer,
    :mod:`nmmm.layers.paint`), with clear coat and substrate; the pigment ``shape`` (sphere,
    cube, rod, spheroid, rhombohedron with ``edge_nm`` + ``angle_deg``) maps to an
    ``equivalent_sphere`` (:func:`nmmm.layers.distributions.equivalent_sphere_diameter`).
``[plate]``      a plate of one compound seen in transmission (gold-ruby glass).
``[thin_film]``  a coherent/incoherent layer stack (interference pigments).
``[effect]``     a flake (metallic / interference) paint by its composition — ``[effect.flakes]``,
    ``[[effect.pigments]]``, binder, coat thicknesses (:mod:`nmmm.recipes.effect_schema`,
    :class:`nmmm.appearance.effect_coat.EffectCoat`): multi-angle colour and, with ``[image]``, a
    stereo pair of a plate.
``[lighting]``   ``illuminants``, ``observer``; ``[viewing]`` ``illumination_deg``,
    ``aspecular_deg``; ``[outputs]`` what to write.

Exactly one of ``film``, ``plate``, ``thin_film``, ``effect`` is the macro object.
"""

from __future__ import annotations

import contextlib
import contextvars
import copy
import difflib
import math
import tomllib
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, Field, ValidationError, field_validator, model_validator

from nmmm.errors import RecipeError
from nmmm.recipes.effect_schema import Effect, check_effect_references
from nmmm.recipes.schema_fields import (PIGMENT_SIZE_KEYS, AngleDeg, AspecularDeg, Fraction, NonNegative, Pigment,  # noqa: F401
                                       Positive, _Strict)

__all__ = ["Recipe", "load_recipe", "parse_recipe", "example_recipes", "example_path", "set_key", "get_key",
           "MACRO_OBJECTS", "compound_file", "files_outside_allowed"]

#: the tables of which exactly one is the macro object of a recipe
MACRO_OBJECTS = ("film", "plate", "thin_film", "effect", "coats")
#: a CPVC is a packing fraction: at most pi/sqrt(18), the densest packing of EQUAL spheres (fcc/hcp; MAX_PACKING of
#: nmmm.layers.pigment_mixture; random close packing is ~0.64)
_CPVC = Annotated[float, Field(gt=0.0, le=math.pi / math.sqrt(18.0))]


class Spectral(_Strict):
    """The wavelength grid (nm), inclusive."""

    start_nm: Positive = 380.0
    stop_nm: Positive = 780.0
    step_nm: Positive = 10.0

    @model_validator(mode="after")
    def _order(self):
        if self.stop_nm <= self.start_nm:
            raise ValueError(f"stop_nm ({self.stop_nm:g}) must exceed start_nm ({self.start_nm:g})")
        if (self.stop_nm - self.start_nm) / self.step_nm > 5000:
            raise ValueError("the grid would exceed 5000 wavelengths; increase step_nm")
        return self


class SizeDamping(_Strict):
    """Surface-scattering damping of a metal compound's free electrons in spheres of radius_nm:
    gamma(R) = gamma_bulk + A v_F / R (:func:`nmmm.materials.size_damped`; A = 1 classical; metal: read from the
    database key when left out; radius_nm: the inclusions' own radius_nm where a level gives one)."""

    radius_nm: Positive
    A: NonNegative = 1.0
    metal: Literal["gold", "silver"] | None = None


class Compound(_Strict):
    """One compound, known by its n + ik: exactly one source (``size_damping``: optional, metals)."""

    database: str | None = None
    uniaxial: list[str] | None = Field(default=None, min_length=2, max_length=2)
    model: str | None = None
    params: dict[str, Any] = Field(default_factory=dict)
    file: str | None = None
    n: Positive | None = None
    k: NonNegative = 0.0
    label: str | None = None
    size_damping: SizeDamping | None = None

    @model_validator(mode="after")
    def _one_source(self):
        given = [s for s in ("database", "uniaxial", "model", "file", "n") if getattr(self, s) is not None]
        if len(given) != 1:
            raise ValueError("give exactly one of 'database', 'uniaxial', 'model' (with 'params'), 'file' "
                             f"or a constant 'n' (and 'k'); got {given or 'none'}")
        if self.params and self.model is None:
            raise ValueError("'params' belongs to a dispersion 'model'")
        if self.model is not None:
            from nmmm.materials import MODELS

            if self.model not in MODELS:
                close = difflib.get_close_matches(self.model, list(MODELS), n=3)
                raise ValueError(f"unknown dispersion model {self.model!r}; choose from {sorted(MODELS)}"
                                 + (f" (did you mean {close[0]!r}?)" if close else ""))
        return self


class InclusionSpec(_Strict):
    """A population of inclusions at one level."""

    compound: str
    fraction: Fraction
    shape: Literal["sphere", "cube", "spheroid", "ellipsoid"] = "sphere"
    aspect_ratio: Positive | None = None
    semi_axes_nm: list[Positive] | None = Field(default=None, min_length=3, max_length=3)
    radius_nm: Positive | None = None

    @model_validator(mode="after")
    def _shape_params(self):
        if self.shape == "spheroid" and self.aspect_ratio is None:
            raise ValueError("shape 'spheroid' needs aspect_ratio (polar / equatorial semi-axis)")
        if self.shape == "ellipsoid" and self.semi_axes_nm is None:
            raise ValueError("shape 'ellipsoid' needs semi_axes_nm = [a, b, c]")
        return self


class MicrostructureSpec(_Strict):
    """A random periodic cell for FFT homogenization (:mod:`nmmm.microstructure`)."""

    model: Literal["boolean", "hardcore"] = "hardcore"
    size_px: int = Field(default=32, ge=8, le=256)
    ndim: Literal[2, 3] = 3
    voxel_nm: Positive = 2.0
    seed: int = 0


class Level(_Strict):
    """One scale: inclusions in a host, homogenized into the compound ``name``."""

    name: str
    scale: Literal["nano", "micro", "meso"] = "nano"
    host: str
    inclusions: list[InclusionSpec] = Field(min_length=1)
    method: str = "maxwell_garnett"
    microstructure: MicrostructureSpec | None = None
    fft_step_nm: Positive = 40.0

    @model_validator(mode="after")
    def _method(self):
        if self.method == "fft":
            if self.microstructure is None:
                object.__setattr__(self, "microstructure", MicrostructureSpec())
            if len(self.inclusions) != 1:
                raise ValueError("method 'fft' takes one inclusion population (one particle phase)")
            if self.inclusions[0].radius_nm is None:
                raise ValueError("method 'fft' needs the inclusions' radius_nm (the particles of the cell)")
        else:
            from nmmm.ema.mixtures import MIX_METHODS
            from nmmm.ema.registry import canonical_method

            try:
                m = canonical_method(self.method)
            except Exception:
                m = None
            if m not in MIX_METHODS:
                raise ValueError(f"unknown homogenization method {self.method!r}; choose 'fft' or one of {list(MIX_METHODS)}")
        total = sum(i.fraction for i in self.inclusions)
        if total > 1 + 1e-12:
            raise ValueError(f"inclusion fractions sum to {total:g} > 1")
        return self


class Binder(_Strict):
    compound: str


class Film(_Strict):
    """The paint film and its stack: clear coat on top, substrate below (0°/d geometry)."""

    thickness_nm: Positive = 20_000.0
    clear_coat_nm: NonNegative = 0.0
    substrate_reflectance: Fraction = 0.8
    #: adding–doubling by default (converged to 1e-4); "km" for Kubelka–Munk + Saunderson
    solver: Literal["km", "ad"] = "ad"
    specular: Literal["included", "excluded"] = "excluded"
    #: adding–doubling points per hemisphere; None: chosen for 1e-4 accuracy
    quad_pts: int | None = Field(default=None, ge=4, le=96)
    #: critical PVC; above it the film holds air voids (default 0.64, random close packing; at most pi/sqrt(18))
    cpvc: _CPVC | None = None


class CoatSpec(_Strict):
    """One coat of a stack (``[[coats]]``, top first)."""

    name: str
    thickness_nm: Positive
    binder: str
    pigments: list[Pigment] = Field(default_factory=list)
    cpvc: _CPVC | None = None

    @model_validator(mode="after")
    def _sum(self):
        total = sum(p.fraction for p in self.pigments)
        if total > 1 + 1e-12:
            raise ValueError(f"pigment fractions sum to {total:g} > 1 (fractions of the dry coat; their sum is the PVC)")
        return self


class SubstrateSpec(_Strict):
    """Below the film or stack: exactly one of ``reflectance`` (number or list over the grid),
    ``file`` (CSV wavelength_nm, reflectance), ``compound`` (n + ik) or ``kind`` (black/white)."""

    reflectance: float | list[float] | None = None
    file: str | None = None
    compound: str | None = None
    kind: Literal["black", "white"] | None = None

    @field_validator("reflectance")
    @classmethod
    def _reflectance_factor(cls, v):
        for i, r in enumerate([v] if isinstance(v, float) else v):
            if not (math.isfinite(r) and 0.0 <= r <= 1.0):
                where = "" if isinstance(v, float) else f" (item {i})"
                raise ValueError(f"a reflectance factor must be in [0, 1] (not percent: 85 % is 0.85); got {r!r}{where}")
        return v

    @model_validator(mode="after")
    def _one(self):
        given = [k for k in ("reflectance", "file", "compound", "kind") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"give exactly one of 'reflectance', 'file', 'compound' or 'kind'; got {given or 'none'}")
        return self


class Measurement(_Strict):
    """The instrument: ``geometry`` among di:8, de:8, 0:d, 45a:0, 0:45a (CIE 15:2018 §4.2)."""

    geometry: Literal["di:8", "de:8", "0:d", "45a:0", "0:45a"] | None = None
    hiding: bool = True


class Plate(_Strict):
    """A plate of one compound in air, normal incidence, seen in transmission."""

    compound: str
    thickness_nm: list[Positive] = Field(default_factory=lambda: [1e6], min_length=1)
    reference_compound: str | None = None


class LayerSpec(_Strict):
    compound: str
    thickness_nm: Positive
    coherent: bool = True


class ThinFilm(_Strict):
    """A layer stack (coherent thin films and incoherent thick layers)."""

    ambient: str | None = None
    layers: list[LayerSpec] = Field(min_length=1)
    substrate: str | None = None
    angles_deg: list[AngleDeg] = Field(default_factory=lambda: [0.0], min_length=1)


class Image(_Strict):
    """A flat plate seen by two eyes at reading distance under a point light (stereo pair)."""

    plate_cm: list[Positive] = Field(default_factory=lambda: [15.0, 10.0], min_length=2, max_length=2)
    distance_cm: Positive = 40.0
    eye_separation_cm: Positive = 6.5
    light_position_cm: list[float] = Field(default_factory=lambda: [0.0, 20.0, 35.0], min_length=3, max_length=3)
    pixels: list[Annotated[int, Field(ge=1, le=4096)]] = Field(default_factory=lambda: [150, 100], min_length=2,
                                                               max_length=2)  # [width, height]
    stereo: bool = True
    exposure: Positive = 1.0
    #: "auto": nmmm.appearance.render with discrete flakes (glints) when installed, else
    #: "simple": the statistical BRDF evaluated per pixel (no glints)
    renderer: Literal["auto", "simple"] = "auto"
    cell_um: Positive = 450.0
    flake_diameter_um: Positive = 15.0
    fov_deg: Annotated[float, Field(gt=1.0, lt=120.0)] = 25.0
    seed: int = 0
    scene: Literal["point", "booth", "booth-overhead", "sky", "light-table"] = "point"  # booth: ViewingBooth, 45° or
    wall_reflectance: Annotated[float, Field(ge=0.0, lt=1.0)] = 0.2  # overhead; sky: CIE sky (nmmm.recipes.plate_image)
    tilt_deg: Annotated[float, Field(gt=-90.0, lt=90.0)] = 0.0  # plate about its horizontal axis, far edge up
    sky_type: Annotated[int, Field(ge=1, le=16)] = 12  # CIE S 011 general sky 1-15 (12 clear), 16 CIE overcast
    sky_sun_elevation_deg: Annotated[float, Field(ge=0.0, le=90.0)] = 45.0
    sky_cct_k: Annotated[float, Field(ge=4000.0, le=25000.0)] | None = None  # CIE daylight; None: D65
    sky_illuminance_lux: Positive = 10000.0  # of the sky on a horizontal plane
    sky_sun_lux: Annotated[float, Field(ge=0.0)] = 0.0  # the sun's disc, normal to its rays (0: none)
    light_table_cd_m2: Positive = 1270.0  # ISO 3664 transparency viewing

    @model_validator(mode="after")
    def _light_above(self):
        if not (all(math.isfinite(c) for c in self.light_position_cm) and self.light_position_cm[2] > 0):
            raise ValueError(f"light_position_cm must be finite and above the plate (z > 0 cm, the plate lies in "
                             f"z = 0); got {self.light_position_cm}")
        return self


class Lighting(_Strict):
    illuminants: list[str] = Field(default_factory=lambda: ["D65"], min_length=1)
    observer: Literal["2", "10"] = "2"

    @model_validator(mode="after")
    def _known(self):
        import colour

        from nmmm.colour.illuminants import canonical_illuminant

        for i, name in enumerate(self.illuminants):
            if canonical_illuminant(name) not in colour.SDS_ILLUMINANTS:  # F11, TL84, CWF accepted
                close = difflib.get_close_matches(name, list(colour.SDS_ILLUMINANTS), n=3)
                raise ValueError(f"illuminants[{i}]: unknown illuminant {name!r}" + (f"; close: {close}" if close else ""))
        return self


class Viewing(_Strict):
    illumination_deg: AngleDeg = 45.0
    aspecular_deg: list[AspecularDeg] = Field(default_factory=lambda: [-15.0, 15.0, 25.0, 45.0, 75.0, 110.0], min_length=1)
    #: multi-angle colour of a [film] too (as a solid paint under a smooth coat of its binder)
    multiangle: bool = True


class Outputs(_Strict):
    csv: bool = True
    netcdf: bool = True
    plots: bool = True
    images: bool = True
    report: bool = True


class Recipe(_Strict):
    """A whole material, validated (see the module docstring)."""

    name: str = "unnamed recipe"
    description: str = ""
    spectral: Spectral = Field(default_factory=Spectral)
    compounds: dict[str, Compound] = Field(default_factory=dict)
    levels: list[Level] = Field(default_factory=list)
    pigment: Pigment | None = None
    pigments: list[Pigment] | None = None
    binder: Binder | None = None
    film: Film | None = None
    coats: list[CoatSpec] | None = None
    substrate: SubstrateSpec | None = None
    measurement: Measurement = Field(default_factory=Measurement)
    plate: Plate | None = None
    thin_film: ThinFilm | None = None
    effect: Effect | None = None
    image: Image | None = None
    lighting: Lighting = Field(default_factory=Lighting)
    viewing: Viewing = Field(default_factory=Viewing)
    outputs: Outputs = Field(default_factory=Outputs)
    #: folder of the recipe file (relative 'file' paths), not part of the TOML
    base_dir: str | None = None

    @property
    def macro(self) -> str:
        return next(k for k in MACRO_OBJECTS if getattr(self, k) is not None)


# --------------------------------------------------------------------------------------
# errors

_PYDANTIC_PREFIXES = ("Value error, ", "Assertion failed, ")


def _loc(loc) -> str:
    parts = []
    for p in loc:
        if isinstance(p, int):
            parts.append(f"[{p}]")
        elif str(p).startswith("function-after") or str(p) in ("constrained-float",):
            continue
        else:
            parts.append(("." if parts else "") + str(p))
    return "".join(parts) or "(top level)"


def _fields_at(model, loc):
    """Known field names of the model reached by ``loc`` (for 'did you mean')."""
    cls = model
    for p in loc[:-1]:
        if isinstance(p, int) or cls is None or str(p).startswith("function-after"):
            continue
        f = getattr(cls, "model_fields", {}).get(p)
        if f is None:
            if cls is Recipe and p:  # compounds.NAME
                return list(Compound.model_fields)
            return []
        ann = f.annotation
        cls = None
        for cand in (ann, *getattr(ann, "__args__", ())):
            for c in (cand, *getattr(cand, "__args__", ())):
                if isinstance(c, type) and issubclass(c, BaseModel):
                    cls = c
                    break
            if cls is not None:
                break
    return [k for k in getattr(cls, "model_fields", {}) if k != "base_dir"] if cls else []


def _message(err) -> str:
    msg = err["msg"]
    for p in _PYDANTIC_PREFIXES:
        if msg.startswith(p):
            msg = msg[len(p):]
    if err["type"] == "extra_forbidden":
        known = _fields_at(Recipe, err["loc"])
        close = difflib.get_close_matches(str(err["loc"][-1]), known, n=1)
        msg = "unknown key" + (f" (did you mean {close[0]!r}?)" if close else "") + (
            f"; known keys: {', '.join(known)}" if known else "")
    elif err["type"] == "missing":
        msg = "required key is missing"
    return msg


def _from_validation_error(exc: ValidationError, source: str) -> RecipeError:
    lines = []
    errs = exc.errors()
    # a table given where a union also takes a literal string (effect.flakes = "aluminium" | {...}): the
    # table's own errors are the ones to show, not "Input should be 'aluminium' or 'mica' (got {the table})"
    errs = [e for e in errs if not (e["type"] == "literal_error" and isinstance(e["input"], dict) and any(
        o is not e and o["type"] != "literal_error" and tuple(o["loc"][:len(e["loc"]) - 1]) == tuple(e["loc"][:-1])
        for o in errs))] or errs
    for err in errs:
        loc = _loc(err["loc"])
        if err["type"] == "literal_error":
            lines.append(f"{loc}: {err['msg']} (got {err['input']!r})")
        else:
            lines.append(f"{loc}: {_message(err)}")
    head = lines[0]
    more = "" if len(lines) == 1 else "\n" + "\n".join("  " + x for x in lines[1:])
    return RecipeError(f"{head}{more}" + (f"  [in {source}]" if source else ""))


# --------------------------------------------------------------------------------------
# cross-references


def _check_references(r: Recipe) -> None:
    known = set(r.compounds)
    for i, lev in enumerate(r.levels):
        for key, name in [("host", lev.host)] + [(f"inclusions[{j}].compound", inc.compound)
                                                   for j, inc in enumerate(lev.inclusions)]:
            if name not in known:
                raise RecipeError(f"levels[{i}].{key}: unknown compound {name!r}; defined so far: {sorted(known)} "
                                  "(a level may use compounds and the results of earlier levels)")
        for j, inc in enumerate(lev.inclusions):
            sd = getattr(r.compounds.get(inc.compound), "size_damping", None)
            if sd is not None and inc.radius_nm is not None and not math.isclose(sd.radius_nm, inc.radius_nm):
                raise RecipeError(f"levels[{i}].inclusions[{j}].radius_nm: {inc.radius_nm:g} nm, but compounds.{inc.compound}"
                                  f".size_damping.radius_nm is {sd.radius_nm:g} nm; the damping is of these spheres: make them equal")
        if lev.name in known:
            raise RecipeError(f"levels[{i}].name: {lev.name!r} is already a compound; give the level's result a new name")
        known.add(lev.name)
    macros = [k for k in MACRO_OBJECTS if getattr(r, k) is not None]
    if len(macros) != 1:
        raise RecipeError(f"(top level): give exactly one macro object among {list(MACRO_OBJECTS)}; got {macros or 'none'}")

    def need(path, name):
        if name is not None and name not in known:
            close = difflib.get_close_matches(name, sorted(known), n=1)
            raise RecipeError(f"{path}: unknown compound {name!r}" + (f" (did you mean {close[0]!r}?)" if close else "")
                              + f"; known: {sorted(known)}")

    if r.pigment is not None and r.pigments is not None:
        raise RecipeError("pigments: give [pigment] (one) or [[pigments]] (several), not both")
    if r.pigments is not None:
        total = sum(p.fraction for p in r.pigments)
        if total > 1 + 1e-12:
            raise RecipeError(f"pigments: the fractions sum to {total:g} > 1; they are volume fractions of the dry film "
                              "and sum to the PVC (< 1)")
        for j, p in enumerate(r.pigments):
            need(f"pigments[{j}].compound", p.compound)
    if r.coats is not None:
        for i, c in enumerate(r.coats):
            need(f"coats[{i}].binder", c.binder)
            for j, p in enumerate(c.pigments):
                need(f"coats[{i}].pigments[{j}].compound", p.compound)
    if r.substrate is not None and r.substrate.compound is not None:
        need("substrate.compound", r.substrate.compound)
    if r.film is not None:
        if r.pigment is None and r.pigments is None:
            raise RecipeError("pigment: required key is missing (a [film] needs a [pigment] table or [[pigments]])")
        if r.binder is None:
            raise RecipeError("binder: required key is missing (a [film] needs a [binder] table)")
    if r.pigment is not None:
        need("pigment.compound", r.pigment.compound)
    if r.binder is not None:
        need("binder.compound", r.binder.compound)
    if r.plate is not None:
        need("plate.compound", r.plate.compound)
        need("plate.reference_compound", r.plate.reference_compound)
    if r.thin_film is not None:
        need("thin_film.ambient", r.thin_film.ambient)
        need("thin_film.substrate", r.thin_film.substrate)
        for j, lay in enumerate(r.thin_film.layers):
            need(f"thin_film.layers[{j}].compound", lay.compound)
    if r.effect is not None:
        check_effect_references(r.effect, need)
    if r.image is not None and r.image.scene == "light-table" and r.plate is None and r.thin_film is None:
        raise RecipeError("image.scene: 'light-table' (the plate seen in transmission against a back-light) needs a "
                          "[plate] or [thin_film] recipe; a paint is opaque — use 'booth', 'sky' or 'point'")
    w0, w1 = r.spectral.start_nm, r.spectral.stop_nm
    if w0 < 360 or w1 > 830:
        raise RecipeError(f"spectral: colours need a grid inside 360–830 nm (the CIE tables); got {w0:g}–{w1:g} nm")


# --------------------------------------------------------------------------------------
# loading


#: True while :func:`files_outside_allowed` is active: compound files may lie outside the recipe's folder
_FILES_OUTSIDE = contextvars.ContextVar("nmmm_recipe_files_outside", default=False)

#: deepest nesting of tables and arrays a recipe may have (a recipe needs < 10)
MAX_DEPTH = 64


@contextlib.contextmanager
def files_outside_allowed(allowed: bool = True):
    """Within the block, a compound's ``file`` may lie outside the recipe's folder (``--allow-outside-files``)."""
    token = _FILES_OUTSIDE.set(bool(allowed))
    try:
        yield
    finally:
        _FILES_OUTSIDE.reset(token)


def compound_file(name: str, file: str, base_dir=None) -> Path:
    """The path of compound ``name``'s data ``file``, confined to the recipe's folder.

    Relative paths are taken from ``base_dir`` (the recipe's folder; the current folder for a
    recipe given as text). A path that leaves that folder (``..``, an absolute path, a symbolic
    link pointing out) is a :class:`RecipeError` unless :func:`files_outside_allowed` is active,
    so that a recipe from elsewhere cannot read ``/etc/passwd`` or ``/proc/self/environ``.
    """
    root = Path(base_dir) if base_dir else Path.cwd()
    p = Path(file).expanduser()
    p = p if p.is_absolute() else root / p
    if not _FILES_OUTSIDE.get():
        try:
            inside = p.resolve().is_relative_to(root.resolve())
        except (OSError, RuntimeError):
            inside = False
        if not inside:
            raise RecipeError(f"compounds.{name}.file: {file!r} lies outside the recipe's folder {str(root)!r}; "
                              "put the data file beside the recipe (a relative path inside its folder), or pass "
                              "--allow-outside-files (files_outside_allowed() in Python) if you trust this recipe")
    return p


def _depth(obj, limit: int, level: int = 0) -> int:
    if level > limit:
        return level
    if isinstance(obj, dict):
        return max([_depth(v, limit, level + 1) for v in obj.values()], default=level)
    if isinstance(obj, (list, tuple)):
        return max([_depth(v, limit, level + 1) for v in obj], default=level)
    return level


def parse_recipe(data: dict, source: str = "", base_dir=None) -> Recipe:
    """Validate a raw recipe dict -> :class:`Recipe` (or raise :class:`RecipeError`)."""
    if not isinstance(data, dict):
        raise RecipeError(f"(top level): a recipe is a table of keys, got {type(data).__name__}")
    if _depth(data, MAX_DEPTH) > MAX_DEPTH:
        raise RecipeError(f"(top level): tables and arrays nested more than {MAX_DEPTH} deep; a recipe needs a "
                          "few levels (compounds.NAME.params, levels[i].inclusions[j])")
    if "base_dir" in data:
        raise RecipeError("base_dir: not a recipe key (the recipe's folder is where its file lies); remove it")
    data = dict(data)
    if base_dir is not None:
        data["base_dir"] = str(base_dir)
    try:
        r = Recipe.model_validate(data)
    except ValidationError as exc:
        raise _from_validation_error(exc, source) from None
    _check_references(r)
    for name, c in r.compounds.items():
        if c.file is not None:
            compound_file(name, c.file, r.base_dir)
    return r


def read_toml(path_or_text) -> tuple[dict, str, Path | None]:
    """Raw dict of a TOML recipe (path, text, or dict) with its source name and folder."""
    if isinstance(path_or_text, dict):
        return copy.deepcopy(path_or_text), "", None
    p = Path(path_or_text) if not (isinstance(path_or_text, str) and "\n" in path_or_text) else None
    if p is not None:
        if not p.exists():
            raise RecipeError(f"(file): recipe file {str(p)!r} not found")
        if p.is_dir():
            raise RecipeError(f"(file): {str(p)!r} is a folder; give the path of a recipe file (.toml)")
        try:
            text = p.read_bytes().decode("utf-8")
        except UnicodeDecodeError as exc:
            raise RecipeError(f"(file): recipe file {str(p)!r} is not UTF-8 text (byte {exc.start}); a recipe is "
                              "a TOML text file saved as UTF-8") from None
        except OSError as exc:
            raise RecipeError(f"(file): cannot read recipe file {str(p)!r}: {exc.strerror or exc}") from None
        source, base = str(p), p.resolve().parent
    else:
        text, source, base = path_or_text, "", None
    try:
        return tomllib.loads(text), source, base
    except tomllib.TOMLDecodeError as exc:
        raise RecipeError(f"(TOML syntax): {exc}" + (f"  [in {source}]" if source else "")) from None
    except RecursionError:
        raise RecipeError(f"(TOML syntax): tables or arrays nested too deep (more than {MAX_DEPTH} levels make no "
                          "recipe)" + (f"  [in {source}]" if source else "")) from None


def load_recipe(path_or_text) -> Recipe:
    """Load and validate a recipe: a TOML file path, TOML text, or a raw dict."""
    raw, source, base = read_toml(path_or_text)
    return parse_recipe(raw, source, base)


# --------------------------------------------------------------------------------------
# dotted keys (sweeps)


def get_key(raw: dict, dotted: str):
    """Value at ``a.b.c`` (``levels[0].inclusions[1].fraction`` or ``levels.0...``)."""
    cur = raw
    for part in _split(dotted):
        try:
            cur = cur[part]
        except (KeyError, IndexError, TypeError):
            raise RecipeError(f"{dotted}: no such key in the recipe") from None
    return cur


def set_key(raw: dict, dotted: str, value) -> dict:
    """A deep copy of ``raw`` with ``dotted`` set to ``value`` (missing tables are created)."""
    out = copy.deepcopy(raw)
    parts = _split(dotted)
    cur = out
    for part in parts[:-1]:
        try:
            cur = cur[part]
        except KeyError:
            cur[part] = {}
            cur = cur[part]
        except (IndexError, TypeError):
            raise RecipeError(f"{dotted}: no such key in the recipe") from None
    if isinstance(cur, list) and not isinstance(parts[-1], int):
        raise RecipeError(f"{dotted}: no such key in the recipe")
    cur[parts[-1]] = value
    return out


def _split(dotted: str) -> list:
    parts = []
    for tok in dotted.replace("[", ".").replace("]", "").split("."):
        if tok == "":
            continue
        parts.append(int(tok) if tok.isdigit() else tok)
    if not parts:
        raise RecipeError(f"{dotted!r}: empty key")
    return parts


# --------------------------------------------------------------------------------------
# shipped examples


def example_path(name: str) -> Path:
    """Path of a shipped example recipe (``"hematite_paint"`` or ``"hematite_paint.toml"``)."""
    stem = name[:-5] if name.endswith(".toml") else name
    p = Path(str(resources.files("nmmm.recipes") / "examples" / f"{stem}.toml"))
    if not p.exists():
        raise RecipeError(f"(example): no shipped recipe {name!r}; available: {sorted(example_recipes())}")
    return p


def example_recipes() -> dict[str, Path]:
    """Shipped example recipes: {stem: path}."""
    folder = Path(str(resources.files("nmmm.recipes") / "examples"))
    return {p.stem: p for p in sorted(folder.glob("*.toml"))}
