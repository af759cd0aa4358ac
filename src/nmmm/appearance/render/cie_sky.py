"""The CIE standard general sky as a spectral environment map (issue 19 item 2).

- :data:`CIE_SKY_TYPES` — the 15 sky types of CIE S 011/E:2003 (ISO 15469:2004), Table 1:
  gradation parameters (a, b) and scattering indicatrix parameters (c, d, e); type 16 is
  the traditional CIE overcast sky (Moon & Spencer 1942), L/Lz = (1 + 2 cos Z) / 3.
- :func:`cie_sky_relative_luminance` — L(Z, γ) / Lz of a point of the sky at zenith angle Z
  and azimuth, the sun at zenith angle Zs: φ(Z) f(χ) / (φ(0) f(Zs)) with the gradation
  φ(Z) = 1 + a exp(b / cos Z) (φ = 1 at the horizon) and the indicatrix
  f(χ) = 1 + c [exp(d χ) − exp(d π/2)] + e cos² χ, χ the angular distance to the sun.
- :func:`cie_sky_environment` — that distribution times a daylight spectrum (D65, or the CIE
  daylight of a stated correlated colour temperature) as a
  :class:`~nmmm.appearance.render.LatLongEnvironment` (z up, the plate frame; φ from +x towards
  +y), scaled so that the sky gives ``illuminance_lux`` on a horizontal plane; below the
  horizon a grey ground of reflectance ``ground_reflectance`` lit by that illuminance and by
  the sun's, if stated (ρ (E + E_sun sin h) / π). The sun's disc itself is not in the map; its
  circumsolar aureole is.
- :func:`cie_sun` — the sun's disc as a :class:`~nmmm.appearance.render.DirectionalLight` (0.53°,
  the same daylight spectrum) giving a stated illuminance normal to its rays.

References
----------
- CIE S 011/E:2003 (ISO 15469:2004), *Spatial distribution of daylight — CIE standard general sky*.
- R. Kittler, S. Darula, R. Perez, "A set of standard skies characterizing daylight conditions
  for computer and energy conscious design", Report ICA 3/95, Bratislava (1998).
- S. Darula, R. Kittler, "CIE general sky standard defining luminance distributions", Proc. eSim 2002,
  Montreal, 11-13 (the same a-e groups and type assignments; checked entry by entry).
- P. Moon, D. E. Spencer, "Illumination from a non-uniform sky", Illum. Eng. 37 (1942) 707.
"""

from __future__ import annotations

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.spectra import check_finite

__all__ = ["CIE_SKY_TYPES", "cie_sky_relative_luminance", "cie_sky_environment", "cie_sun"]

_GRADATION = {"I": (4.0, -0.70), "II": (1.1, -0.8), "III": (0.0, -1.0), "IV": (-1.0, -0.55), "V": (-1.0, -0.32),
              "VI": (-1.0, -0.15)}
_INDICATRIX = {1: (0.0, -1.0, 0.0), 2: (2.0, -1.5, 0.15), 3: (5.0, -2.5, 0.30), 4: (10.0, -3.0, 0.45),
               5: (16.0, -3.0, 0.30), 6: (24.0, -2.8, 0.15)}
_GROUPS = {1: ("I", 1), 2: ("I", 2), 3: ("II", 1), 4: ("II", 2), 5: ("III", 1), 6: ("III", 2), 7: ("III", 3),
           8: ("III", 4), 9: ("IV", 2), 10: ("IV", 3), 11: ("IV", 4), 12: ("V", 4), 13: ("V", 5), 14: ("VI", 5),
           15: ("VI", 6)}

#: sky type -> (a, b, c, d, e) of CIE S 011/E:2003 Table 1 (1: overcast, steep gradation ...
#: 12: CIE standard clear sky, low luminance turbidity; 13: clear, polluted atmosphere;
#: 15: white-blue sky with a wide solar corona)
CIE_SKY_TYPES = {t: _GRADATION[g] + _INDICATRIX[i] for t, (g, i) in _GROUPS.items()}

_KM = 683.002  # lm/W


