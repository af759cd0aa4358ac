"""Optical models of a sample for fitting: layers, dispersion parameters, roughness, TOML files.

Public objects
--------------
- :class:`EllipsometryModel` — ambient / layers / substrate whose thicknesses and dispersion
  parameters are :class:`~nmmm.ellipsometry.fitting.Parameter` s; ``build(values)`` makes the
  :class:`nmmm.layers.Stack`, ``fit(data)`` fits it.
- :func:`read_model` — an :class:`EllipsometryModel` from a TOML file.
- :func:`dispersion_material` — a dispersion-model Material from a name and parameter values
  (``DISPERSION_PARAMETERS`` lists each model's parameters and units).
- :func:`roughness_material` — the surface-roughness medium: Bruggeman 50/50 mixture of the
  layer below and void (Fujiwara 2007, ch. 5; Aspnes, Theeten, Hottier, Phys. Rev. B 20, 3292
  (1979)).

Model file (TOML)
-----------------
Layers are listed from the ambient down to the substrate. A number is a fixed value; a table
``{value = ..., fit = true, min = ..., max = ...}`` is a parameter (``fit`` defaults to true).
A medium is a database key (``material = "main/Si/Green-2008"``, see
:func:`nmmm.materials.get`), a Material CSV file (``file = "epoxy.csv"``), a constant
(``n = 1.5, k = 0``) or a dispersion model (``model = "cauchy"`` with its parameters)::

    name = "epoxy on silicon"
    ambient = 1.0                      # n of the ambient (or a table like a layer's medium)

    [substrate]
    material = "main/Si/Green-2008"

    [[layers]]                         # top layer first
    name = "roughness"
    roughness = true                   # Bruggeman 50/50 of the layer below with void
    thickness_nm = {value = 3, min = 0, max = 30}

    [[layers]]
    name = "epoxy"
    thickness_nm = {value = 500, min = 10, max = 3000}
    model = "cauchy"                   # n = A + B/λ² + C/λ⁴, λ in µm
    A = {value = 1.5, min = 1.2, max = 2.0}
    B_um2 = {value = 0.005, min = -0.1, max = 0.2}   # B in µm² (or B_nm2 in nm²; plain B is µm²)
    C_um4 = 0

    [fit]                              # optional: data window, evaluation budget
    wavelength_min_nm = 300
    wavelength_max_nm = 1000
    max_nfev = 500

Oscillator models take ``oscillators = [{amplitude_ev2 = ..., center_ev = ..., broadening_ev =
...}, ...]``; Sellmeier takes lists ``B = [...]``, ``C = [...]``. Parameter names are
``<layer>.<parameter>`` (``epoxy.thickness_nm``, ``epoxy.A``, ``gold.oscillators[0].center_ev``,
``substrate.eps_inf``).

Units of the dispersion coefficients are those of :data:`DISPERSION_PARAMETERS`: energies in eV,
and — the exceptions to nm everywhere, as in the literature with λ in µm — Cauchy ``B`` in µm²
and ``C`` in µm⁴, Sellmeier ``C`` in µm². Write the unit in the key to make it explicit
(``B_um2``, ``C_um4``, ``C_um2``), or give nm-based values (``B_nm2``, ``C_nm4``, ``C_nm2``:
converted, 1 µm² = 10⁶ nm²); see :data:`nmmm.materials.models.EXPLICIT_UNIT_KEYS`. The fitted
parameter keeps the key's name and unit (``epoxy.B_nm2``, nm²).
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from nmmm.ellipsometry.fitting import FitResult, Parameter, fit_psi_delta
from nmmm.errors import DataFileError, InvalidInputError, RecipeError

__all__ = [
    "EllipsometryModel",
    "DISPERSION_PARAMETERS",
    "dispersion_material",
    "roughness_material",
    "read_model",
    "make_stack",
]

_OSC_KEYS = ("amplitude_ev2", "center_ev", "broadening_ev")

#: model name -> {parameter: unit}; list-valued parameters end with "[]"
DISPERSION_PARAMETERS: dict[str, dict[str, str]] = {
    "constant": {"n": "", "k": ""},
    "cauchy": {"A": "", "B": "um^2", "C": "um^4", "k_amplitude": "", "k_exponent": "1/eV", "band_edge_ev": "eV"},
    "sellmeier": {"A": "", "B[]": "", "C[]": "um^2"},
    "drude": {"plasma_ev": "eV", "gamma_ev": "eV", "eps_inf": ""},
    "lorentz": {"eps_inf": "", "oscillators[]": ""},
    "drude_lorentz": {"plasma_ev": "eV", "gamma_ev": "eV", "eps_inf": "", "oscillators[]": ""},
    "tauc_lorentz": {"A": "eV", "E0": "eV", "C": "eV", "Eg": "eV", "eps_inf": ""},
}
_OSC_UNITS = {"amplitude_ev2": "eV^2", "center_ev": "eV", "broadening_ev": "eV"}


def dispersion_material(model: str, values: dict, name: str | None = None):
    """A Material of ``nmmm.materials.models`` from flat parameter values.

    ``values`` uses the flat names of :data:`DISPERSION_PARAMETERS`: ``"A"``, ``"B[0]"``,
    ``"oscillators[1].center_ev"``.

    >>> m = dispersion_material("cauchy", {"A": 1.5, "B": 0.004})
    >>> round(float(m.n(500.0)), 4)
    1.516
    """
    from nmmm.materials import models as M

    key = model.lower().replace("-", "_").replace(" ", "_")
    if key not in DISPERSION_PARAMETERS:
        raise InvalidInputError(f"unknown dispersion model {model!r}; choose one of {sorted(DISPERSION_PARAMETERS)}")
    nm = name or key
    v = _canonical_flat(key, dict(values))
    if key == "constant":
        return M.Constant(nk=complex(v.get("n", 1.0), v.get("k", 0.0)), name=nm)
    kwargs = {}
    for pname in DISPERSION_PARAMETERS[key]:
        if pname == "oscillators[]":
            i, osc = 0, []
            while f"oscillators[{i}].center_ev" in v:
                osc.append(tuple(v[f"oscillators[{i}].{k}"] for k in _OSC_KEYS))
                i += 1
            kwargs["oscillators"] = tuple(osc)
        elif pname.endswith("[]"):
            base = pname[:-2]
            i, arr = 0, []
            while f"{base}[{i}]" in v:
                arr.append(v[f"{base}[{i}]"])
                i += 1
            kwargs[base] = tuple(arr)
        elif pname in v:
            kwargs[pname] = v[pname]
    cls = {"cauchy": M.Cauchy, "sellmeier": M.Sellmeier, "drude": M.Drude, "lorentz": M.Lorentz,
           "drude_lorentz": M.DrudeLorentz, "tauc_lorentz": M.TaucLorentz}[key]
    return cls(name=nm, **kwargs)


_ALIAS_UNITS = {"um2": "um^2", "um4": "um^4", "nm2": "nm^2", "nm4": "nm^4"}


def _canonical_flat(model: str, values: dict) -> dict:
    """Flat values with explicit-unit keys (``B_nm2``, ``C_nm2[1]``) converted to the model's
    own keys and units (:data:`nmmm.materials.models.EXPLICIT_UNIT_KEYS`)."""
    from nmmm.materials.models import EXPLICIT_UNIT_KEYS

    aliases = EXPLICIT_UNIT_KEYS.get(model, {})
    out = {}
    for k, val in values.items():
        base, sep, idx = k.partition("[")
        if base in aliases:
            target, factor = aliases[base]
            k, val = target + sep + idx, float(val) * factor
        if k in out:
            raise InvalidInputError(f"{model}: {k} is given twice (once with its unit in the name); keep one")
        out[k] = val
    return out


def roughness_material(below, void=1.0, fraction_void: float = 0.5, name: str = "roughness"):
    """Surface roughness as an effective medium: Bruggeman mixture of the material below and
    void (50/50 by default), the standard overlayer of ellipsometry (Fujiwara 2007, ch. 5;
    Aspnes, Theeten & Hottier 1979). Computed with :mod:`nmmm.ema`."""
    from nmmm.ema.bruggeman_rule import bruggeman
    from nmmm.materials.material import DerivedMaterial, as_material
    from nmmm.spectra import check_fraction

    below = as_material(below)
    void = as_material(void, name="void")
    fv = float(check_fraction(fraction_void, "fraction_void"))

    def eps(w):
        return bruggeman(void.eps(w), below.eps(w), fv)

    return DerivedMaterial(name=name, eps_function=eps, components=(below, void),
                           reference=f"Bruggeman EMA, {fv:.0%} void in {below.name} (surface roughness)",
                           metadata={"fraction_void": fv})


def make_stack(ambient, layers, substrate):
    """An :class:`nmmm.layers.Stack` from media and ``[(medium, thickness_nm), ...]`` (top first);
    layers of zero thickness are left out."""
    from nmmm.layers.thinfilm import Stack

    kept = []
    for m, t in layers:
        t = np.asarray(t, dtype=float)
        if t.ndim == 0 and t <= 0:
            continue
        kept.append((m, t if t.ndim else float(t)))
    return Stack(layers=kept, ambient=ambient, substrate=substrate)


# ----------------------------------------------------------------------------------------
# model description
# ----------------------------------------------------------------------------------------
def _param(name: str, spec, unit: str = "") -> Parameter:
    """A Parameter from a number (fixed) or a table {value, fit=true, min, max}."""
    if isinstance(spec, dict):
        unknown = set(spec) - {"value", "fit", "vary", "min", "max"}
        if unknown or "value" not in spec:
            raise RecipeError(f"{name}: a parameter table needs 'value' and may have fit, min, max; got {sorted(spec)}")
        vary = bool(spec.get("fit", spec.get("vary", True)))
        return Parameter(name, float(spec["value"]), vary, float(spec.get("min", -np.inf)),
                         float(spec.get("max", np.inf)), unit)
    if isinstance(spec, bool) or not isinstance(spec, (int, float)):
        raise RecipeError(f"{name}: expected a number or a table {{value=..., fit=true, min=..., max=...}}, got {spec!r}")
    return Parameter(name, float(spec), False, unit=unit)


@dataclass(frozen=True)
class _Medium:
    """A medium spec: fixed Material (``material``) or a dispersion model with parameters."""

    prefix: str
    material: object = None
    model: str | None = None
    parameters: tuple = ()

    @classmethod
    def from_spec(cls, prefix: str, spec, base_dir: Path | None = None) -> "_Medium":
        from nmmm.materials.material import Material, as_material

        if isinstance(spec, Material):
            return cls(prefix, material=spec)
        if isinstance(spec, (int, float, complex)) and not isinstance(spec, bool):
            return cls(prefix, material=as_material(complex(spec), name=prefix))
        if isinstance(spec, str):
            spec = {"material": spec}
        if not isinstance(spec, dict):
            raise RecipeError(f"{prefix}: a medium is a database key, a number (n), or a table; got {spec!r}")
        if "material" in spec:
            from nmmm.materials import get

            m = spec["material"]
            return cls(prefix, material=m if isinstance(m, Material) else get(m))
        if "file" in spec:
            from nmmm.materials import read_csv

            p = Path(spec["file"])
            if base_dir is not None and not p.is_absolute():
                p = base_dir / p
            return cls(prefix, material=read_csv(p))
        model = spec.get("model", "constant" if "n" in spec else None)
        if model is None:
            raise RecipeError(f"{prefix}: give material = '<database key>', file = '<csv>', n = ..., or model = "
                              f"one of {sorted(DISPERSION_PARAMETERS)}")
        key = str(model).lower().replace("-", "_")
        if key not in DISPERSION_PARAMETERS:
            raise RecipeError(f"{prefix}: unknown model {model!r}; choose one of {sorted(DISPERSION_PARAMETERS)}")
        from nmmm.materials.models import EXPLICIT_UNIT_KEYS

        aliases = EXPLICIT_UNIT_KEYS.get(key, {})
        allowed = {p.rstrip("[]") for p in DISPERSION_PARAMETERS[key]} | set(aliases)
        extra = set(spec) - allowed - {"model", "name", "thickness_nm", "roughness", "fraction_void"}
        if extra:
            raise RecipeError(f"{prefix}: unknown parameter(s) {sorted(extra)} for model {key!r}; it takes {sorted(allowed)}")
        params = []
        units = DISPERSION_PARAMETERS[key]
        for pname, unit in units.items():
            base = pname.rstrip("[]")
            if base not in spec:
                continue
            val = spec[base]
            if pname == "oscillators[]":
                for i, osc in enumerate(val):
                    if isinstance(osc, (list, tuple)):
                        osc = dict(zip(_OSC_KEYS, osc))
                    if set(osc) != set(_OSC_KEYS):
                        raise RecipeError(f"{prefix}.oscillators[{i}]: needs {', '.join(_OSC_KEYS)}; got {sorted(osc)}")
                    for k in _OSC_KEYS:
                        params.append(_param(f"{prefix}.oscillators[{i}].{k}", osc[k], _OSC_UNITS[k]))
            elif pname.endswith("[]"):
                for i, item in enumerate(val):
                    params.append(_param(f"{prefix}.{base}[{i}]", item, unit))
            else:
                params.append(_param(f"{prefix}.{base}", val, unit))
        for alias, (target, _) in aliases.items():  # explicit units: B_um2, B_nm2, C_nm2[i], ...
            if alias not in spec:
                continue
            twice = [k for k in spec if k == target or aliases.get(k, ("",))[0] == target]
            if len(twice) > 1:
                raise RecipeError(f"{prefix}: the coefficient {target} is given twice ({', '.join(twice)}); keep one")
            unit = _ALIAS_UNITS[alias.split("_", 1)[1]]
            val = spec[alias]
            if isinstance(val, (list, tuple)):
                params += [_param(f"{prefix}.{alias}[{i}]", item, unit) for i, item in enumerate(val)]
            else:
                params.append(_param(f"{prefix}.{alias}", val, unit))
        return cls(prefix, model=key, parameters=tuple(params))

    def build(self, values: dict):
        if self.material is not None:
            return self.material
        start = len(self.prefix) + 1
        local = {p.name[start:]: values[p.name] for p in self.parameters}
        return dispersion_material(self.model, local, name=self.prefix)


@dataclass(frozen=True)
class _Layer:
    name: str
    thickness: Parameter
    medium: _Medium | None  # None for a roughness layer
    roughness: bool = False
    fraction_void: float = 0.5


@dataclass(frozen=True)
class EllipsometryModel:
    """A sample for ellipsometry: ambient, layers (top first) and substrate, with parameters.

    Build one with :meth:`from_dict` / :func:`read_model`, or directly::

        EllipsometryModel.from_dict({"substrate": {"material": "main/Si/Green-2008"},
                                     "layers": [{"name": "film", "model": "cauchy",
                                                 "thickness_nm": {"value": 100}, "A": 1.5}]})
    """

    name: str
    ambient: _Medium
    layers: tuple
    substrate: _Medium
    options: dict = field(default_factory=dict)

    # -- construction ---------------------------------------------------------------------
    @classmethod
    def from_dict(cls, spec: dict, base_dir=None) -> "EllipsometryModel":
        """From a dictionary with the layout of the TOML model file (module docstring)."""
        if not isinstance(spec, dict):
            raise RecipeError("a model is a table with 'substrate' and optional 'ambient', 'layers', 'fit'")
        unknown = set(spec) - {"name", "ambient", "substrate", "layers", "fit"}
        if unknown:
            raise RecipeError(f"unknown model key(s) {sorted(unknown)}; allowed: name, ambient, substrate, layers, fit")
        if "substrate" not in spec:
            raise RecipeError("the model needs a [substrate] (e.g. material = 'main/Si/Green-2008')")
        fit_opts = spec.get("fit", {})
        bad = set(fit_opts) - {"wavelength_min_nm", "wavelength_max_nm", "max_nfev"} if isinstance(fit_opts, dict) else {"?"}
        if bad:
            raise RecipeError(f"[fit] accepts wavelength_min_nm, wavelength_max_nm, max_nfev; got {sorted(bad)}")
        base = Path(base_dir) if base_dir is not None else None
        ambient = _Medium.from_spec("ambient", spec.get("ambient", 1.0), base)
        substrate = _Medium.from_spec("substrate", spec["substrate"], base)
        layers = []
        names = set()
        raw_layers = list(spec.get("layers", []))
        for i, lay in enumerate(raw_layers):
            if not isinstance(lay, dict):
                raise RecipeError(f"layers[{i}] must be a table")
            lname = str(lay.get("name", f"layer{i}"))
            if lname in names or lname in ("ambient", "substrate"):
                raise RecipeError(f"layers[{i}]: the name {lname!r} is used twice (or reserved); give each layer a name")
            names.add(lname)
            if "thickness_nm" not in lay:
                raise RecipeError(f"layer {lname!r}: needs thickness_nm (a number or {{value=..., fit=true}})")
            th = _param(f"{lname}.thickness_nm", lay["thickness_nm"], "nm")
            if th.vary and th.min == -np.inf:
                th = Parameter(th.name, th.value, True, 0.0, th.max, "nm")
            if th.value < 0 or (th.vary and th.min < 0):
                raise RecipeError(f"layer {lname!r}: thickness_nm must be >= 0 (and its min >= 0)")
            if lay.get("roughness", False):
                fv = lay.get("fraction_void", 0.5)
                if isinstance(fv, bool) or not isinstance(fv, (int, float)) or not 0 <= fv <= 1:
                    raise RecipeError(f"layer {lname!r}: fraction_void must be a volume fraction in [0, 1] "
                                      f"(0.5 is the usual roughness), got {fv!r}")
                layers.append(_Layer(lname, th, None, True, float(fv)))
            else:
                if "fraction_void" in lay:
                    raise RecipeError(f"layer {lname!r}: fraction_void applies only to a roughness layer "
                                      "(roughness = true)")
                layers.append(_Layer(lname, th, _Medium.from_spec(lname, lay, base)))
        return cls(str(spec.get("name", "model")), ambient, tuple(layers), substrate, dict(spec.get("fit", {})))

    # -- parameters -----------------------------------------------------------------------
    @property
    def parameters(self) -> tuple:
        """Every parameter (fixed and varied), in a stable order."""
        out = list(self.ambient.parameters)
        for lay in self.layers:
            out.append(lay.thickness)
            if lay.medium is not None:
                out.extend(lay.medium.parameters)
        out.extend(self.substrate.parameters)
        return tuple(out)

    @property
    def values(self) -> dict:
        return {p.name: p.value for p in self.parameters}

    def with_values(self, values: dict) -> "EllipsometryModel":
        """A copy with new start values (e.g. a fit's result), same fit flags and bounds."""
        from dataclasses import replace

        def upd(p):
            return replace(p, value=float(values.get(p.name, p.value)))

        def med(m):
            return m if m is None else replace(m, parameters=tuple(upd(p) for p in m.parameters))

        layers = tuple(replace(lay, thickness=upd(lay.thickness), medium=med(lay.medium)) for lay in self.layers)
        return replace(self, ambient=med(self.ambient), layers=layers, substrate=med(self.substrate))

    # -- building ---------------------------------------------------------------------------
    def media(self, values: dict | None = None) -> list:
        """[(name, Material, thickness_nm)] for the layers, top first (roughness resolved)."""
        v = self.values if values is None else values
        built = []
        below = self.substrate.build(v)
        for lay in reversed(self.layers):
            if lay.roughness:
                mat = roughness_material(below, self.ambient.build(v), lay.fraction_void, name=lay.name)
            else:
                mat = lay.medium.build(v)
            built.append((lay.name, mat, v[lay.thickness.name]))
            below = mat
        return built[::-1]

    def build(self, values: dict | None = None):
        """The :class:`nmmm.layers.Stack` for the given parameter values (default: start values)."""
        v = self.values if values is None else values
        return make_stack(self.ambient.build(v), [(m, t) for _, m, t in self.media(v)], self.substrate.build(v))

    def material(self, layer: str, values: dict | None = None):
        """The Material of a layer (or ``"substrate"``/``"ambient"``) at the given values."""
        v = self.values if values is None else values
        if layer == "substrate":
            return self.substrate.build(v)
        if layer == "ambient":
            return self.ambient.build(v)
        for name, mat, _ in self.media(v):
            if name == layer:
                return mat
        raise InvalidInputError(f"no layer {layer!r}; layers: {[lay.name for lay in self.layers]}")

    # -- fitting ------------------------------------------------------------------------------
    def scan(self, data, parameter: str, values, *, set_best: bool = True):
        """χ² of the data over a grid of one parameter, the others at their current values.

        Used to find the start of a fit where χ² has many local minima (the interference order
        of a thick film). A layer thickness is scanned in one vectorised ``Stack.rt`` call (its
        thickness-grid axis); other parameters one value at a time.

        Returns
        -------
        (model, values, chi2)
            ``model`` is this model with ``parameter`` set to the best value (``set_best``), or
            unchanged.
        """
        from nmmm.ellipsometry.fitting import psi_delta_residuals
        from nmmm.ellipsometry.forward import psi_delta_from_rho
        from nmmm.spectra import check_finite

        grid = np.atleast_1d(check_finite(values, "values").astype(float))
        names = [p.name for p in self.parameters]
        if parameter not in names:
            raise InvalidInputError(f"unknown parameter {parameter!r}; the model has {names}")
        v = self.values
        layer_of = {lay.thickness.name: lay.name for lay in self.layers}
        if parameter in layer_of:
            if np.any(grid <= 0):
                raise InvalidInputError("scan thicknesses must be > 0 nm")
            built = [(m, grid if name == layer_of[parameter] else t) for name, m, t in self.media(v)]
            stack = make_stack(self.ambient.build(v), built, self.substrate.build(v))
            res = stack.rt(data.wavelength_nm, data.angle_deg, grid=False)
            psi, delta = psi_delta_from_rho(res.rp / res.rs)
            chi2 = np.array([np.sum(psi_delta_residuals(data, p, d) ** 2) for p, d in zip(psi, delta)])
        else:
            from nmmm.ellipsometry.forward import psi_delta

            chi2 = np.empty(grid.size)
            for i, x in enumerate(grid):
                p, d = psi_delta(self.build({**v, parameter: x}), data.wavelength_nm, data.angle_deg)
                chi2[i] = np.sum(psi_delta_residuals(data, p, d) ** 2)
        model = self
        if set_best:
            par = next(p for p in self.parameters if p.name == parameter)
            best = float(np.clip(grid[int(np.argmin(chi2))], par.min, par.max))
            model = self.with_values({**v, parameter: best})
        return model, grid, chi2

    def fit(self, data, **kwargs) -> FitResult:
        """Fit the varied parameters to ``data`` (all angles at once); see
        :func:`nmmm.ellipsometry.fitting.fit_psi_delta`. The ``[fit]`` options of the model
        file (wavelength window) apply."""
        opts = self.options
        if "wavelength_min_nm" in opts or "wavelength_max_nm" in opts:
            data = data.within(opts.get("wavelength_min_nm"), opts.get("wavelength_max_nm"))
        for key in ("max_nfev",):
            if key in opts and key not in kwargs:
                kwargs[key] = int(opts[key])
        result = fit_psi_delta(data, self.build, self.parameters, **kwargs)
        result.extra["model"] = self.with_values(result.values)
        return result


def read_model(path) -> EllipsometryModel:
    """An :class:`EllipsometryModel` from a TOML file (layout in the module docstring)."""
    p = Path(path)
    if not p.is_file():
        raise DataFileError(f"model file not found: {p}")
    try:
        spec = tomllib.loads(p.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise DataFileError(f"{p}: not valid TOML ({exc})") from None
    try:
        return EllipsometryModel.from_dict(spec, base_dir=p.parent)
    except RecipeError as exc:
        raise RecipeError(f"{p}: {exc}") from None
