"""Labelled results: a run and a sweep as xarray Datasets with CF-style units.

- :func:`run_to_xarray` — a :class:`~nmmm.recipes.run.RunResult` as one Dataset
  (``RunResult.to_xarray()``), the layout of ``results.nc`` written by ``nmmm run``.
- :func:`write_run_netcdf` — that Dataset into a netCDF-4 file (h5netcdf engine).
- :func:`spectrum_coordinates` — the structured description (kind, substrate, geometry,
  compound, thickness, aspecular angle) of a spectrum from the run's label.
- :func:`sweep_to_xarray` — the points of a sweep as one cube with a dimension per varied key.
- :func:`write_sweep_cube` — that cube as ``OUT/results.nc`` and, for large sweeps, ``OUT/results.zarr``.
- :func:`run_result_html` — the notebook display of a run (``RunResult._repr_html_``).
- :func:`units_of_key` — the unit a recipe key's name states (``_nm`` → nm, ``fraction`` → 1, …).

Layout of a run (``xr.open_dataset("results.nc")``)::

    dimensions  wavelength (units nm), spectrum, compound, illuminant, cielab, rgb, aspecular_angle (degree)
    spectra(spectrum, wavelength)            reflectance / transmittance / reflectance factor, units 1
        coordinates along spectrum: kind, substrate, geometry, compound_seen, thickness (mm), label
    reflectance_factor(aspecular_angle, wavelength)   flake paints only, units 1
    n(compound, wavelength), k(compound, wavelength)  units 1
    lab(spectrum, illuminant, cielab)        CIE 1976 L*, a*, b* (units 1), attribute observer
    srgb(spectrum, illuminant, rgb)          IEC 61966-2-1 sRGB in [0, 1]
    multiangle_lab(aspecular_angle, cielab)  flake paints only
    one 0-d variable per scalar result (L_D65, flop_index, …) with its units

Spectra are ratios (reflectance, transmittance, reflectance factor): they do not depend on the
illuminant, which is the dimension of the colour variables (``lab``, ``srgb``) instead.

References
----------
- CF Metadata Conventions 1.10, https://cfconventions.org (``units``, ``long_name``,
  ``standard_name = "radiation_wavelength"``).
- S. Hoyer, J. Hamman, "xarray: N-D labeled arrays and datasets in Python", J. Open Res. Softw.
  5(1), 10 (2017). https://doi.org/10.5334/jors.148
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd
    import xarray as xr
# ``RunResult`` (nmmm.recipes.run) is named in annotations only: run imports this module, not the reverse

__all__ = ["run_to_xarray", "write_run_netcdf", "spectrum_coordinates", "sweep_to_xarray", "write_sweep_cube",
           "run_result_html", "units_of_key", "ZARR_MIN_POINTS"]

#: sweeps of at least this many points are also written as a Zarr store (chunked, lazily read)
ZARR_MIN_POINTS = 1000

_SUFFIX_UNITS = (("_nm2", "nm2"), ("_nm", "nm"), ("_um", "um"), ("_mm", "mm"), ("_cm", "cm"), ("_deg", "degree"),
                 ("_s", "s"), ("_m2_per_L", "m2 L-1"), ("_pct", "%"))
_DIMENSIONLESS = ("fraction", "reflectance", "transmittance", "spread", "index", "depth", "roughness",
                  "contrast_ratio", "mean_primary", "flop_index", "strength", "delta_e00")


def units_of_key(key: str) -> str | None:
    """The unit a key's name states: ``pigment.diameter_nm`` → ``"nm"``, ``pigment.fraction`` → ``"1"``,
    ``L_D65`` and ``masstone_L`` → ``"1"`` (CIELAB is dimensionless); ``None`` when the name states none."""
    last = key.rsplit(".", 1)[-1]
    for suffix, unit in _SUFFIX_UNITS:
        if last.endswith(suffix):
            return unit
    if re.match(r"^(?:[Lab]_|masstone_[Lab]$)", last) or any(last.endswith(d) for d in _DIMENSIONLESS):
        return "1"
    return None


def _num(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        return math.nan


def spectrum_coordinates(label: str, geometry_default: str = "") -> dict[str, Any]:
    """Structured description of a run's spectrum from its label.

    >>> c = spectrum_coordinates("reflectance (substrate 0.85)", "0°/d")
    >>> c["kind"], c["substrate"], c["geometry"]
    ('reflectance', '0.85', '0°/d')
    >>> spectrum_coordinates("reflectance factor (aspecular 45°)")["aspecular_deg"]
    45.0
    """
    m = re.match(r"^\s*(reflectance factor|reflectance|transmittance|absorptance)\b(.*)$", label)
    kind, rest = (m.group(1), m.group(2)) if m else (label.split("(")[0].strip() or label, label)
    out = {"kind": kind, "substrate": "", "geometry": geometry_default, "compound_seen": "",
           "thickness_mm": math.nan, "aspecular_deg": math.nan}
    if s := re.search(r"substrate\s+(-?[\d.eE+-]+)", rest):
        out["substrate"] = s.group(1)
    elif s := re.search(r"\b(black|white)\b", rest):
        out["substrate"] = s.group(1)
    if a := re.search(r"aspecular\s+(-?[\d.]+)\s*°", rest):
        out["aspecular_deg"] = float(a.group(1))
        out["geometry"] = f"aspecular {a.group(1)}°"
    elif a := re.search(r"(-?[\d.]+)\s*°\s*incidence", rest):
        out["geometry"] = f"{a.group(1)}° incidence, specular"
    if kind == "transmittance" and (t := re.match(r"^\s*(.*?)\s*\(([\d.eE+-]+)\s*mm\)\s*$", rest)):
        out["compound_seen"], out["thickness_mm"] = t.group(1), _num(t.group(2))
        out["geometry"] = "0°/0° (normal incidence, regular transmission)"
    return out


def _geometry_of(res) -> str:
    r = res.recipe
    meas = getattr(r, "measurement", None)
    if meas is not None and getattr(meas, "geometry", None):
        return str(meas.geometry)
    film = getattr(r, "film", None)
    if film is not None:
        return f"0°/d, specular {getattr(film, 'specular', 'excluded')}"
    return ""


def run_to_xarray(res: RunResult) -> xr.Dataset:
    """The run ``res`` as a labelled Dataset (layout in the module docstring)."""
    import xarray as xr

    import nmmm

    w = np.asarray(res.wavelength_nm, float)
    labels = list(res.spectra)
    obs = res.recipe.lighting.observer
    ds = xr.Dataset(coords={"wavelength": ("wavelength", w, {
        "units": "nm", "long_name": "vacuum wavelength", "standard_name": "radiation_wavelength"})})
    if labels:
        geom = _geometry_of(res)
        coords = [spectrum_coordinates(k, geom) for k in labels]
        ds["spectra"] = (("spectrum", "wavelength"), np.stack([np.asarray(res.spectra[k], float) for k in labels]),
                         {"units": "1", "long_name": "reflectance, transmittance or reflectance factor (see kind)"})
        ds = ds.assign_coords(
            spectrum=("spectrum", np.arange(len(labels)), {"long_name": "spectrum index"}),
            kind=("spectrum", [c["kind"] for c in coords], {"long_name": "quantity measured"}),
            substrate=("spectrum", [c["substrate"] for c in coords],
                       {"long_name": "substrate under the film (its reflectance, black or white); empty if none"}),
            geometry=("spectrum", [c["geometry"] for c in coords],
                      {"long_name": "illumination/viewing geometry (CIE 015 notation where it applies)"}),
            compound_seen=("spectrum", [c["compound_seen"] for c in coords],
                           {"long_name": "compound of the plate seen in transmission; empty if none"}),
            thickness=("spectrum", [c["thickness_mm"] for c in coords],
                       {"units": "mm", "long_name": "plate thickness (NaN where not a plate)"}),
            label=("spectrum", labels, {"long_name": "human-readable name of the spectrum"}),
        )
        if primary := res.primary:
            ds.attrs["primary_spectrum"] = labels.index(primary)
            ds.attrs["primary_label"] = primary
    if res.materials:
        names = list(res.materials)
        nk = np.stack([np.asarray(res.materials[k], complex) for k in names])
        ds = ds.assign_coords(compound=("compound", names, {"long_name": "compound name in the recipe"}))
        ds["n"] = (("compound", "wavelength"), nk.real, {"units": "1", "long_name": "refractive index n"})
        ds["k"] = (("compound", "wavelength"), nk.imag, {"units": "1", "long_name": "extinction coefficient k"})
    ills = list(res.recipe.lighting.illuminants)
    if res.colours and labels:
        lab = np.full((len(labels), len(ills), 3), np.nan)
        rgb = np.full((len(labels), len(ills), 3), np.nan)
        for r in res.colours:
            i, j = labels.index(r["spectrum"]), ills.index(r["illuminant"])
            lab[i, j] = (r["L"], r["a"], r["b"])
            rgb[i, j] = r.get("srgb", (np.nan,) * 3)
        ds = ds.assign_coords(
            illuminant=("illuminant", ills, {"long_name": "CIE illuminant (colour-science name)"}),
            cielab=("cielab", ["L*", "a*", "b*"], {"long_name": "CIE 1976 L*a*b* component"}),
            rgb=("rgb", ["R", "G", "B"], {"long_name": "sRGB channel"}))
        ds["lab"] = (("spectrum", "illuminant", "cielab"), lab,
                     {"units": "1", "long_name": "CIELAB (CIE 015:2018), white Y = 100 under the same illuminant",
                      "observer": f"CIE {obs} degree"})
        ds["srgb"] = (("spectrum", "illuminant", "rgb"), rgb,
                      {"units": "1", "long_name": "sRGB (IEC 61966-2-1), encoded, clipped to [0, 1], "
                                                  "adapted from the illuminant's white to D65 (CAT02)"})
    if res.multiangle:
        g = np.array([r["aspecular_deg"] for r in res.multiangle], float)
        ds = ds.assign_coords(aspecular_angle=("aspecular_angle", g, {
            "units": "degree", "long_name": "aspecular angle (from the specular direction, in the plane of incidence)"}))
        if "cielab" not in ds.coords:
            ds = ds.assign_coords(cielab=("cielab", ["L*", "a*", "b*"], {"long_name": "CIE 1976 L*a*b* component"}))
        ds["multiangle_lab"] = (("aspecular_angle", "cielab"),
                                np.array([[r["L"], r["a"], r["b"]] for r in res.multiangle], float),
                                {"units": "1", "long_name": "CIELAB at each aspecular angle",
                                 "illuminant": res.multiangle[0]["illuminant"], "observer": f"CIE {obs} degree"})
        if labels:
            rf = [k for k in labels if spectrum_coordinates(k)["kind"] == "reflectance factor"]
            angles = [spectrum_coordinates(k)["aspecular_deg"] for k in rf]
            if rf and sorted(angles) == sorted(g.tolist()):
                by_angle = dict(zip(angles, rf))
                ds["reflectance_factor"] = (("aspecular_angle", "wavelength"),
                                            np.stack([res.spectra[by_angle[a]] for a in g.tolist()]),
                                            {"units": "1", "long_name": "reflectance factor (π × BRDF)"})
    for name, v in res.scalars.items():
        try:
            val = float(v)
        except (TypeError, ValueError):
            continue
        unit = units_of_key(name)
        ds[_var_name(name)] = ((), val, {"long_name": name.replace("_", " "), **({"units": unit} if unit else {})})
    ds.attrs.update({
        "Conventions": "CF-1.10", "title": res.recipe.name, "source": f"nmmm {nmmm.__version__} (nmmm run)",
        "observer": f"CIE {obs} degree standard observer", "recipe": res.recipe_text or "",
        "notes": "\n".join(res.notes)})
    return ds


def _var_name(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_]+", "_", name).strip("_") or "value"


def write_run_netcdf(res: RunResult, path) -> Path:
    """Write :func:`run_to_xarray` of ``res`` into the netCDF-4 file ``path`` (h5netcdf engine)."""
    path = Path(path)
    run_to_xarray(res).to_netcdf(path, engine="h5netcdf")
    return path


# --------------------------------------------------------------------------------------
# sweeps


def sweep_to_xarray(df: pd.DataFrame, varies, attrs: dict | None = None) -> xr.Dataset:
    """The points of a sweep (the DataFrame of :func:`nmmm.recipes.sweep.load_results`) as one cube.

    ``varies`` is ``[(key, values), ...]`` as given to the sweep: each key becomes a dimension
    (in that order) whose coordinate holds its values, with the unit the key's name states; the
    primary spectrum becomes ``spectrum(<keys>..., wavelength)`` and every scalar column
    (``L_D65``, ``flop_index``, ``physics_s`` …) a variable over the keys. Points absent from
    ``df`` (not yet computed) are NaN.
    """
    import xarray as xr

    varies = [(k, list(v)) for k, v in varies]
    dims = [k for k, _ in varies]
    shape = tuple(len(v) for _, v in varies)
    coords = {}
    for k, vals in varies:
        attrs_k = {"long_name": f"recipe key {k}"}
        if (u := units_of_key(k)) is not None and all(isinstance(x, (int, float)) for x in vals):
            attrs_k["units"] = u
        coords[k] = (k, np.asarray(vals, dtype=object if any(isinstance(x, str) for x in vals) else float), attrs_k)
    index = {k: {_hashable(v): i for i, v in reversed(list(enumerate(vals)))} for k, vals in varies}
    wl = None
    for _, r in df.iterrows():
        if r.get("wavelength_nm") is not None:
            wl = np.asarray(r["wavelength_nm"], float)
            break
    skip = {"wavelength_nm", "spectrum", "primary", "worker", "point_id", "point_index"}
    scalar_cols = [c for c in df.columns if c not in skip and not c.startswith("param:")
                   and np.issubdtype(df[c].dtype, np.number)]
    data = {c: np.full(shape, np.nan) for c in scalar_cols}
    spec = np.full(shape + ((wl.size,) if wl is not None else (0,)), np.nan)
    pids = np.full(shape, "", dtype=object)
    for _, r in df.iterrows():
        try:
            pos = tuple(index[k][_hashable(r[f"param:{k}"])] for k in dims)
        except KeyError:
            continue  # a point of another grid in the same folder
        for c in scalar_cols:
            data[c][pos] = r[c]
        if wl is not None and r.get("spectrum") is not None:
            spec[pos] = np.asarray(r["spectrum"], float)
        pids[pos] = r.get("point_id", "")
    ds = xr.Dataset(coords=coords)
    if wl is not None:
        ds = ds.assign_coords(wavelength=("wavelength", wl, {
            "units": "nm", "long_name": "vacuum wavelength", "standard_name": "radiation_wavelength"}))
        primary = str(df["primary"].iloc[0]) if "primary" in df and len(df) else ""
        c = spectrum_coordinates(primary)
        ds["spectrum"] = (tuple(dims) + ("wavelength",), spec, {
            "units": "1", "long_name": f"primary spectrum: {primary}", "kind": c["kind"],
            "substrate": c["substrate"], "geometry": c["geometry"]})
    for c in scalar_cols:
        unit = "s" if c == "physics_s" else units_of_key(c)
        ds[_var_name(c)] = (tuple(dims), data[c], {"long_name": c.replace("_", " "), **({"units": unit} if unit else {})})
    ds["point_id"] = (tuple(dims), pids.astype(str), {"long_name": "point id (hash of recipe and values)"})
    ds.attrs.update({"Conventions": "CF-1.10", "source": "nmmm sweep", "varied_keys": ", ".join(dims),
                     **(attrs or {})})
    return ds


def _hashable(v):
    if isinstance(v, float) and v.is_integer():
        return v
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    return v


def write_sweep_cube(df: pd.DataFrame, varies, out_dir, attrs: dict | None = None,
                     zarr_min_points: int = ZARR_MIN_POINTS) -> dict[str, str]:
    """Write :func:`sweep_to_xarray` as ``OUT/results.nc`` and, when the grid has at least
    ``zarr_min_points`` points (and zarr is installed), ``OUT/results.zarr``; returns the paths written."""
    out = Path(out_dir)
    ds = sweep_to_xarray(df, varies, attrs)
    files = {}
    p = out / "results.nc"
    tmp = out / ".results.nc.tmp"
    ds.to_netcdf(tmp, engine="h5netcdf")
    tmp.replace(p)
    files["netcdf"] = str(p)
    n_points = int(np.prod([len(v) for _, v in varies])) if varies else 0
    if n_points >= zarr_min_points:
        try:
            import zarr  # noqa: F401
        except ImportError:
            import warnings

            warnings.warn(f"{n_points} sweep points: results.zarr not written (pip install zarr); results.nc has "
                          "the same cube", UserWarning, stacklevel=2)
        else:
            zs = ds.copy()
            for name in list(zs.variables):  # zarr stores object (str) arrays as fixed-width unicode
                if zs[name].dtype == object:
                    zs[name] = zs[name].astype(str)
            zs.to_zarr(out / "results.zarr", mode="w")
            files["zarr"] = str(out / "results.zarr")
    return files


# --------------------------------------------------------------------------------------
# notebook display


def run_result_html(res: RunResult) -> str:
    """HTML of a run for Jupyter: recipe, scalars, the colours table and a plot of its spectra."""
    from nmmm.html_repr import figure_png_base64, result_html

    rows = [("recipe", res.recipe.name), ("macro object", getattr(res.recipe, "macro", "")),
            ("wavelength", f"{res.wavelength_nm[0]:g}–{res.wavelength_nm[-1]:g} nm, {len(res.wavelength_nm)} points"),
            ("primary spectrum", res.primary or "-")]
    rows += [(k, f"{v:.4g}" if isinstance(v, float) else v) for k, v in res.scalars.items()]
    curves = dict(list(res.spectra.items())[:10])
    png = figure_png_base64(res.wavelength_nm, curves, ylabel="spectrum (1)", title=res.recipe.name) if curves else None
    colours = [{"spectrum": r["spectrum"], "illuminant": r["illuminant"], "L*": r["L"], "a*": r["a"], "b*": r["b"]}
               for r in res.colours]
    return result_html(f"RunResult: {res.recipe.name}", rows, png, {"CIELAB": colours})
