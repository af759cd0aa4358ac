"""nmmm.appearance.render — spectral images of painted plates and objects.

- :mod:`~nmmm.appearance.render.lights` — spectral light sources (CIE illuminants, CSV files).
- :mod:`~nmmm.appearance.render.camera` — pinhole cameras, stereo pairs.
- :mod:`~nmmm.appearance.render.plate` — NumPy/Numba plate renderer with discrete flakes.
- :mod:`~nmmm.appearance.render.exr` — spectral OpenEXR (Fichet et al. 2021 layout).
- :mod:`~nmmm.appearance.render.mitsuba_paint` — the ``nmmm_paint`` Mitsuba 3 BSDF (optional
  extra ``nmmm[mitsuba]``; the LLVM variant needs a system libLLVM >= 17).
- :mod:`~nmmm.appearance.render.mitsuba_envmap` — ``nmmm_envmap``, a spectral lat-long sky.
- :mod:`~nmmm.appearance.render.mitsuba_scene` — painted sphere / panel / plate scenes, stereo.
- ``nmmm render plate|object`` — :mod:`~nmmm.appearance.render.cli`.

The Mitsuba modules are imported on demand (``from nmmm.appearance.render.mitsuba_scene
import render_object``) so that nmmm works without Mitsuba.
"""

from nmmm.appearance.render.camera import PinholeCamera, stereo_pair
from nmmm.appearance.render.exr import (
    parse_spectral_channel,
    read_spectral_exr,
    spectral_channel_name,
    write_spectral_exr,
)
from nmmm.appearance.render.lights import (
    DirectionalLight,
    LatLongEnvironment,
    PointLight,
    SpectralPowerDistribution,
    UniformEnvironment,
    default_wavelengths,
    read_spd_csv,
    spd,
)
from nmmm.appearance.render.plate import (
    LambertianBRDF,
    PaintedPlate,
    SpectralImage,
    ViewingBooth,
    render_plate,
    deposit_metallic_plate,
    render_stereo_plate,
    seed_metallic_plate,
)

__all__ = [
    "PinholeCamera",
    "stereo_pair",
    "parse_spectral_channel",
    "read_spectral_exr",
    "spectral_channel_name",
    "write_spectral_exr",
    "DirectionalLight",
    "LatLongEnvironment",
    "PointLight",
    "SpectralPowerDistribution",
    "UniformEnvironment",
    "default_wavelengths",
    "read_spd_csv",
    "spd",
    "LambertianBRDF",
    "PaintedPlate",
    "SpectralImage",
    "render_plate",
    "render_stereo_plate",
    "seed_metallic_plate",
    "deposit_metallic_plate",
    "ViewingBooth",
]
