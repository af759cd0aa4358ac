"""Measured reflectance spectra in and out: CGATS.17 text, CxF3 XML and CSV.

- :class:`MeasuredSpectra` — spectra (N samples × W wavelengths, reflectance factor in [0, 1]),
  sample names, the instrument geometry and the file's keywords.
- :func:`read_cgats`, :func:`write_cgats` — CGATS.17 (ASTM E1708 / ISO 28178) text with
  ``SPECTRAL_NM<λ>`` fields (``SPECTRAL_<λ>``, ``NM<λ>``, ``R<λ>`` and Argyll's ``SPEC_<λ>`` also
  read), keyword ``MEASUREMENT_GEOMETRY``. Argyll's ``.ti3`` (``CTI3``) is read as percent, its
  format's unit, unless ``SPECTRAL_NORM`` says otherwise; ``SPECTRAL_BANDS`` /
  ``SPECTRAL_START_NM`` / ``SPECTRAL_END_NM`` must agree with the fields.
- :func:`read_cxf`, :func:`write_cxf`, :func:`cxf_geometries` — CxF3 (ISO 17972-1): each
  ``Object``'s ``ReflectanceSpectrum`` with its ``ColorSpecification`` (wavelength start and
  increment, geometry from CxF3-core's GeometryChoice: SphereGeometry ``di:8``/``de:8``, SingleAngle
  ``45:0``/``45a:0``, MultiAngle ``45as15`` …, UnknownGeometry); a multi-angle file holds one
  specification per angle or one MultiAngle specification of several BRDFAngles (split into one
  geometry per angle by each spectrum's Name), and one geometry is read at a time.
- :func:`read_spectra_csv` — ``wavelength_nm,<sample>,<sample>…`` (a column per sample).
- :func:`read_measured` — any of them by the file's suffix.

Units. A file holds reflectance factors (0–1) or percent (0–100). ``unit="auto"`` reads factors
and refuses values above 1.5 as "percent, not factors" (a measured factor reaches ~1.1 at most
for fluorescent whites), never rescaling silently; ``unit="percent"`` says so and divides by
100. CGATS's ``SPECTRAL_NORM`` keyword (100 or 1, as X-Rite writes it) declares it too. Near the
specular a metallic's multi-angle factors exceed 1 (a silver's 45as-15: ~3–5): a CxF3 file of
aspecular angles only is read as factors up to :data:`MULTI_ANGLE_FACTOR_MAX` when at one of its
angles no spectrum exceeds 1.5; ``unit="fraction"`` reads any values as factors.

Why not colour-science's readers: ``colour.read_sds_from_xrite_file`` reads X-Rite's CGATS
dialect but drops the geometry and keywords and does not see a truncated data block; colour-science
has no CxF reader in its core package (``colour-cxf`` is separate and not a dependency). The
spectra are handed to colour-science as ``SpectralDistribution`` objects
(:meth:`MeasuredSpectra.to_colour`).

References
----------
- ISO 28178:2009 Graphic technology — Exchange format for colour and process control data using
  XML or ASCII text (CGATS.17); ASTM E1708-95 Standard practice for electronic interchange of
  color and appearance data.
- ISO 17972-1:2015 Graphic technology — Colour data exchange format — Part 1: Relationship to CxF3.
"""

from __future__ import annotations

import re
import shlex
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from nmmm.errors import DataFileError, InvalidInputError

__all__ = ["MeasuredSpectra", "read_cgats", "write_cgats", "read_cxf", "write_cxf", "cxf_geometries", "canonical_geometry",
           "read_spectra_csv", "read_measured", "PERCENT_THRESHOLD"]

#: a reflectance factor above this is read as percent (and refused under ``unit="auto"``)
PERCENT_THRESHOLD = 1.5
CXF_NS = "http://colorexchangeformat.com/CxF3-core"
_UNITS = ("auto", "fraction", "percent")
#: the largest reflectance factor read as factors without unit='fraction' in a multi-angle CxF3 file whose other
#: angles stay below PERCENT_THRESHOLD (a silver's near-specular 45as-15 reading: ~3-5)
MULTI_ANGLE_FACTOR_MAX = 15.0


@dataclass(frozen=True)
class MeasuredSpectra:
    """Reflectance spectra of N samples on one wavelength grid, with their geometry."""

    wavelength_nm: np.ndarray
    reflectance: np.ndarray  # (N, W), factors in [0, ~1.1]
    names: tuple
    geometry: str | None = None
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        w = np.asarray(self.wavelength_nm, float)
        r = np.atleast_2d(np.asarray(self.reflectance, float))
        if w.ndim != 1 or w.size < 2 or np.any(np.diff(w) <= 0):
            raise InvalidInputError("wavelength_nm must be 1-D and increasing, at least 2 values")
        if r.shape[-1] != w.size:
            raise InvalidInputError(f"reflectance has {r.shape[-1]} values per sample, the grid {w.size}")
        if len(self.names) != r.shape[0]:
            raise InvalidInputError(f"{len(self.names)} names for {r.shape[0]} samples")
        object.__setattr__(self, "wavelength_nm", w)
        object.__setattr__(self, "reflectance", r)
        object.__setattr__(self, "names", tuple(str(n) for n in self.names))

    def __len__(self) -> int:
        return self.reflectance.shape[0]

    def spectrum(self, name_or_index=0) -> np.ndarray:
        """One sample's spectrum, by name or index."""
        if isinstance(name_or_index, str):
            if name_or_index not in self.names:
                raise InvalidInputError(f"no sample {name_or_index!r}; the file has {list(self.names)[:10]}")
            return self.reflectance[self.names.index(name_or_index)]
        return self.reflectance[int(name_or_index)]

    def on_grid(self, wavelength_nm) -> np.ndarray:
        """The spectra interpolated (linearly) onto ``wavelength_nm``, which they must cover."""
        w = np.asarray(wavelength_nm, float)
        lo, hi = self.wavelength_nm[0], self.wavelength_nm[-1]
        if w[0] < lo - 1e-9 or w[-1] > hi + 1e-9:
            raise InvalidInputError(f"the measured spectra cover {lo:g}–{hi:g} nm; the grid needs {w[0]:g}–{w[-1]:g} nm "
                                    "(narrow the recipe's [spectral] range)")
        return np.stack([np.interp(w, self.wavelength_nm, r) for r in self.reflectance])

    def to_colour(self):
        """colour-science ``MultiSpectralDistributions`` (labels = sample names)."""
        import colour

        return colour.MultiSpectralDistributions(self.reflectance.T, self.wavelength_nm, labels=list(self.names))


def _scaled(values: np.ndarray, unit: str, where: str, declared: str | None = None) -> np.ndarray:
    """Factors from ``values`` in ``unit``; ``declared``: how the file itself states the unit (CGATS
    SPECTRAL_NORM, Argyll's format): percent data that are all dark are then read, with a warning."""
    if unit not in _UNITS:
        raise InvalidInputError(f"unit must be one of {_UNITS}, got {unit!r}")
    if not np.all(np.isfinite(values)):
        raise DataFileError(f"{where}: a spectral value is not a finite number")
    top = float(values.max()) if values.size else 0.0
    if unit == "percent":
        if top <= PERCENT_THRESHOLD and declared:  # said, not refused: a chart of dark samples is possible
            import warnings

            warnings.warn(f"{where}: read as percent ({declared}), but no value exceeds {PERCENT_THRESHOLD:g} (the "
                          f"largest is {top:g} %): an almost black sample; if these are reflectance factors (0-1), "
                          "read with unit='fraction' (CLI --fraction) or fix the file", UserWarning, stacklevel=3)
        elif top <= PERCENT_THRESHOLD:
            raise DataFileError(f"{where}: read as percent (unit='percent', CLI --percent), but no value exceeds "
                                f"{PERCENT_THRESHOLD:g} (the largest is {top:g}): these are reflectance factors (0-1); "
                                "dividing them by 100 would give an almost black sample — drop --percent")
        return values / 100.0
    if top > PERCENT_THRESHOLD and unit == "auto":  # unit='fraction': the caller says so (a bright metallic near specular)
        raise DataFileError(f"{where}: reflectance up to {top:g} — these look like percent, not factors (0-1); "
                            "read with unit='percent' (CLI --percent) to divide by 100, or fix the file (a near-specular "
                            "multi-angle reading of an effect finish can exceed 1: then unit='fraction', CLI --fraction)")
    if float(values.min()) < -0.05:
        raise DataFileError(f"{where}: reflectance down to {float(values.min()):g} < 0; a measured reflectance factor is >= 0")
    return values


_SPECTRAL_FIELD = re.compile(r"^(?:SPECTRAL_NM_?|SPECTRAL_|SPEC_|NM_?|R_?)(\d+(?:\.\d+)?)$", re.IGNORECASE)


def _cgats_keyword(line: str, keywords: dict[str, str]) -> None:
    """Record a CGATS header line ``KEY value`` (value unquoted); ``KEYWORD "X"`` only declares X."""
    key, _, val = line.partition(" ")
    if key.upper() != "KEYWORD":
        keywords[key.upper()] = val.strip().strip('"')