def _check_type(sky_type):
    if isinstance(sky_type, bool) or sky_type not in (*CIE_SKY_TYPES, 16):
        raise InvalidInputError(f"sky_type must be a CIE standard general sky type 1-15 (CIE S 011, e.g. 12 clear, "
                                f"1 overcast) or 16 (the traditional CIE overcast sky), got {sky_type!r}")
    return int(sky_type)


def cie_sky_relative_luminance(zenith_deg, azimuth_deg, sun_zenith_deg, sun_azimuth_deg, sky_type: int = 12):
    """L / Lz of the CIE standard general sky ``sky_type`` at sky points (``zenith_deg``,
    ``azimuth_deg``; broadcast, Z in [0, 90]) for the sun at (``sun_zenith_deg``, ``sun_azimuth_deg``)."""
    t = _check_type(sky_type)
    Z = np.radians(np.asarray(check_finite(zenith_deg, "zenith_deg"), float))
    if np.any(Z < 0) or np.any(Z > np.pi / 2 + 1e-12):
        raise InvalidInputError("zenith_deg must lie in [0, 90] (the sky above the horizon)")
    if t == 16:
        return (1 + 2 * np.cos(Z)) / 3 + 0 * np.asarray(azimuth_deg, float)
    zs = float(check_finite(sun_zenith_deg, "sun_zenith_deg"))
    if not 0 <= zs <= 90:
        raise InvalidInputError(f"sun_zenith_deg must lie in [0, 90] (the sun above the horizon), got {zs!r}")
    Zs = np.radians(zs)
    a, b, c, d, e = CIE_SKY_TYPES[t]
    with np.errstate(divide="ignore", over="ignore"):
        phi = 1 + a * np.where(np.cos(Z) > 1e-9, np.exp(b / np.maximum(np.cos(Z), 1e-300)), 0.0)
    phi0 = 1 + a * np.exp(b)
    dA = np.radians(np.asarray(azimuth_deg, float) - float(sun_azimuth_deg))
    chi = np.arccos(np.clip(np.cos(Zs) * np.cos(Z) + np.sin(Zs) * np.sin(Z) * np.cos(dA), -1, 1))

    def f(x):
        return 1 + c * (np.exp(d * x) - np.exp(d * np.pi / 2)) + e * np.cos(x) ** 2

    return phi * f(chi) / (phi0 * f(Zs))


def _daylight(w, cct_k):
    from nmmm.appearance.render.lights import spd

    if cct_k is None:
        return spd("D65").on(w)
    import colour

    t = float(check_finite(cct_k, "sky cct_k"))
    if not 4000 <= t <= 25000:
        raise InvalidInputError(f"sky cct_k must lie in 4000-25000 K (the CIE daylight locus), got {t!r}")
    sd = colour.sd_CIE_illuminant_D_series(colour.temperature.CCT_to_xy_CIE_D(t))
    return np.interp(w, sd.wavelengths, sd.values)


