"""Instrument geometries: how a spectrophotometer's reading follows from the fluxes of a film.

- :data:`GEOMETRIES` — registry name -> description and source.
- :func:`check_geometry` — the name, validated (an unknown one names the known ones).
- :func:`geometry_reflectance` — the reading from adding–doubling fluxes or from a
  Kubelka–Munk body reflectance.

Geometries (CIE 15:2018 §4.2, ISO 13655, ASTM E1164):

``di:8``  diffuse illumination, 8° viewing, specular component included (SCI). By Helmholtz
    reciprocity equal to 8°:di, the directional–hemispherical reflectance; computed at normal
    incidence (the Fresnel reflectance of n = 1.5 is 0.0400 at 0° and 0.0401 at 8°). AD: the
    total collimated reflectance. KM: Saunderson (1942) with k1 = Fresnel at normal
    incidence, k2 the internal diffuse reflectance.
``de:8``  the same, specular component excluded (SCE, the gloss trap removes the mirror
    reflection k1). AD: total − the top surface's Fresnel reflectance. KM: Saunderson without k1.
``0:d``   normal illumination, hemispherical collection with the specular component (the
    geometry of :mod:`nmmm.layers.paint`): the same fluxes as di:8.
``0:45a`` normal illumination, annular (azimuth-averaged) collection at 45°: the reflectance
    factor π L(45°)/E, no specular. AD: the outgoing flux per node divided by that of a perfect
    diffuser, interpolated to sin²45° (the solver is azimuth-averaged, i.e. annular).
    KM: R_f = (1 − k1)(1 − R_F(45°)) R_b / (n² (1 − k2 R_b)) — the diffuse internal flux leaves
    as a Lambertian radiance refracted by Fresnel at 45° (Saunderson 1942; Völz 2001 §3.4).
``45a:0`` annular illumination at 45°, normal viewing: equal to 0:45a by Helmholtz
    reciprocity of the reflectance factor (CIE 15:2018 §4.2.2 Note).

References
----------
- CIE 15:2018 *Colorimetry*, 4th ed., §4.2 (geometries). doi:10.25039/TR.015.2018
- ASTM E1164-12, Standard practice for obtaining spectrometric data for object-color evaluation.
- J. L. Saunderson, J. Opt. Soc. Am. 32, 727 (1942).
- H. G. Völz, *Industrial Color Testing*, 2nd ed., Wiley-VCH (2001).
"""

from __future__ import annotations

import difflib

import numpy as np

from nmmm.errors import InvalidInputError

__all__ = ["GEOMETRIES", "check_geometry", "geometry_reflectance"]

#: instrument geometries: name -> (description, source)
GEOMETRIES = {
    "di:8": ("diffuse:8°, specular included (SCI)", "CIE 15:2018 §4.2.1"),
    "de:8": ("diffuse:8°, specular excluded (SCE)", "CIE 15:2018 §4.2.1"),
    "0:d": ("0°:diffuse, specular included", "CIE 15:2018 §4.2.1"),
    "45a:0": ("45° annular:0°", "CIE 15:2018 §4.2.2"),
    "0:45a": ("0°:45° annular", "CIE 15:2018 §4.2.2"),
}


def check_geometry(name: str) -> str:
    if name not in GEOMETRIES:
        close = difflib.get_close_matches(str(name), list(GEOMETRIES), n=1)
        raise InvalidInputError(f"unknown geometry {name!r}; choose from {list(GEOMETRIES)}"
                                + (f" (did you mean {close[0]!r}?)" if close else ""))
    return name


def geometry_reflectance(geometry: str, solver: str, ad=None, body=None, n_top=None):
    """The reading in ``geometry`` from AD fluxes (``ad``: a StackADResult) or from a KM
    body reflectance ``body`` under a surface of index ``n_top``."""
    from nmmm.layers.fresnel_equations import fresnel
    from nmmm.layers.kubelka_munk import saunderson_k1, saunderson_k2

    check_geometry(geometry)
    if solver == "ad":
        if geometry in ("di:8", "0:d"):
            return ad.reflectance
        if geometry == "de:8":
            return ad.reflectance - ad.specular_reflectance
        return ad.reflectance_factor_45
    k1 = saunderson_k1(n_top)
    k2 = saunderson_k2(n_top)
    Rb = np.asarray(body, float)
    core = Rb / (1 - k2 * Rb)
    if geometry in ("di:8", "0:d"):
        return k1 + (1 - k1) * (1 - k2) * core
    if geometry == "de:8":
        return (1 - k1) * (1 - k2) * core
    r45 = fresnel(np.asarray(n_top), 1.0, np.degrees(np.arcsin(np.sin(np.radians(45.0)) / np.asarray(n_top)))).R
    return (1 - k1) * (1 - r45) * core / np.asarray(n_top) ** 2