def read_cgats(path, unit: str = "auto") -> MeasuredSpectra:
    """A CGATS.17 file's spectral fields (module docstring)."""
    p = Path(path)
    text = p.read_text(encoding="utf-8-sig", errors="strict")
    lines = [ln.strip() for ln in text.splitlines()]
    keywords, fields, rows = {}, None, []
    state = "header"
    for no, ln in enumerate(lines, 1):
        if not ln or ln.startswith("#"):
            continue
        if state == "header":
            if ln.upper() == "BEGIN_DATA_FORMAT":
                state, fields = "format", []
            elif ln.upper() == "BEGIN_DATA":
                raise DataFileError(f"{p.name}: line {no}: BEGIN_DATA before BEGIN_DATA_FORMAT; a CGATS file names its fields first")
            else:
                _cgats_keyword(ln, keywords)
        elif state == "format":
            if ln.upper() == "END_DATA_FORMAT":
                state = "between"
            else:
                fields += ln.split()
        elif state == "between":
            if ln.upper() == "BEGIN_DATA":
                state = "data"
            else:
                _cgats_keyword(ln, keywords)
        elif state == "data":
            if ln.upper() == "END_DATA":
                state = "done"
                break
            try:
                rows.append((no, shlex.split(ln)))
            except ValueError:
                raise DataFileError(f"{p.name}: line {no}: an unclosed quote") from None
    if fields is None:
        raise DataFileError(f"{p.name}: no BEGIN_DATA_FORMAT block; not a CGATS.17 file")
    if state != "done":
        raise DataFileError(f"{p.name}: truncated — no END_DATA after {len(rows)} data rows (the file ends inside "
                            f"the {'data' if state == 'data' else 'header'} block)")
    declared = keywords.get("NUMBER_OF_SETS")
    if declared is not None and declared.isdigit() and int(declared) != len(rows):
        raise DataFileError(f"{p.name}: NUMBER_OF_SETS says {declared} samples, the data block has {len(rows)} (truncated?)")
    spec = [(i, float(m.group(1))) for i, f in enumerate(fields) if (m := _SPECTRAL_FIELD.match(f))]
    if not spec:
        raise DataFileError(f"{p.name}: no spectral fields (SPECTRAL_NM400 …) among {fields[:8]}; only spectra can be "
                            "matched — export the spectral data from the instrument")
    name_col = next((fields.index(k) for k in ("SAMPLE_NAME", "SAMPLE_ID") if k in fields), None)
    vals, names = [], []
    for no, r in rows:
        if len(r) != len(fields):
            raise DataFileError(f"{p.name}: line {no}: {len(r)} values for {len(fields)} fields (truncated or misquoted row)")
        try:
            vals.append([float(r[i]) for i, _ in spec])
        except ValueError:
            raise DataFileError(f"{p.name}: line {no}: a spectral value is not a number") from None
        names.append(r[name_col] if name_col is not None else f"sample {len(names) + 1}")
    norm = keywords.get("SPECTRAL_NORM")
    try:
        declared = None if norm is None else ("percent" if abs(float(norm) - 100) < 1e-9 else
                                              "fraction" if abs(float(norm) - 1) < 1e-9 else None)
    except ValueError:
        declared = None
    if unit == "percent" and declared == "fraction":
        raise DataFileError(f"{p.name}: read as percent (unit='percent', CLI --percent), but the file says SPECTRAL_NORM "
                            f"{norm} (reflectance factors, 0-1); drop --percent, or fix the keyword if the data are percent")
    first = next((ln for ln in lines if ln and not ln.startswith("#")), "")
    argyll = first.split()[0].upper() in ("CTI3", "CTI1", "CTI2") if first else False
    said = None if declared is None else f"SPECTRAL_NORM {norm}"
    if argyll and declared is None and unit == "auto":
        declared, said = "percent", "the CTI3 format's unit, no SPECTRAL_NORM"  # Argyll's SPEC_<nm> are 0-100
    from_file = unit == "auto" and declared is not None
    if from_file:
        unit = declared
    order = np.argsort([w for _, w in spec])
    w = np.array([spec[i][1] for i in order])
    _check_spectral_bands(p.name, keywords, w)
    R = _scaled(np.array(vals, float)[:, order] if vals else np.zeros((0, w.size)), unit, p.name,
                declared=said if from_file else None)
    if R.shape[0] == 0:
        raise DataFileError(f"{p.name}: the data block holds no samples")
    geo = keywords.get("MEASUREMENT_GEOMETRY") or keywords.get("GEOMETRY")
    return MeasuredSpectra(w, R, tuple(names), geo, keywords)


def _check_spectral_bands(name: str, keywords: dict, w: np.ndarray) -> None:
    """Argyll's (and CGATS's common) ``SPECTRAL_BANDS`` / ``SPECTRAL_START_NM`` / ``SPECTRAL_END_NM``
    keywords, where given, must describe the spectral fields found (else fields were lost)."""
    said = []
    for key, got in (("SPECTRAL_BANDS", float(w.size)), ("SPECTRAL_START_NM", float(w[0])), ("SPECTRAL_END_NM", float(w[-1]))):
        v = keywords.get(key)
        try:
            if v is not None and abs(float(v) - got) > 1e-6:
                said.append(f"{key} {v} but the fields give {got:g}")
        except ValueError:
            raise DataFileError(f"{name}: {key} {v!r} is not a number") from None
    if said:
        raise DataFileError(f"{name}: the header and the spectral fields disagree ({'; '.join(said)}); fields missing or "
                            "the header stale — re-export the file")


def _fmt(x: float) -> str:
    return f"{x:.6f}"


def write_cgats(path, spectra: MeasuredSpectra, originator: str = "nmmm") -> Path:
    """CGATS.17 text (factors, ``SPECTRAL_NORM 1``), atomically."""
    from nmmm.atomic_io import atomic_write_text

    w = spectra.wavelength_nm
    fields = ["SAMPLE_ID", "SAMPLE_NAME"] + [f"SPECTRAL_NM{x:g}" for x in w]
    out = ["CGATS.17", f'ORIGINATOR "{originator}"', 'DESCRIPTOR "reflectance factor"']
    if spectra.geometry:  # keywords outside CGATS.17's reserved list are declared with KEYWORD before use
        out += ['KEYWORD "MEASUREMENT_GEOMETRY"', f'MEASUREMENT_GEOMETRY "{spectra.geometry}"']
    out += ['KEYWORD "SPECTRAL_NORM"', "SPECTRAL_NORM 1", f"NUMBER_OF_FIELDS {len(fields)}", "BEGIN_DATA_FORMAT", " ".join(fields), "END_DATA_FORMAT",
            f"NUMBER_OF_SETS {len(spectra)}", "BEGIN_DATA"]
    for i, (name, r) in enumerate(zip(spectra.names, spectra.reflectance), 1):
        safe = name.replace('"', "'")
        out.append(f'{i} "{safe}" ' + " ".join(_fmt(v) for v in r))
    out.append("END_DATA")
    atomic_write_text(path, "\n".join(out) + "\n")
    return Path(path)


