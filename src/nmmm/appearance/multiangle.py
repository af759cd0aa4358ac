"""Multi-angle colour of gonio-apparent (effect) paints, flop index, colour travel.

Multi-angle spectrophotometers illuminate at 45° and measure the spectral reflectance
factor at several **aspecular angles** γ, measured in the plane of incidence from the
specular direction, positive towards the illuminator (ASTM E284 / E2194). With the
illumination at θ_i = 45°, the detector then lies at θ_v = 45° − γ from the normal on the
specular side (γ = 45°: along the normal; γ = 110°: 65° on the illuminator's side;
γ = −15°: 60° on the specular side, beyond the specular direction).

- :data:`ASTM_E2194_ASPECULAR_DEG` — 15°, 45°, 110° (the three angles required for metal
  flake pigmented materials), :data:`ASTM_E2194_ALL_ASPECULAR_DEG` adds the optional
  25° and 75°.
- :data:`ASTM_E2539_ASPECULAR_DEG` — −15°, 15°, 25°, 45°, 75°, 110° at 45° illumination
  (interference pigments). E2539 (§1.2) also calls for more than one illumination angle;
  only the 45° set is tabulated here. Geometries at another illumination angle (e.g. the
  15° ones of multi-angle instruments, written 15as−45 … 15as80) are evaluated with
  ``illumination_deg=15``; that list was not checked against the standard's text.
- :data:`GEOMETRY_SETS` — named geometry sets ``{illumination_deg: aspecular angles}`` of the
  standards and of commercial instruments, each with its source in :data:`GEOMETRY_SOURCES`;
  :func:`multiangle_lab_set` evaluates one set (one :class:`MultiAngleColour` per illumination).
  Only sets whose angles were found in a source are listed (see *Not listed* below).
- :func:`aspecular_directions` — (ωi, ωo) unit vectors for given aspecular angles, in the plane
  of incidence or out of it (``azimuth_deg``: the viewing direction turned about the specular
  direction, see below).
- :func:`multiangle_reflectance` — reflectance factors R = π f at those geometries.
- :func:`multiangle_lab` -> :class:`MultiAngleColour` (L*, a*, b*, C*, h per angle).
- :func:`flop_index` with :data:`FLOP_INDEX_METHODS` and the angles each formula takes,
  :data:`FLOP_INDEX_ASPECULAR_DEG`: ``"Alman 1987"``, the X-Rite / DuPont flop index
  FI = 2.69 (L*15 − L*110)^1.11 / (L*45)^0.86; ``"highlight-shade dL* (US 11472963)"``,
  ΔL*(h−s) = (L*15 + L*25)/2 − (L*75 + L*110)/2, the highlight − shade lightness difference
  defined in the abstract of US Patent 11,472,963 (see :func:`lightness_flop_highlight_shade`).
- :func:`plot_colour_travel` — a*b* trajectory, L* against aspecular angle, swatches.

Out-of-plane geometries
-----------------------
Some instruments also view out of the plane of incidence. Here such a geometry is written
(θi, γ, φ): the viewing direction makes the angle γ with the specular direction and is turned
by φ about it, φ = 0 being the in-plane side of positive γ (towards the normal and the
illuminator) and φ = +90° the +y side (the plane of incidence is xz, light from +x)::

    ωo = cos γ · r + sin γ · (cos φ · t + sin φ · ŷ),   r = (−sin θi, 0, cos θi),
    t = (cos θi, 0, sin θi)

so φ = 0 is the in-plane geometry above and (γ, 180°) is (−γ, 0). This parametrisation is this
module's own; ASTM E2175's out-of-plane notation was not read here. X-Rite's out-of-plane
geometries (:data:`XRITE_OUT_OF_PLANE_DEG`) turn about r the same way but count φ from the other
in-plane side: read literally here, 45as60az125.3 would view from below the horizon; read as
φ = 180° − 125.3°, every out-of-plane geometry of either illuminator views along a direction of
the other's set, within 0.04° (shared detectors, as the in-plane ones are).

*Not listed*, for want of a source read here: sets named after an instrument model (X-Rite
MA98, MA-T6, MA-T12; the "X-Rite 19 geometries" set is sourced from X-Rite's code, which names
no model), the 15° illumination set of ASTM E2539, the geometries and colour-difference formula of DIN 6175-2 / DIN 6175:2019,
and any flop formula named "flop index" other than Alman's. The stored copies of ASTM
E2539-12/-14 reachable here hold only the opening pages (scope, §1.1–1.9), not the apparatus
section or geometry table; X-Rite's brochures and manuals (MA98, MA-T6/T12, MA-5 QC, Color iQC
calculations guide) were not reachable beyond their first page; the open-access paper that
compares the MA98, Datacolor FX10 and BYK-mac geometries (J. Opt. Soc. Am. A 32(1), 1,
http://opg.optica.org/josaa/viewmedia.cfm?uri=josaa-32-1-1) was reachable only up to its
introduction. A ratio
L*15/L*110 is claimed in a coated-article patent application (US 2026/0176480 A1, abstract)
without being named a flop index; it is not registered.

References
----------
- ASTM E2194-14 (reapproved 2017), Standard Test Method for Multiangle Color
  Measurement of Metal Flake Pigmented Materials.
- ASTM E2539-14 (reapproved 2017), Standard Test Method for Multiangle Color
  Measurement of Interference Pigments.
- ASTM E284, Standard Terminology of Appearance (aspecular angle).
- D. H. Alman, "Directional color measurement of metallic flake finishes", Proc. ISCC
  Williamsburg Conference on Appearance (1987) 53–56 — the flop index used by X-Rite
  multi-angle instruments (MA68, MA98).
- C. S. McCamy, "Observation and measurement of the appearance of metallic materials.
  Part I. Macro appearance", Color Res. Appl. 21 (1996) 292.
- CIE 015:2018 Colorimetry — CIELAB.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.spectra import as_wavelength_nm, check_finite

__all__ = [
    "ASTM_E2194_ASPECULAR_DEG",
    "ASTM_E2194_ALL_ASPECULAR_DEG",
    "ASTM_E2539_ASPECULAR_DEG",
    "GEOMETRY_SETS",
    "GEOMETRY_SOURCES",
    "XRITE_OUT_OF_PLANE_DEG",
    "multiangle_lab_set",
    "aspecular_directions",
    "multiangle_reflectance",
    "multiangle_lab",
    "MultiAngleColour",
    "flop_index",
    "flop_index_alman1987",
    "lightness_flop_highlight_shade",
    "FLOP_INDEX_METHODS",
    "FLOP_INDEX_ASPECULAR_DEG",
    "plot_colour_travel",
]

#: ASTM E2194: the three aspecular angles required for metal flake pigmented materials (deg)
ASTM_E2194_ASPECULAR_DEG = (15.0, 45.0, 110.0)
#: ASTM E2194 with the optional 25° and 75° geometries (the usual five-angle instrument)
ASTM_E2194_ALL_ASPECULAR_DEG = (15.0, 25.0, 45.0, 75.0, 110.0)
#: ASTM E2539: aspecular angles at 45° illumination for interference pigments (deg)
ASTM_E2539_ASPECULAR_DEG = (-15.0, 15.0, 25.0, 45.0, 75.0, 110.0)

#: named multi-angle geometry sets: name -> {illumination angle (deg): aspecular angles (deg)}
GEOMETRY_SETS = {
    "ASTM E2194": {45.0: ASTM_E2194_ASPECULAR_DEG},
    "ASTM E2194 (5 angles)": {45.0: ASTM_E2194_ALL_ASPECULAR_DEG},
    "ASTM E2539 (45° illumination)": {45.0: ASTM_E2539_ASPECULAR_DEG},
    "BYK-mac i": {45.0: (-15.0, 15.0, 25.0, 45.0, 75.0, 110.0)},
    "X-Rite 19 geometries (in-plane)": {45.0: (-15.0, 15.0, 25.0, 45.0, 75.0, 110.0),
                                        15.0: (-45.0, -15.0, 15.0, 45.0, 80.0)},
}

#: the out-of-plane geometries of X-Rite's 19-geometry list, ``{illumination_deg: ((γ, φ), ...)}`` in this
#: module's (γ, φ) convention (module docstring). X-Rite writes them 45as25az±90, 45as60az±125.3,
#: 15as38.3az±43 and 15as46.9az±104.5: its azimuth is 180° − φ here (its φ = 0 is the in-plane side of
#: negative γ), the only reading under which each of them views along a direction that the other
#: illuminator's geometries also use (the instrument's detectors are shared by its two illuminators,
#: as its in-plane geometries are; tests/appearance/test_multiangle_sets.py). The sign of φ (±y) is
#: not needed: the geometries come in ± pairs.
XRITE_OUT_OF_PLANE_DEG = {
    45.0: ((25.0, 90.0), (25.0, -90.0), (60.0, 54.7), (60.0, -54.7)),
    15.0: ((38.3, 137.0), (38.3, -137.0), (46.9, 75.5), (46.9, -75.5)),
}
#: where each set of :data:`GEOMETRY_SETS` comes from
GEOMETRY_SOURCES = {
    "ASTM E2194": "ASTM E2194-14 (2017), the three aspecular angles required for metal flake pigmented materials",
    "ASTM E2194 (5 angles)": "ASTM E2194-14 (2017), with the optional 25° and 75° geometries",
    "ASTM E2539 (45° illumination)": "ASTM E2539-14 (2017), the 45° illumination set for interference pigments "
                                     "(§1.2 also asks for more than one illumination angle)",
    "BYK-mac i": "BYK-Gardner's BYK-mac i description (https://www.byk-instruments.com/en-US/color/byk-mac-i): colour "
                 "at 15°, 25°, 45°, 75° and 110° aspecular plus a behind-gloss angle (−15°) for interference pigments, "
                 "45° illumination — as summarised in a third-party note; the vendor page itself was not read here",
    "X-Rite 19 geometries (in-plane)": "the directional multi-angle geometries named in X-Rite's own formulation "
                                       "code (TypeScript importing @xrite/cloud-formulation-domain-model and "
                                       "@xrite/colorimetry-js; a public GitHub file whose repository the search tool "
                                       "did not name): 45as−15/15/25/45/75/110 and 15as−45/−15/15/45/80, with "
                                       "out-of-plane ones (XRITE_OUT_OF_PLANE_DEG); the file names no instrument, "
                                       "and a vendor's code is weaker than its product sheet",
}


def _angle_pairs(aspecular_deg, azimuth_deg):
    """(γ, φ) as two flat float arrays of equal length: ``azimuth_deg`` is one value or one per angle."""
    g = np.atleast_1d(np.asarray(aspecular_deg, float))
    phi = np.atleast_1d(np.asarray(azimuth_deg, float))
    try:
        g, phi = np.broadcast_arrays(g, phi)
    except ValueError:
        raise InvalidInputError(
            f"azimuth_deg (shape {phi.shape}) must be one value or one per aspecular angle (shape {g.shape})"
        ) from None
    return g.ravel().copy(), phi.ravel().copy()


def aspecular_directions(aspecular_deg, illumination_deg: float = 45.0, azimuth_deg=0.0):
    """Incident and viewing unit vectors for aspecular angles γ (deg).

    The plane of incidence is xz; the light comes from +x (``wi`` = (sin θi, 0, cos θi)),
    the specular direction r = (−sin θi, 0, cos θi) is on −x. In the plane (``azimuth_deg``
    = 0, the default) the viewing direction makes θ_v = θi − γ with the normal, on the
    specular side for θ_v > 0. Out of the plane, ``azimuth_deg`` φ (broadcast against γ)
    turns the viewing direction about r: ωo = cos γ r + sin γ (cos φ t + sin φ ŷ) with
    t = (cos θi, 0, sin θi), the in-plane direction of positive γ (module docstring).
    Returns ``(wi (3,), wo (K, 3))``; a geometry below the horizon raises
    :class:`InvalidInputError`.
    """
    g = np.atleast_1d(check_finite(aspecular_deg, "aspecular_deg")).astype(float)
    ti = float(check_finite(illumination_deg, "illumination_deg"))
    if not 0 <= ti < 90:
        raise InvalidInputError(f"illumination_deg must lie in [0, 90), got {ti}")
    g, phi = _angle_pairs(g, check_finite(azimuth_deg, "azimuth_deg"))
    ri, rg, rp = np.radians(ti), np.radians(g), np.radians(phi)
    wi = np.array([np.sin(ri), 0.0, np.cos(ri)])
    r = np.array([-np.sin(ri), 0.0, np.cos(ri)])
    t = np.array([np.cos(ri), 0.0, np.sin(ri)])
    y = np.array([0.0, 1.0, 0.0])
    wo = (np.cos(rg)[:, None] * r
          + np.sin(rg)[:, None] * (np.cos(rp)[:, None] * t + np.sin(rp)[:, None] * y))
    in_plane = np.mod(phi, 180.0) == 0.0
    # in the plane (φ = 0 or 180°), write the direction exactly as θ_v = θi ∓ γ: no rounding off the plane
    tv = np.radians(ti - g * np.where(np.mod(phi, 360.0) == 0.0, 1.0, -1.0))
    wo[in_plane] = np.stack([-np.sin(tv), np.zeros_like(tv), np.cos(tv)], axis=-1)[in_plane]
    below = wo[:, 2] <= 1e-12
    if np.any(below):
        if np.all(phi[below] == 0):
            raise InvalidInputError(
                f"aspecular angle(s) {g[below].tolist()} put the detector below the surface at {ti}° illumination; "
                f"choose γ in ({ti - 90:g}, {ti + 90:g})"
            )
        raise InvalidInputError(
            f"(aspecular, azimuth) geometries {list(zip(g[below].tolist(), phi[below].tolist()))} put the detector "
            f"below the surface at {ti}° illumination (viewing direction z ≤ 0)"
        )
    return wi, wo


def multiangle_reflectance(brdf, wavelength_nm, aspecular_deg=ASTM_E2539_ASPECULAR_DEG,
                           illumination_deg: float = 45.0, azimuth_deg=0.0) -> np.ndarray:
    """Spectral reflectance factors R(γ, λ) = π f(λ, ωi, ωo) (relative to the perfect
    diffuser) at the aspecular angles -> (K, L); ``azimuth_deg`` as in
    :func:`aspecular_directions` (0: in the plane of incidence). The specular Dirac of a
    smooth coat is never seen at these geometries (γ ≠ 0)."""
    w = as_wavelength_nm(wavelength_nm)
    wi, wo = aspecular_directions(aspecular_deg, illumination_deg, azimuth_deg)
    return np.pi * np.asarray(brdf(w, wi, wo), float)


def _spectra_to_lab(w, R, illuminant, observer):
    from nmmm.colour import spectra_to_lab, spectra_to_xyz

    return spectra_to_xyz(w, R, illuminant=illuminant, observer=observer), spectra_to_lab(
        w, R, illuminant=illuminant, observer=observer)


@dataclass(frozen=True)
class MultiAngleColour:
    """CIELAB at several aspecular angles (one row per angle). ``azimuth_deg`` (one per
    row, out of the plane of incidence when ≠ 0, see :func:`aspecular_directions`) is
    ``None`` for an in-plane set."""

    aspecular_deg: np.ndarray
    illumination_deg: float
    wavelength_nm: np.ndarray
    reflectance: np.ndarray  # (K, L) reflectance factors
    xyz: np.ndarray  # (K, 3)
    lab: np.ndarray  # (K, 3)
    illuminant: str
    observer: str
    name: str = ""
    azimuth_deg: np.ndarray | None = None

    @property
    def azimuths(self) -> np.ndarray:
        """Azimuth of each row (deg); zeros for an in-plane set."""
        return np.zeros(len(self.aspecular_deg)) if self.azimuth_deg is None else np.asarray(self.azimuth_deg)

    @property
    def L(self):
        return self.lab[:, 0]

    @property
    def chroma(self):
        return np.hypot(self.lab[:, 1], self.lab[:, 2])

    @property
    def hue_deg(self):
        return np.degrees(np.arctan2(self.lab[:, 2], self.lab[:, 1])) % 360.0

    def lightness_at(self, aspecular_deg: float, azimuth_deg: float = 0.0) -> float:
        """L* at one of the measured aspecular angles (in the plane of incidence unless
        ``azimuth_deg`` says otherwise)."""
        k = np.flatnonzero(np.isclose(self.aspecular_deg, aspecular_deg) & np.isclose(self.azimuths, azimuth_deg))
        if k.size == 0:
            avail = (self.aspecular_deg.tolist() if self.azimuth_deg is None
                     else list(zip(self.aspecular_deg.tolist(), self.azimuths.tolist())))
            raise InvalidInputError(
                f"aspecular angle {aspecular_deg}° at azimuth {azimuth_deg}° was not measured; available: {avail}"
            )
        return float(self.lab[k[0], 0])

    def flop_index(self, method: str = "Alman 1987") -> float:
        return flop_index(self, method=method)

    def table(self) -> list[dict]:
        """Rows (aspecular_deg, L, a, b, C, h_deg) for reports/CSV; an out-of-plane set adds
        azimuth_deg after aspecular_deg."""
        rows = []
        for g, p, (l, a, b), c, h in zip(self.aspecular_deg, self.azimuths, self.lab, self.chroma, self.hue_deg):
            row = dict(aspecular_deg=float(g))
            if self.azimuth_deg is not None:
                row["azimuth_deg"] = float(p)
            rows.append(dict(row, L=float(l), a=float(a), b=float(b), C=float(c), h_deg=float(h)))
        return rows


def multiangle_lab(brdf, wavelength_nm, aspecular_deg=ASTM_E2539_ASPECULAR_DEG, illumination_deg: float = 45.0,
                   illuminant: str = "D65", observer: str = "10", azimuth_deg=None) -> MultiAngleColour:
    """CIELAB of the paint at the aspecular angles (D65 / CIE 1964 10° by default, as
    multi-angle instruments report), from :mod:`nmmm.colour`. ``azimuth_deg`` (one value,
    or one per angle) views out of the plane of incidence (:func:`aspecular_directions`);
    ``None`` (default) is the in-plane set.

    L* above 100 is normal near the specular direction of effect paints (reflectance
    factor > 1)."""
    w = as_wavelength_nm(wavelength_nm)
    g = np.atleast_1d(np.asarray(aspecular_deg, float))
    phi = None
    if azimuth_deg is not None:
        g, phi = _angle_pairs(g, azimuth_deg)
    R = multiangle_reflectance(brdf, w, g, illumination_deg, 0.0 if phi is None else phi)
    xyz, lab = _spectra_to_lab(w, R, illuminant, observer)
    return MultiAngleColour(g, float(illumination_deg), w, R, np.asarray(xyz), np.asarray(lab), illuminant,
                            str(observer), getattr(brdf, "name", ""), phi)


def multiangle_lab_set(brdf, wavelength_nm, geometry: str = "ASTM E2539 (45° illumination)", illuminant: str = "D65",
                       observer: str = "10") -> dict:
    """CIELAB at every geometry of a named set of :data:`GEOMETRY_SETS` ->
    ``{illumination_deg: MultiAngleColour}``."""
    if geometry not in GEOMETRY_SETS:
        raise InvalidInputError(f"unknown geometry set {geometry!r}; choose among {list(GEOMETRY_SETS)}")
    return {ti: multiangle_lab(brdf, wavelength_nm, g, ti, illuminant, observer) for ti, g in GEOMETRY_SETS[geometry].items()}


# -- flop index -------------------------------------------------------------------------


def _lightnesses(values, names):
    out = []
    for v, n in zip(values, names):
        v = np.asarray(check_finite(v, n), float)
        if np.any(v < 0):
            raise InvalidInputError(f"{n} must be >= 0 (CIELAB lightness), got min {float(v.min()):g}")
        out.append(v)
    return out


def flop_index_alman1987(L15, L45, L110):
    """Flop index FI = 2.69 (L*15 − L*110)^1.11 / (L*45)^0.86 (Alman 1987; X-Rite, DuPont).

    A solid colour has L*15 ≈ L*110 and FI ≈ 0; silver metallics reach 15–17. When
    L*110 > L*15 (unusual, e.g. retro-reflecting finishes) the signed power is used, giving
    a negative index.

    >>> round(float(flop_index_alman1987(100.0, 50.0, 20.0)), 2)  # 2.69·80^1.11/50^0.86
    12.05
    """
    L15, L45, L110 = _lightnesses((L15, L45, L110), ("L*15", "L*45", "L*110"))
    if np.any(L45 <= 0):
        raise InvalidInputError("L*45 must be > 0 for the flop index")
    d = L15 - L110
    return 2.69 * np.sign(d) * np.abs(d) ** 1.11 / L45 ** 0.86


def lightness_flop_highlight_shade(L15, L25, L75, L110):
    """Highlight − shade lightness difference ΔL*(h−s) = (L*15 + L*25)/2 − (L*75 + L*110)/2.

    Defined in US Patent 11,472,963 ("Glitter pigment, pigment-containing composition, and
    pigment-containing painted product"), abstract: with the illuminant at 45° incidence,
    angles counted from the regularly reflected direction (0°), positive towards the light
    (this module's aspecular angle), "ΔL*(h−s) value is a difference in L* between a
    highlight and shade ... The highlight is an average of values measured at 15° and 25°,
    and the shade is an average of values measured at 75° and 110°" (abstract as reproduced
    at https://golden.com/wiki/US_Patent_11472963_Glitter_pigment%2C_pigment-containing_composition%2C_and_pigment-containing_painted_product-BY84JRP;
    the patent's full text was not read). The patent uses it (claimed below 30, with
    L*(15) above 100) to bound the angle-dependent change of the reflected light, i.e. the
    lightness flop; it is a plain difference in L* units, not scaled like Alman's index.
    The patent gives no worked example in the text read, so the check is the definition on
    hand-computed values:

    >>> float(lightness_flop_highlight_shade(120.0, 100.0, 40.0, 30.0))  # 110 − 35
    75.0
    """
    L15, L25, L75, L110 = _lightnesses((L15, L25, L75, L110), ("L*15", "L*25", "L*75", "L*110"))
    return (L15 + L25) / 2.0 - (L75 + L110) / 2.0


#: registry of flop formulas: name -> function of the lightnesses at
#: :data:`FLOP_INDEX_ASPECULAR_DEG` [name] (in that order, 45° illumination)
FLOP_INDEX_METHODS = {
    "Alman 1987": flop_index_alman1987,
    "highlight-shade dL* (US 11472963)": lightness_flop_highlight_shade,
}
#: the aspecular angles (deg, 45° illumination) whose L* each method of
#: :data:`FLOP_INDEX_METHODS` takes, in argument order
FLOP_INDEX_ASPECULAR_DEG = {
    "Alman 1987": (15.0, 45.0, 110.0),
    "highlight-shade dL* (US 11472963)": (15.0, 25.0, 75.0, 110.0),
}


def flop_index(colour_or_L, *lightnesses, method: str = "Alman 1987"):
    """Flop index by a formula of :data:`FLOP_INDEX_METHODS` (``method``), from a
    :class:`MultiAngleColour` (which must hold the in-plane angles
    :data:`FLOP_INDEX_ASPECULAR_DEG` [method] at 45° illumination) or from the lightnesses
    at those angles, given in that order (``flop_index(L15, L45, L110)`` for Alman 1987)."""
    if method not in FLOP_INDEX_METHODS:
        raise InvalidInputError(f"unknown flop index method {method!r}; choose among {list(FLOP_INDEX_METHODS)}")
    angles = FLOP_INDEX_ASPECULAR_DEG[method]
    if isinstance(colour_or_L, MultiAngleColour):
        c = colour_or_L
        if lightnesses:
            raise InvalidInputError("give a MultiAngleColour alone, or the lightnesses alone")
        if not np.isclose(c.illumination_deg, 45.0):
            raise InvalidInputError(f"flop formulas are defined at 45° illumination, got {c.illumination_deg}°")
        return float(FLOP_INDEX_METHODS[method](*(c.lightness_at(g) for g in angles)))
    values = (colour_or_L, *lightnesses)
    if len(values) != len(angles):
        names = ", ".join(f"L*{g:g}" for g in angles)
        raise InvalidInputError(f"method {method!r} takes {len(angles)} lightnesses ({names}), got {len(values)}")
    return FLOP_INDEX_METHODS[method](*values)


# -- plots ------------------------------------------------------------------------------


def plot_colour_travel(colours, path=None, title: str = "Colour travel"):
    """Colour travel: a*b* trajectory over the aspecular angles (annotated), L* against
    the aspecular angle and sRGB swatches per angle, for one or several
    :class:`MultiAngleColour`. Saves to ``path`` (PNG) if given; returns the figure."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from nmmm.colour import white_point, xyz_to_srgb

    if isinstance(colours, MultiAngleColour):
        colours = [colours]
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.4), gridspec_kw={"width_ratios": [1.1, 1.1, 0.8]})
    ax_ab, ax_l, ax_sw = axes
    for k, c in enumerate(colours):
        lab = c.lab
        line, = ax_ab.plot(lab[:, 1], lab[:, 2], "o-", label=c.name or f"paint {k}")
        labels = [f"{g:g}°" if c.azimuth_deg is None else f"{g:g}°/az {p:g}°"
                  for g, p in zip(c.aspecular_deg, c.azimuths)]
        for t, a, b in zip(labels, lab[:, 1], lab[:, 2]):
            ax_ab.annotate(t, (a, b), textcoords="offset points", xytext=(4, 4), fontsize=7,
                           color=line.get_color())
        ax_l.plot(c.aspecular_deg, lab[:, 0], "o-", color=line.get_color(), label=c.name or f"paint {k}")
        # swatches: display-referred sRGB, exposure so that the brightest angle fits
        Y = np.clip(c.xyz[:, 1].max() / 100.0, 1e-6, None)
        white = white_point(c.wavelength_nm, c.illuminant, c.observer)
        rgb = np.clip(xyz_to_srgb(c.xyz / max(Y, 1.0), white_xyz=white), 0, 1)
        for j, t in enumerate(labels):
            ax_sw.add_patch(plt.Rectangle((j, -k - 1), 0.95, 0.9, color=rgb[j]))
            if k == 0:
                ax_sw.text(j + 0.47, 0.1, t, ha="center", fontsize=7)
    ax_ab.axhline(0, color="0.8", lw=0.5)
    ax_ab.axvline(0, color="0.8", lw=0.5)
    ax_ab.set_xlabel("a* (1)")
    ax_ab.set_ylabel("b* (1)")
    ax_ab.set_title("a*b* trajectory")
    ax_ab.legend(fontsize=7)
    ax_l.set_xlabel("aspecular angle (°)")
    ax_l.set_ylabel("L* (1)")
    ax_l.set_title("lightness flop")
    ax_sw.set_xlim(0, max(len(c.aspecular_deg) for c in colours))
    ax_sw.set_ylim(-len(colours) - 0.2, 0.6)
    ax_sw.set_axis_off()
    ax_sw.set_title("sRGB swatches")
    fig.suptitle(title)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig
