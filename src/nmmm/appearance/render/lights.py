"""Light sources with spectral power distributions, for the plate renderer.

Public objects
--------------
- :class:`SpectralPowerDistribution` — a tabulated SPD (wavelength_nm, values); ``.on(grid)``
  resamples it (linear), refusing grids outside its range.
- :func:`spd` — build one from a CIE illuminant name (colour-science ``SDS_ILLUMINANTS``:
  ``"D65"``, ``"A"``, ``"FL2"``, …), a CSV file (``wavelength_nm,power``), a
  ``(wavelength_nm, values)`` pair, a constant (equal energy) or an SPD.
- :func:`read_spd_csv` — read a measured emission spectrum (clear errors for missing or
  malformed files).
- :class:`DirectionalLight` — a distant source: spectral irradiance ``E⊥(λ)`` on a plane
  facing it, from direction ``direction`` (pointing *towards* the light).
- :class:`PointLight` — an isotropic point source of spectral intensity ``I(λ)`` (per sr)
  at ``position_mm``; irradiance ``I / r²`` (r in metres).
- :class:`UniformEnvironment` — constant spectral radiance from the whole sky.
- :class:`LatLongEnvironment` — a spectral latitude–longitude environment map
  (``LatLongEnvironment.sky(...)``: zenith/horizon/ground spectra).

Units: if the SPD is absolute (W m⁻² nm⁻¹ for a directional light, W sr⁻¹ nm⁻¹ for a point
light, W m⁻² sr⁻¹ nm⁻¹ for the environment), the rendered radiance is in
W m⁻² sr⁻¹ nm⁻¹; CIE illuminants are relative (100 at 560 nm) and so is the image.

References
----------
- CIE 015:2018 Colorimetry (standard illuminants), via colour-science
  (T. Mansencal et al., https://doi.org/10.5281/zenodo.3757045).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from nmmm.errors import DataFileError, InvalidInputError, OutOfRangeError
from nmmm.spectra import as_wavelength_nm, check_finite

__all__ = [
    "SpectralPowerDistribution",
    "spd",
    "read_spd_csv",
    "DirectionalLight",
    "PointLight",
    "UniformEnvironment",
    "LatLongEnvironment",
    "default_wavelengths",
]


def default_wavelengths() -> np.ndarray:
    """The default rendering grid: 380–780 nm every 5 nm (81 wavelengths)."""
    return np.arange(380.0, 780.0 + 1e-9, 5.0)


@dataclass(frozen=True, repr=False)
class SpectralPowerDistribution:
    """A tabulated spectral power distribution (values >= 0 on an increasing grid)."""

    wavelength_nm: np.ndarray
    values: np.ndarray
    name: str = "spd"

    def __post_init__(self):
        w = np.asarray(check_finite(self.wavelength_nm, "SPD wavelength_nm"), float).ravel()
        v = np.asarray(check_finite(self.values, "SPD values"), float).ravel()
        if w.size != v.size or w.size < 1:
            raise InvalidInputError(f"SPD needs as many values as wavelengths, got {w.size} and {v.size}")
        if w.size > 1 and np.any(np.diff(w) <= 0):
            raise InvalidInputError("SPD wavelengths must be strictly increasing")
        if np.any(v < 0):
            raise InvalidInputError(f"SPD '{self.name}' has negative power; emission spectra are >= 0")
        object.__setattr__(self, "wavelength_nm", w)
        object.__setattr__(self, "values", v)

    def __repr__(self):
        return f"<SPD '{self.name}' {self.wavelength_nm[0]:g}-{self.wavelength_nm[-1]:g} nm, {self.wavelength_nm.size} samples>"

    def on(self, wavelength_nm) -> np.ndarray:
        """Values resampled (linear interpolation) on ``wavelength_nm``; raises
        :class:`OutOfRangeError` for wavelengths outside the tabulated range."""
        w = as_wavelength_nm(wavelength_nm)
        lo, hi = self.wavelength_nm[0], self.wavelength_nm[-1]
        if np.any(w < lo - 1e-9) or np.any(w > hi + 1e-9):
            raise OutOfRangeError(
                f"SPD '{self.name}' covers {lo:g}-{hi:g} nm but the rendering grid spans "
                f"{np.min(w):g}-{np.max(w):g} nm; supply a spectrum covering the grid or narrow the grid"
            )
        if self.wavelength_nm.size == 1:
            return np.full(w.shape, self.values[0])
        return np.interp(w, self.wavelength_nm, self.values)


def read_spd_csv(path) -> SpectralPowerDistribution:
    """Read a CSV of ``wavelength_nm,power`` rows (an optional header line, ``#`` comments,
    comma / semicolon / tab separated). Raises :class:`DataFileError` naming the file and
    row for a missing file, a non-numeric row, fewer than two rows, unsorted wavelengths or
    negative power."""
    p = Path(path)
    if not p.is_file():
        raise DataFileError(f"spectral power distribution file not found: {str(p)!r}; expected a CSV "
                            "with rows 'wavelength_nm,power'")
    rows = []
    with p.open(newline="") as fh:
        text = fh.read()
    dialect_delim = ";" if text.count(";") > text.count(",") else ("\t" if "\t" in text and "," not in text else ",")
    for i, row in enumerate(csv.reader(text.splitlines(), delimiter=dialect_delim), start=1):
        cells = [c.strip() for c in row if c.strip() != ""]
        if not cells or cells[0].startswith("#"):
            continue
        if len(cells) < 2:
            raise DataFileError(f"{p}: row {i} has {len(cells)} column(s); expected 'wavelength_nm,power'")
        try:
            w, v = float(cells[0]), float(cells[1])
        except ValueError:
            if not rows:  # header line
                continue
            raise DataFileError(f"{p}: row {i} is not numeric ({','.join(cells)!r}); expected 'wavelength_nm,power'")
        if not (np.isfinite(w) and np.isfinite(v)):
            raise DataFileError(f"{p}: row {i} has a non-finite value")
        rows.append((w, v))
    if len(rows) < 2:
        raise DataFileError(f"{p}: needs at least two 'wavelength_nm,power' rows, found {len(rows)}")
    a = np.asarray(rows)
    if np.any(np.diff(a[:, 0]) <= 0):
        k = int(np.flatnonzero(np.diff(a[:, 0]) <= 0)[0])
        raise DataFileError(f"{p}: wavelengths must increase strictly (data row {k + 2}: {a[k + 1, 0]:g} after {a[k, 0]:g})")
    if np.any(a[:, 1] < 0):
        raise DataFileError(f"{p}: negative power in the emission spectrum (an SPD is >= 0)")
    if a[0, 0] < 100 or a[-1, 0] > 5000:
        raise DataFileError(f"{p}: wavelengths {a[0, 0]:g}-{a[-1, 0]:g} do not look like nm; give wavelength_nm")
    if not np.any(a[:, 1] > 0):
        raise DataFileError(f"{p}: the power is zero at every wavelength ({a[0, 0]:g}-{a[-1, 0]:g} nm): a light "
                            "source emits somewhere; check the power column")
    lo, hi = VISIBLE_NM
    if a[0, 0] > lo or a[-1, 0] < hi:
        import warnings

        warnings.warn(f"{p}: the spectrum covers only {a[0, 0]:g}-{a[-1, 0]:g} nm, not the visible {lo:g}-{hi:g} nm "
                      "that colour and rendering need; a render grid outside it is refused (measure or supply "
                      "the full range)", UserWarning, stacklevel=2)
    return SpectralPowerDistribution(a[:, 0], a[:, 1], name=p.stem)


#: The range (nm) a light source's spectrum should cover for colour and rendering.
VISIBLE_NM = (380.0, 780.0)


def spd(source) -> SpectralPowerDistribution:
    """A :class:`SpectralPowerDistribution` from a CIE illuminant name, a CSV path, a
    ``(wavelength_nm, values)`` pair, a positive constant (equal-energy) or an SPD."""
    if isinstance(source, SpectralPowerDistribution):
        return source
    if isinstance(source, (str, Path)):
        s = str(source)
        import colour

        from nmmm.colour.illuminants import canonical_illuminant

        s = canonical_illuminant(s) if s not in colour.SDS_ILLUMINANTS and not Path(s).exists() else s  # F11, TL84, CWF
        if s in colour.SDS_ILLUMINANTS:
            sd = colour.SDS_ILLUMINANTS[s]
            return SpectralPowerDistribution(np.asarray(sd.wavelengths, float), np.asarray(sd.values, float), name=s)
        if Path(s).suffix.lower() in (".csv", ".txt") or Path(s).exists():
            return read_spd_csv(s)
        raise InvalidInputError(
            f"unknown light spectrum {s!r}: give a CIE illuminant name known to colour-science "
            f"(e.g. 'D65', 'A', 'D50', 'FL2', 'LED-B3') or a CSV file 'wavelength_nm,power'"
        )
    if np.isscalar(source):
        v = float(source)
        if not (np.isfinite(v) and v >= 0):
            raise InvalidInputError(f"a constant SPD must be finite and >= 0, got {source!r}")
        return SpectralPowerDistribution(np.array([1.0, 1e5]), np.array([v, v]), name="equal energy")
    if isinstance(source, tuple) and len(source) == 2:
        return SpectralPowerDistribution(np.asarray(source[0], float), np.asarray(source[1], float), name="tabulated")
    raise InvalidInputError(f"cannot build an SPD from {type(source).__name__}; use a name, a CSV path, "
                            "(wavelength_nm, values) or a constant")


def _unit(v, name):
    a = np.asarray(check_finite(v, name), float).ravel()
    if a.shape != (3,):
        raise InvalidInputError(f"{name} must be a 3-vector, got shape {a.shape}")
    n = np.linalg.norm(a)
    if n == 0:
        raise InvalidInputError(f"{name} must be non-zero")
    return a / n


@dataclass(frozen=True)
class DirectionalLight:
    """A distant light: ``direction`` points from the scene towards the light (plate frame,
    z = plate normal); spectral irradiance on a surface facing it ``irradiance × SPD(λ)``.
    ``angular_diameter_deg`` > 0 gives the source a disc (radiance E⊥ / Ω, Ω its solid
    angle) whose mirror image appears in a smooth clear coat."""

    direction: tuple = (0.0, 0.0, 1.0)
    spectrum: object = "D65"
    irradiance: float = 1.0
    angular_diameter_deg: float = 0.0

    def __post_init__(self):
        a = float(check_finite(self.angular_diameter_deg, "angular_diameter_deg"))
        if not 0 <= a < 90:
            raise InvalidInputError(f"angular_diameter_deg must lie in [0, 90) (the Sun: 0.53), got {a!r}")
        object.__setattr__(self, "angular_diameter_deg", a)
        object.__setattr__(self, "direction", tuple(_unit(self.direction, "light direction")))
        object.__setattr__(self, "spectrum", spd(self.spectrum))
        e = float(check_finite(self.irradiance, "irradiance"))
        if e < 0:
            raise InvalidInputError(f"irradiance must be >= 0, got {e!r}")
        object.__setattr__(self, "irradiance", e)

    @classmethod
    def from_angles(cls, zenith_deg: float, azimuth_deg: float = 0.0, spectrum="D65", irradiance: float = 1.0,
                    angular_diameter_deg: float = 0.0):
        """Light from zenith angle θ (0 = overhead) and azimuth φ (from +x towards +y), degrees."""
        t, p = np.radians(zenith_deg), np.radians(azimuth_deg)
        return cls((np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)), spectrum, irradiance,
                   angular_diameter_deg)

    def spectral(self, wavelength_nm) -> np.ndarray:
        return self.irradiance * self.spectrum.on(wavelength_nm)


@dataclass(frozen=True)
class PointLight:
    """An isotropic point light at ``position_mm`` (plate frame) of spectral intensity
    ``intensity × SPD(λ)`` per steradian; irradiance falls as 1/r² with r in metres.
    ``radius_mm`` > 0 makes it a small uniform sphere (radiance I / (π ρ²), ρ in metres)
    whose mirror image appears in a smooth clear coat; it still lights the plate as a point."""

    position_mm: tuple = (0.0, 0.0, 1000.0)
    spectrum: object = "D65"
    intensity: float = 1.0
    radius_mm: float = 0.0

    def __post_init__(self):
        r = float(check_finite(self.radius_mm, "radius_mm"))
        if r < 0:
            raise InvalidInputError(f"radius_mm must be >= 0, got {r!r}")
        object.__setattr__(self, "radius_mm", r)
        p = np.asarray(check_finite(self.position_mm, "light position_mm"), float).ravel()
        if p.shape != (3,):
            raise InvalidInputError(f"light position_mm must be a 3-vector, got shape {p.shape}")
        object.__setattr__(self, "position_mm", tuple(p))
        object.__setattr__(self, "spectrum", spd(self.spectrum))
        e = float(check_finite(self.intensity, "intensity"))
        if e < 0:
            raise InvalidInputError(f"intensity must be >= 0, got {e!r}")
        object.__setattr__(self, "intensity", e)

    def spectral(self, wavelength_nm) -> np.ndarray:
        return self.intensity * self.spectrum.on(wavelength_nm)


@dataclass(frozen=True)
class UniformEnvironment:
    """A uniform sky: the same spectral radiance ``radiance × SPD(λ)`` from every direction."""

    spectrum: object = "D65"
    radiance: float = 1.0

    def __post_init__(self):
        object.__setattr__(self, "spectrum", spd(self.spectrum))
        e = float(check_finite(self.radiance, "radiance"))
        if e < 0:
            raise InvalidInputError(f"environment radiance must be >= 0, got {e!r}")
        object.__setattr__(self, "radiance", e)

    def spectral(self, wavelength_nm) -> np.ndarray:
        return self.radiance * self.spectrum.on(wavelength_nm)


@dataclass(frozen=True, repr=False)
class LatLongEnvironment:
    """A spectral environment map: radiance ``radiance`` (H, W, L) on ``wavelength_nm`` over
    a latitude–longitude grid (z up = the plate normal; row i at θ = (i + ½) π / H from the
    zenith, column j at φ = (j + ½) 2π / W from +x towards +y). Bilinear lookup between texel centres."""

    wavelength_nm: np.ndarray
    radiance: np.ndarray
    name: str = "environment map"

    def __post_init__(self):
        w = np.asarray(check_finite(self.wavelength_nm, "wavelength_nm"), float).ravel()
        r = np.asarray(check_finite(self.radiance, "environment radiance"), float)
        if r.ndim != 3 or r.shape[2] != w.size:
            raise InvalidInputError(f"radiance must be (height, width, {w.size}) on wavelength_nm, got {r.shape}")
        if np.any(r < 0):
            i, j, k = (int(x) for x in np.argwhere(r < 0)[0])
            raise InvalidInputError(f"environment radiance must be >= 0 (an emitted radiance); texel (row {i}, column "
                                    f"{j}) at {w[k]:g} nm is {r[i, j, k]:g} ({int(np.sum(r < 0))} negative values): "
                                    "clip the map at 0 or fix its calibration")
        object.__setattr__(self, "wavelength_nm", w)
        object.__setattr__(self, "radiance", r)

    def __repr__(self):
        h, w_, L = self.radiance.shape
        return f"<LatLongEnvironment '{self.name}' {w_}x{h}, {L} wavelengths>"

    @classmethod
    def sky(cls, wavelength_nm, zenith, horizon, ground=None, height: int = 32, width: int = 64, name="sky"):
        """Zenith spectrum blended into the horizon's as cos θ; ``ground`` (default
        0.2 × horizon) below the horizon (:func:`mitsuba_envmap.latlong_environment`)."""
        from nmmm.appearance.render.mitsuba_envmap import latlong_environment

        w = np.asarray(wavelength_nm, float).ravel()
        return cls(w, latlong_environment(w, zenith, horizon, ground, height, width), name)

    def _on(self, wavelength_nm):
        w = as_wavelength_nm(wavelength_nm).ravel()
        if w.shape == self.wavelength_nm.shape and np.allclose(w, self.wavelength_nm):
            return self.radiance
        lo, hi = self.wavelength_nm[0], self.wavelength_nm[-1]
        if np.any(w < lo - 1e-9) or np.any(w > hi + 1e-9):
            raise OutOfRangeError(f"environment map covers {lo:g}-{hi:g} nm, the grid spans {w.min():g}-{w.max():g} nm")
        flat = self.radiance.reshape(-1, self.wavelength_nm.size)
        return np.stack([np.interp(w, self.wavelength_nm, row) for row in flat]).reshape(
            self.radiance.shape[:2] + (w.size,))

    def texel(self, directions) -> np.ndarray:
        """Flat texel index (...) of unit directions (..., 3)."""
        d = np.asarray(directions, float)
        h, wd = self.radiance.shape[:2]
        th = np.arccos(np.clip(d[..., 2], -1, 1))
        ph = np.mod(np.arctan2(d[..., 1], d[..., 0]), 2 * np.pi)
        i = np.clip((th / np.pi * h).astype(np.int64), 0, h - 1)
        j = np.clip((ph / (2 * np.pi) * wd).astype(np.int64), 0, wd - 1)
        return i * wd + j

    def lookup(self, wavelength_nm, directions) -> np.ndarray:
        """Radiance (..., L) seen along ``directions``, bilinear between the four nearest texel
        centres (φ periodic, θ clamped at the first/last row), as the plate renderer reads it."""
        from nmmm.appearance.render.latlong_lookup import envmap_lookup_bilinear

        return envmap_lookup_bilinear(self, wavelength_nm, directions)

    def upper_quadrature(self, wavelength_nm, n_theta: int = 16, n_phi: int = 32):
        """(directions (K, 3), solid angles (K,), radiance (K, L)) of the upper hemisphere,
        the map averaged over n_theta × n_phi cells (equal steps in θ and φ)."""
        r = self._on(wavelength_nm)
        h, wd = r.shape[:2]
        th_t = (np.arange(h) + 0.5) / h * np.pi
        ph_t = (np.arange(wd) + 0.5) / wd * 2 * np.pi
        te = np.linspace(0, np.pi / 2, n_theta + 1)
        pe = np.linspace(0, 2 * np.pi, n_phi + 1)
        dirs, sa, rad = [], [], []
        sin_t = np.sin(th_t)
        for a in range(n_theta):
            rows = (th_t >= te[a]) & (th_t < te[a + 1])
            for b in range(n_phi):
                cols = (ph_t >= pe[b]) & (ph_t < pe[b + 1])
                tc, pc = 0.5 * (te[a] + te[a + 1]), 0.5 * (pe[b] + pe[b + 1])
                if rows.any() and cols.any():
                    wts = sin_t[rows][:, None] * np.ones(cols.sum())[None, :]
                    val = np.einsum("ij,ijl->l", wts, r[rows][:, cols]) / wts.sum()
                else:
                    val = r.reshape(-1, r.shape[2])[self.texel(
                        np.array([np.sin(tc) * np.cos(pc), np.sin(tc) * np.sin(pc), np.cos(tc)]))]
                dirs.append((np.sin(tc) * np.cos(pc), np.sin(tc) * np.sin(pc), np.cos(tc)))
                sa.append((np.cos(te[a]) - np.cos(te[a + 1])) * (pe[b + 1] - pe[b]))
                rad.append(val)
        return np.asarray(dirs), np.asarray(sa), np.asarray(rad)