# ---------------------------------------------------------------------------------------- CxF3


def _local(tag: str) -> str:
    return tag.rsplit("}", 1)[-1]


def _find(el, name):
    return next((c for c in el.iter() if _local(c.tag) == name), None)


_SPHERE_GEOMETRY = {"Specular_Included": "di:8", "Specular_Excluded": "de:8", "Diffuse": "d:d"}


def _angle(el, name, where):
    a = _find(el, name)
    try:
        return float(a.text)
    except (AttributeError, TypeError, ValueError):
        raise DataFileError(f"{where}: <{_local(el.tag)}> without a numeric <{name}>") from None


def _geometry_of_spec(spec, where: str = "CxF3") -> str | None:
    """The geometry of one ``ColorSpecification`` as nmmm writes it: CxF3-core's GeometryChoice is
    EmissiveMode | SphereGeometry (``Specular_Included`` -> ``"di:8"``, ``Specular_Excluded`` ->
    ``"de:8"``) | SingleAngle (``"45:0"``; ``"45a:0"`` / ``"0:45a"`` when its
    SingleAngleConfiguration is Annular) | UnknownGeometry (its text) | MultiAngle (each BRDFAngle's
    Notation attribute, or ``"45as15"`` from its angles; a list when there are several, each spectrum's
    Name then picks its angle). A non-standard ``<Geometry>`` text (older nmmm files) is read too."""
    gc = _find(spec, "GeometryChoice")
    if gc is not None:
        kids = list(gc)
        if not kids:
            raise DataFileError(f"{where}: an empty <GeometryChoice>; CxF3-core needs SphereGeometry, SingleAngle, "
                                "MultiAngle, UnknownGeometry or EmissiveMode")
        el, kind = kids[0], _local(kids[0].tag)
        if kind == "SphereGeometry":
            text = (el.text or "").strip()
            if text not in _SPHERE_GEOMETRY:
                raise DataFileError(f"{where}: SphereGeometry {text!r}; CxF3-core allows {list(_SPHERE_GEOMETRY)}")
            return _SPHERE_GEOMETRY[text]
        if kind == "SingleAngle":
            ill, meas = _angle(el, "IlluminationAngle", where), _angle(el, "MeasurementAngle", where)
            conf = _find(el, "SingleAngleConfiguration")
            annular = conf is not None and (conf.text or "").strip() == "Annular"
            a_ill = "a" if annular and ill != 0 else ""
            a_meas = "a" if annular and ill == 0 and meas != 0 else ""
            return f"{ill:g}{a_ill}:{meas:g}{a_meas}"
        if kind == "MultiAngle":
            names = []
            for b in (c for c in el if _local(c.tag) == "BRDFAngle"):
                note = b.get("Notation") or (getattr(_find(b, "Notation"), "text", None) or "").strip()  # XSD: attribute
                names.append(note or f"{_angle(b, 'IlluminationAngle', where):g}as{_angle(b, 'Aspecular', where):g}")
            if not names:
                raise DataFileError(f"{where}: a MultiAngle specification without a BRDFAngle (CxF3-core needs one or more)")
            if len(set(names)) != len(names):
                raise DataFileError(f"{where}: a MultiAngle specification names an angle twice: {names}")
            return names[0] if len(names) == 1 else list(names)  # several: each spectrum's Name picks its angle
        if kind == "UnknownGeometry":
            text = (el.text or "").strip()
            return None if text.lower() in ("", "unknown") else text
        if kind == "EmissiveMode":
            raise DataFileError(f"{where}: an emissive measurement (EmissiveMode), not a reflectance geometry")
        raise DataFileError(f"{where}: <{kind}> in GeometryChoice; CxF3-core allows SphereGeometry, SingleAngle, "
                            "MultiAngle, UnknownGeometry or EmissiveMode")
    single = _find(spec, "SingleAngle")
    if single is not None:
        return f"{_angle(single, 'IlluminationAngle', where):g}:{_angle(single, 'MeasurementAngle', where):g}"
    g = _find(spec, "Geometry")
    if g is not None and (g.text or "").strip():
        return g.text.strip()
    return None


def _cxf_tree(p: Path):
    try:
        root = ET.parse(p).getroot()
    except ET.ParseError as exc:
        raise DataFileError(f"{p.name}: not well-formed XML ({exc}); a truncated CxF3 file?") from None
    if _local(root.tag) != "CxF":
        raise DataFileError(f"{p.name}: the root element is <{_local(root.tag)}>, a CxF3 file's is <cc:CxF>")
    specs = {}
    for s in root.iter():
        if _local(s.tag) == "ColorSpecification":
            wr = _find(s, "WavelengthRange")
            specs[s.get("Id")] = dict(geometry=_geometry_of_spec(s, f"{p.name}: ColorSpecification {s.get('Id')!r}"),
                                      start=float(wr.get("StartWL")) if wr is not None and wr.get("StartWL") else None,
                                      increment=float(wr.get("Increment")) if wr is not None and wr.get("Increment") else None)
    return root, specs


def _cxf_samples(p: Path):
    root, specs = _cxf_tree(p)
    out = []
    for obj in root.iter():
        if _local(obj.tag) != "Object":
            continue
        for rs in obj.iter():
            if _local(rs.tag) != "ReflectanceSpectrum":
                continue
            sp = specs.get(rs.get("ColorSpecification"), {})
            start = rs.get("StartWL") or sp.get("start")
            inc = rs.get("Increment") or sp.get("increment")
            if start is None:
                raise DataFileError(f"{p.name}: object {obj.get('Name')!r}: a ReflectanceSpectrum without StartWL")
            if inc is None:
                raise DataFileError(f"{p.name}: object {obj.get('Name')!r}: no wavelength Increment — neither the "
                                    f"ReflectanceSpectrum nor its ColorSpecification {rs.get('ColorSpecification')!r} "
                                    "has <WavelengthRange StartWL=... Increment=...> (CxF3-core requires it); add it, "
                                    "nmmm does not guess the spacing")
            try:
                v = np.array([float(x) for x in (rs.text or "").split()])
            except ValueError:
                raise DataFileError(f"{p.name}: object {obj.get('Name')!r}: a spectral value is not a number") from None
            geometry = sp.get("geometry")
            if isinstance(geometry, list):  # a MultiAngle specification of several BRDFAngles
                geometry = _multi_angle_of(rs, geometry, f"{p.name}: object {obj.get('Name')!r}")
            out.append((obj.get("Name") or obj.get("Id") or f"object {len(out) + 1}", geometry,
                        float(start) + float(inc) * np.arange(v.size), v))
    if not out:
        raise DataFileError(f"{p.name}: no ReflectanceSpectrum in any Object; only spectra can be matched")
    return out


def _multi_angle_of(rs, notations: list, where: str) -> str:
    """The BRDFAngle of one ReflectanceSpectrum in a MultiAngle ColorSpecification: its ``Name``
    attribute is the angle's Notation (compared after :func:`canonical_geometry`)."""
    name = (rs.get("Name") or "").strip()
    if not name:
        raise DataFileError(f"{where}: a ReflectanceSpectrum of the MultiAngle ColorSpecification "
                            f"{rs.get('ColorSpecification')!r} ({len(notations)} BRDFAngles {notations}) has no Name; "
                            "nmmm does not guess which angle it is — set Name to the Notation of its BRDFAngle")
    hit = [n for n in notations if canonical_geometry(n) == canonical_geometry(name)]
    if not hit:
        raise DataFileError(f"{where}: ReflectanceSpectrum Name {name!r} is none of the BRDFAngle Notations {notations} "
                            f"of its ColorSpecification {rs.get('ColorSpecification')!r}")
    return hit[0]


def cxf_geometries(path) -> list:
    """The geometries (``"45:0"``, ``"45:-15"`` …, or None) of a CxF3 file's spectra, in file order."""
    seen = []
    for _, g, _, _ in _cxf_samples(Path(path)):
        if g not in seen:
            seen.append(g)
    return seen


def read_cxf(path, geometry: str | None = None, unit: str = "auto") -> MeasuredSpectra:
    """The spectra of a CxF3 file measured at one geometry (needed when the file has several)."""
    p = Path(path)
    samples = _cxf_samples(p)
    geos = []
    for _, g, _, _ in samples:
        if g not in geos:
            geos.append(g)
    if geometry is None and len(geos) > 1:
        raise DataFileError(f"{p.name}: spectra at {len(geos)} geometries {geos}; a spectrum set is one geometry — "
                            "choose one (geometry=..., CLI --geometry)")
    want = geos[0] if geometry is None else geometry
    chosen = [s for s in samples if canonical_geometry(s[1]) == canonical_geometry(want)]  # --geometry SCE finds de:8
    if not chosen:
        raise DataFileError(f"{p.name}: no spectra at geometry {geometry!r}; the file has {geos}")
    names = [n for n, *_ in chosen]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise DataFileError(f"{p.name}: sample name(s) {twice} appear more than once at geometry {want!r}; within one "
                            "geometry each object needs its own name (two spectra of one object need two "
                            "ColorSpecifications, e.g. SphereGeometry Specular_Included and Specular_Excluded)")
    w = chosen[0][2]
    for name, _, wi, _ in chosen:
        if wi.size != w.size or not np.allclose(wi, w):
            raise DataFileError(f"{p.name}: object {name!r} is on another wavelength grid ({wi[0]:g}–{wi[-1]:g} nm, "
                                f"{wi.size} values) than the first ({w[0]:g}–{w[-1]:g} nm, {w.size})")
    values = np.stack([v for *_, v in chosen])
    if unit == "auto" and values.size and PERCENT_THRESHOLD < float(values.max()) <= MULTI_ANGLE_FACTOR_MAX:
        # a multi-angle file: near the specular a metallic's factors exceed 1 (3-5 at 45as-15 for a silver); the
        # file is in factors when, at another of its angles, no spectrum exceeds the percent threshold
        top = {}
        for _, g, _, v in samples:
            top[canonical_geometry(g)] = max(top.get(canonical_geometry(g), 0.0), float(np.max(v)))
        if all(_ASPECULAR.fullmatch(g or "") for g in top) and min(top.values()) <= PERCENT_THRESHOLD:
            unit = "fraction"
    R = _scaled(values, unit, p.name)
    return MeasuredSpectra(w, R, tuple(n for n, *_ in chosen), chosen[0][1], {"geometries": geos})