def cie_sky_environment(wavelength_nm, sky_type: int = 12, sun_elevation_deg: float = 45.0,
                        sun_azimuth_deg: float = 90.0, cct_k=None, illuminance_lux: float = 10000.0,
                        ground_reflectance: float = 0.2, height: int = 64, width: int = 128,
                        sun_normal_illuminance_lux: float = 0.0):
    """The CIE standard general sky ``sky_type`` as a spectral lat-long map on ``wavelength_nm``
    (see the module docstring); the sun at ``sun_elevation_deg`` above the horizon and azimuth
    ``sun_azimuth_deg`` (from +x towards +y; 90 puts it behind a plate seen from −y).
    ``sun_normal_illuminance_lux``: the sun of :func:`cie_sun` that goes with the sky (0: none); it
    lights the ground too, ρ (E_sky + E_sun sin h) / π (the disc itself is not in the map)."""
    from nmmm.appearance.render.lights import LatLongEnvironment
    from nmmm.appearance.render.plate.environment import _luminance_weight

    w = np.asarray(wavelength_nm, float).ravel()
    el = float(check_finite(sun_elevation_deg, "sun_elevation_deg"))
    if not 0 <= el <= 90:
        raise InvalidInputError(f"sun_elevation_deg must lie in [0, 90], got {el!r}")
    az = float(check_finite(sun_azimuth_deg, "sun_azimuth_deg"))
    E = float(check_finite(illuminance_lux, "sky illuminance_lux"))
    if E <= 0:
        raise InvalidInputError(f"sky illuminance_lux must be > 0, got {E!r}")
    E_sun = float(check_finite(sun_normal_illuminance_lux, "sun_normal_illuminance_lux"))
    if E_sun < 0:
        raise InvalidInputError(f"sun_normal_illuminance_lux must be >= 0 (0: no sun), got {E_sun!r}")
    rho = float(check_finite(ground_reflectance, "ground_reflectance"))
    if not 0 <= rho < 1:
        raise InvalidInputError(f"ground_reflectance must lie in [0, 1), got {rho!r}")
    h, wd = int(height), int(width)
    if h < 4 or h % 2 or wd < 4:
        raise InvalidInputError(f"sky map height must be even and >= 4, width >= 4; got {height!r} x {width!r}")
    th = (np.arange(h) + 0.5) / h * 180.0
    ph = (np.arange(wd) + 0.5) / wd * 360.0
    up = th < 90
    rel = cie_sky_relative_luminance(th[up][:, None], ph[None, :], 90.0 - el, az, sky_type)
    # horizontal illuminance of a unit zenith luminance: sum L cos Z dΩ over the texels
    dOm = (np.cos(np.radians(th[up] - 90 / h)) - np.cos(np.radians(th[up] + 90 / h))) * (2 * np.pi / wd)
    e_unit = float(np.sum(rel * (np.cos(np.radians(th[up])) * dOm)[:, None]))
    Lz = E / e_unit  # cd/m²
    S = _daylight(w, cct_k)
    S = S / (_KM * float(_luminance_weight(w) @ S))  # 1 cd/m² of this spectrum
    lum = np.empty((h, wd))
    lum[up] = Lz * rel
    lum[~up] = rho * (E + E_sun * np.sin(np.radians(el))) / np.pi  # the ground under the sky and the sun
    name = f"CIE sky type {int(sky_type)}, sun {el:g} deg, {'D65' if cct_k is None else f'{float(cct_k):g} K'}, {E:g} lx"
    return LatLongEnvironment(w, lum[..., None] * S[None, None, :], name=name)


#: the sun's mean angular diameter, degrees
SUN_ANGULAR_DIAMETER_DEG = 0.53


def cie_sun(wavelength_nm, sun_elevation_deg: float = 45.0, sun_azimuth_deg: float = 90.0,
            normal_illuminance_lux: float = 70000.0, cct_k=None):
    """The sun of :func:`cie_sky_environment` as a :class:`~nmmm.appearance.render.DirectionalLight`
    of angular diameter 0.53° and spectrum the same daylight, giving ``normal_illuminance_lux``
    on a plane normal to its rays (a clear-sky sun gives about 60 000-100 000 lx)."""
    from nmmm.appearance.render.lights import DirectionalLight, SpectralPowerDistribution
    from nmmm.appearance.render.plate.environment import _luminance_weight

    w = np.asarray(wavelength_nm, float).ravel()
    el = float(check_finite(sun_elevation_deg, "sun_elevation_deg"))
    if not 0 < el <= 90:
        raise InvalidInputError(f"sun_elevation_deg must lie in (0, 90] for a sun that lights the plate, got {el!r}")
    E = float(check_finite(normal_illuminance_lux, "sun normal_illuminance_lux"))
    if E <= 0:
        raise InvalidInputError(f"sun normal_illuminance_lux must be > 0, got {E!r}")
    S = _daylight(w, cct_k)
    S = S / (_KM * float(_luminance_weight(w) @ S))  # 1 lx of this spectrum
    a, z = np.radians(float(check_finite(sun_azimuth_deg, "sun_azimuth_deg"))), np.radians(90.0 - el)
    d = (float(np.sin(z) * np.cos(a)), float(np.sin(z) * np.sin(a)), float(np.cos(z)))
    return DirectionalLight(d, SpectralPowerDistribution(w, S, name="CIE daylight sun"), E, SUN_ANGULAR_DIAMETER_DEG)
