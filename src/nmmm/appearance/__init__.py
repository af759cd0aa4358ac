"""nmmm.appearance — macro scale: BRDFs of paints, multi-angle colour, rendering.

Colorimetry (spectra → XYZ → CIELAB, ΔE2000, sRGB) lives on the ground floor in
:mod:`nmmm.colour`; its names are re-exported here (``from nmmm.appearance import spectra_to_lab``
keeps working).

- :mod:`~nmmm.appearance.brdf` — spectral BRDFs of clear, opaque, metallic and
  interference paints (:class:`PaintBRDF`), BRDF tables for renderers.
- :mod:`~nmmm.appearance.flakes` — flake tilt distributions, flake optics, discrete flake lists.
- :mod:`~nmmm.appearance.multiangle` — CIELAB at the ASTM E2194 / E2539 geometries, flop index.
- :mod:`~nmmm.appearance.sparkle` — sparkle and graininess of images (renders or photographs).
- :mod:`~nmmm.appearance.effect_coat` — an effect coat from its composition (:class:`EffectCoat`:
  flakes, pigments, binder, coat thicknesses -> derived flake layer -> BRDF and flake list).
- :mod:`~nmmm.appearance.deposit` — effect paints from a simulated flake deposit
  (:func:`grey_metallic_from_deposit`: the same flakes as a list and as the statistical BRDF).
- :mod:`~nmmm.appearance.render` — spectral plate renderer, stereo pairs, OpenEXR, Mitsuba.

The BRDF, flake, multi-angle and sparkle names are imported on first use (PEP 562), so that
``import nmmm.appearance`` for colour stays light.
"""

import importlib

from nmmm.colour import (
    delta_e2000,
    spectra_to_lab,
    spectra_to_srgb,
    spectra_to_xyz,
    weighting_factors,
    white_point,
    xyz_to_lab,
    xyz_to_srgb,
)

_LAZY = {
    "PaintBRDF": "brdf", "ClearCoat": "brdf", "clear_dielectric": "brdf", "opaque_paint": "brdf",
    "opaque_paint_from_film": "brdf", "metallic_paint": "brdf", "interference_paint": "brdf",
    "grey_metallic_paint": "brdf", "brdf_table": "brdf", "write_brdf_table": "brdf",
    "FlakeLayer": "flakes", "FlakeList": "flakes", "TiltDistribution": "flakes", "gaussian_tilt": "flakes",
    "aluminium_flakes": "flakes", "mica_pigment": "flakes",
    "multiangle_lab": "multiangle", "flop_index": "multiangle", "FLOP_INDEX_METHODS": "multiangle",
    "aspecular_directions": "multiangle", "plot_colour_travel": "multiangle",
    "ASTM_E2194_ASPECULAR_DEG": "multiangle", "ASTM_E2539_ASPECULAR_DEG": "multiangle",
    "FLOP_INDEX_ASPECULAR_DEG": "multiangle", "GEOMETRY_SETS": "multiangle", "multiangle_lab_set": "multiangle",
    "XRITE_OUT_OF_PLANE_DEG": "multiangle",
    "sparkle_graininess": "sparkle", "grey_metallic_from_deposit": "deposit", "grey_metallic_coat": "deposit",
    "EffectCoat": "effect_coat", "FlakeSpec": "effect_coat",
}


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(f"nmmm.appearance.{_LAZY[name]}"), name)
    raise AttributeError(f"module 'nmmm.appearance' has no attribute {name!r}")


__all__ = [
    "delta_e2000",
    "spectra_to_lab",
    "spectra_to_srgb",
    "spectra_to_xyz",
    "weighting_factors",
    "white_point",
    "xyz_to_lab",
    "xyz_to_srgb",
    *_LAZY,
]