_ANGLES = re.compile(r"(-?\d+(?:\.\d+)?)([ac]?):(-?\d+(?:\.\d+)?)([ac]?)")
#: a multi-angle (goniospectrophotometer) geometry: illumination angle, "as", aspecular angle (ASTM E2175)
_ASPECULAR = re.compile(r"(-?\d+(?:\.\d+)?)as(-?\d+(?:\.\d+)?)")


def canonical_geometry(geometry: str | None) -> str | None:
    """A measuring geometry in one spelling: ``"di:8"`` (sphere, specular included: SCI, d/8:i,
    d:8i), ``"de:8"`` (SCE, d/8:e, d:8e), ``"d:8"`` (sphere, specular component not said),
    ``"45a:0"`` / ``"0:45a"`` (annular or circumferential, ``c``), ``"45:0"`` (``45/0``, ``45°/0°``,
    uniplanar); anything else stripped. CIE 15:2004 §5 names these geometries."""
    if geometry is None:
        return None
    g = str(geometry).strip()
    t = g.lower().replace(" ", "").replace("°", "").replace("/", ":").replace("_", "")
    if t in ("sci", "di:8", "d:8i", "d:8:i", "d8i", "spin", "specularincluded", "d:8sci", "d8:i"):
        return "di:8"
    if t in ("sce", "de:8", "d:8e", "d:8:e", "d8e", "spex", "specularexcluded", "d:8sce", "d8:e"):
        return "de:8"
    if t in ("d:8", "d8", "8:d"):
        return "d:8"
    m = _ANGLES.fullmatch(t)
    if m:
        return f"{float(m.group(1)):g}{'a' if m.group(2) else ''}:{float(m.group(3)):g}{'a' if m.group(4) else ''}"
    m = _ASPECULAR.fullmatch(t)
    if m:
        return f"{float(m.group(1)):g}as{float(m.group(2)):g}"
    return g or None


_SPHERE_WORDS = {"di:8": "a sphere with the specular component included (SCI)",
                 "de:8": "a sphere with the specular component excluded (SCE)",
                 "d:8": "a sphere, the specular component not said"}
_PREDICTABLE = ("di:8", "de:8", "0:d", "45a:0", "0:45a")


def geometry_mismatch(measured: str | None, predicted: str) -> str | None:
    """What differs between a target's measuring geometry and the recipe's prediction, in words
    (None when they agree: same geometry after :func:`canonical_geometry`, or 45a:0 against 0:45a,
    equal by Helmholtz reciprocity)."""
    m, p = canonical_geometry(measured), canonical_geometry(predicted)
    if m is None or m == p or {m, p} == {"45a:0", "0:45a"}:
        return None
    fix = f'; set [measurement] geometry = "{m}" in the recipe to predict what was measured' if m in _PREDICTABLE else ""
    if {m, p} == {"di:8", "de:8"}:
        lighter = "target" if m == "di:8" else "prediction"
        return (f"the target was measured {_SPHERE_WORDS[m]}, the recipe predicts {_SPHERE_WORDS[p]}: they differ by the "
                f"gloss (about 4 % reflected at the surface), so the {lighter} reads lighter, most on dark colours{fix}")
    if m == "d:8" and p in ("di:8", "de:8"):
        return (f"the target's geometry {measured!r} is {_SPHERE_WORDS[m]}; the recipe predicts {_SPHERE_WORDS[p]} — "
                "check the instrument's SCI/SCE setting (they differ by the gloss)")
    if m == "45:0" and p in ("45a:0", "0:45a"):
        return (f"the target is {measured!r} (uniplanar, or annular not said), the recipe predicts {p} (annular): equal "
                "for a diffusing, non-directional paint; a metallic, pearlescent or textured finish differs")
    if {m, p} <= {"0:d", "di:8"}:
        return (f"the target is {m}, the recipe predicts {p}: both include the specular component and differ only by the "
                f"0° / 8° incidence (negligible for a matt or semi-gloss paint){fix}")
    sphere = lambda g: g in _SPHERE_WORDS or g == "0:d"  # noqa: E731
    if sphere(m) != sphere(p) and (sphere(m) or _ANGLES.fullmatch(m)):
        kind_m = "a sphere (diffuse) reading" if sphere(m) else "a directional (45°/0°) reading"
        kind_p = "a sphere (diffuse) prediction" if sphere(p) else "a directional (45°/0°) prediction"
        return (f"the target is {kind_m} ({m}), the recipe gives {kind_p} ({p}): a sphere includes light at every "
                f"angle, 45°/0° excludes the gloss and sees the surface texture — not comparable{fix}")
    return (f"the target's geometry {measured!r} is not one nmmm predicts ({', '.join(_PREDICTABLE)}); the recipe "
            f"predicts {p} — check that they describe the same measurement")


def _geometry_xml(spec_el, geometry: str | None):
    """MeasurementSpec with CxF3-core's GeometryChoice (the reader's mapping, reversed)."""
    g = canonical_geometry(geometry)
    ms = ET.SubElement(spec_el, f"{{{CXF_NS}}}MeasurementSpec")
    ET.SubElement(ms, f"{{{CXF_NS}}}MeasurementType").text = "Spectrum_Reflectance"
    gc = ET.SubElement(ms, f"{{{CXF_NS}}}GeometryChoice")
    m = _ANGLES.fullmatch(g or "")
    if g in ("di:8", "de:8"):
        ET.SubElement(gc, f"{{{CXF_NS}}}SphereGeometry").text = ("Specular_Included" if g == "di:8"
                                                                  else "Specular_Excluded")
    elif m:
        sa = ET.SubElement(gc, f"{{{CXF_NS}}}SingleAngle")
        annular = bool(m.group(2) or m.group(4))
        ET.SubElement(sa, f"{{{CXF_NS}}}SingleAngleConfiguration").text = "Annular" if annular else "Uniplanar"
        ET.SubElement(sa, f"{{{CXF_NS}}}IlluminationAngle").text = m.group(1)
        ET.SubElement(sa, f"{{{CXF_NS}}}MeasurementAngle").text = m.group(3)
    else:
        ET.SubElement(gc, f"{{{CXF_NS}}}UnknownGeometry").text = g or "unknown"
    return ms


def _multi_angle_xml(spec_el, notations: list):
    """MeasurementSpec with CxF3-core's MultiAngle: one BRDFAngle per ``"<illumination>as<aspecular>"``
    geometry (IlluminationAngle, Aspecular elements; Notation attribute), the spectra naming theirs."""
    ms = ET.SubElement(spec_el, f"{{{CXF_NS}}}MeasurementSpec")
    ET.SubElement(ms, f"{{{CXF_NS}}}MeasurementType").text = "Spectrum_Reflectance"
    gc = ET.SubElement(ms, f"{{{CXF_NS}}}GeometryChoice")
    ma = ET.SubElement(gc, f"{{{CXF_NS}}}MultiAngle")
    for note in notations:
        ill, asp = _ASPECULAR.fullmatch(note).groups()
        b = ET.SubElement(ma, f"{{{CXF_NS}}}BRDFAngle", Notation=note)
        ET.SubElement(b, f"{{{CXF_NS}}}IlluminationAngle").text = ill
        ET.SubElement(b, f"{{{CXF_NS}}}Aspecular").text = asp
    return ms


#: CxF3-core's WavelengthRange: StartWL an integer nm in [360, 400], Increment an integer nm
CXF_START_WL_NM = (360, 400)


def _cxf_grid(w: np.ndarray) -> tuple:
    d = np.diff(w)
    if not np.allclose(d, d[0]):
        raise InvalidInputError("CxF3 spectra need a uniform wavelength grid (StartWL + Increment)")
    start, inc = float(w[0]), float(d[0])
    if abs(start - round(start)) > 1e-9 or abs(inc - round(inc)) > 1e-9:
        raise InvalidInputError(f"CxF3-core's StartWL and Increment are integers (nm); this grid starts at {start:g} nm "
                                f"in steps of {inc:g} nm — resample onto whole nanometres, or write CGATS")
    lo, hi = CXF_START_WL_NM
    if not lo <= round(start) <= hi:
        raise InvalidInputError(f"CxF3-core requires StartWL between {lo} and {hi} nm; this grid starts at {start:g} nm "
                                f"— {'extend the [spectral] range down to 400 nm' if start > hi else f'start it at {lo} nm or above'}"
                                ", or write CGATS (any grid)")
    return int(round(start)), int(round(inc))


def write_cxf(path, spectra, creator: str = "nmmm", creation_date: str | None = None) -> Path:
    """CxF3 XML of one :class:`MeasuredSpectra` or several (one per geometry: a multi-angle set
    whose objects share names), atomically, valid against CxF3-core: geometry ``di:8``/``de:8`` as
    SphereGeometry Specular_Included/Excluded, ``45:0``/``45a:0``/``0:45a`` as SingleAngle with its
    SingleAngleConfiguration (Uniplanar/Annular), multi-angle ``"45as15"`` sets (illumination,
    aspecular angle) on one grid as one MultiAngle ColorSpecification with a BRDFAngle each (each
    ReflectanceSpectrum's Name = its angle's Notation), others as UnknownGeometry; the grid uniform, in
    whole nm, starting at 360–400 nm (the schema's StartWL). ``creation_date`` (ISO 8601, default
    now, UTC) goes on the file and each object."""
    from datetime import datetime, timezone

    from nmmm.atomic_io import atomic_write_bytes

    created = creation_date or datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")

    sets = [spectra] if isinstance(spectra, MeasuredSpectra) else list(spectra)
    ET.register_namespace("cc", CXF_NS)
    root = ET.Element(f"{{{CXF_NS}}}CxF")
    info = ET.SubElement(root, f"{{{CXF_NS}}}FileInformation")
    ET.SubElement(info, f"{{{CXF_NS}}}Creator").text = creator
    ET.SubElement(info, f"{{{CXF_NS}}}CreationDate").text = created
    res = ET.SubElement(root, f"{{{CXF_NS}}}Resources")
    coll = ET.SubElement(res, f"{{{CXF_NS}}}ObjectCollection")
    objects = {}
    cs_coll = ET.SubElement(res, f"{{{CXF_NS}}}ColorSpecificationCollection")
    groups = {}  # ColorSpecification -> the sets it holds: one per set, or one MultiAngle per grid
    for k, s in enumerate(sets):
        grid = _cxf_grid(s.wavelength_nm)
        multi = _ASPECULAR.fullmatch(canonical_geometry(s.geometry) or "")
        groups.setdefault(("multi", grid) if multi else ("one", k), (grid, []))[1].append(s)
    for k, ((kind, _), ((start, inc), members)) in enumerate(groups.items()):
        sid = f"CS{k + 1}"
        cs = ET.SubElement(cs_coll, f"{{{CXF_NS}}}ColorSpecification", Id=sid)
        if kind == "multi":
            notes = [canonical_geometry(m.geometry) for m in members]
            if len(set(notes)) != len(notes):
                raise InvalidInputError(f"CxF3 multi-angle sets name an angle twice: {notes}")
            ms = _multi_angle_xml(cs, notes)
        else:
            ms, notes = _geometry_xml(cs, members[0].geometry), [None]
        ET.SubElement(ms, f"{{{CXF_NS}}}WavelengthRange", StartWL=str(start), Increment=str(inc))
        for s, note in zip(members, notes):
            for name, r in zip(s.names, s.reflectance):
                if name not in objects:
                    obj = ET.SubElement(coll, f"{{{CXF_NS}}}Object", ObjectType="Standard", Name=name,
                                        Id=str(len(objects) + 1))
                    ET.SubElement(obj, f"{{{CXF_NS}}}CreationDate").text = created
                    objects[name] = ET.SubElement(obj, f"{{{CXF_NS}}}ColorValues")
                attrs = dict(ColorSpecification=sid, StartWL=str(start)) | ({"Name": note} if note else {})
                rs = ET.SubElement(objects[name], f"{{{CXF_NS}}}ReflectanceSpectrum", **attrs)
                rs.text = " ".join(_fmt(v) for v in r)
    ET.indent(root)
    atomic_write_bytes(path, ET.tostring(root, encoding="utf-8", xml_declaration=True))
    return Path(path)


# ---------------------------------------------------------------------------------------- CSV


def read_spectra_csv(path, unit: str = "auto", geometry: str | None = None) -> MeasuredSpectra:
    """``wavelength_nm,<name>,<name>…`` with a header line; one column per sample."""
    import csv

    p = Path(path)
    with p.open(encoding="utf-8-sig", newline="") as fh:
        rows = [r for r in csv.reader(fh) if r and not r[0].lstrip().startswith("#")]
    if len(rows) < 3:
        raise DataFileError(f"{p.name}: a header and at least two wavelengths are needed, got {len(rows)} lines")
    head = [h.strip() for h in rows[0]]
    if head[0].lower() not in ("wavelength_nm", "wavelength", "nm"):
        raise DataFileError(f"{p.name}: the first column must be 'wavelength_nm' (got {head[0]!r}); then one column per sample")
    if len(head) < 2:
        raise DataFileError(f"{p.name}: no sample columns after wavelength_nm")
    data = []
    for no, r in enumerate(rows[1:], 2):
        if len(r) != len(head):
            raise DataFileError(f"{p.name}: line {no}: {len(r)} values for {len(head)} columns (truncated row?)")
        try:
            data.append([float(x) for x in r])
        except ValueError:
            raise DataFileError(f"{p.name}: line {no}: a value is not a number") from None
    a = np.array(data)
    if np.any(np.diff(a[:, 0]) <= 0):
        raise DataFileError(f"{p.name}: wavelengths must increase down the file")
    names = tuple(h if h.lower() != "reflectance" else p.stem for h in head[1:])
    return MeasuredSpectra(a[:, 0], _scaled(a[:, 1:].T, unit, p.name), names, geometry, {})


def read_measured(path, unit: str = "auto", geometry: str | None = None) -> MeasuredSpectra:
    """A measured file by its suffix: ``.cxf`` / ``.xml`` (CxF3), ``.txt`` / ``.cgats`` / ``.cgt`` /
    ``.it8`` (CGATS.17), ``.csv``."""
    p = Path(path)
    if not p.exists():
        raise DataFileError(f"measured file {str(p)!r} not found")
    suf = p.suffix.lower()
    if suf in (".cxf", ".xml"):
        return read_cxf(p, geometry, unit)
    if suf in (".txt", ".cgats", ".cgt", ".it8", ".ti3"):
        s = read_cgats(p, unit)
        if geometry is not None and s.geometry is not None and canonical_geometry(s.geometry) != canonical_geometry(geometry):
            raise DataFileError(f"{p.name}: measured at {s.geometry!r}, not {geometry!r}")
        return s
    if suf == ".csv":
        return read_spectra_csv(p, unit, geometry)
    raise DataFileError(f"{p.name}: unknown measured-file type {suf!r}; give .cxf (CxF3), .txt/.cgats (CGATS.17) or .csv")
