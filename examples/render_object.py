"""A sphere and a curved panel painted with nmmm's grey metallic paint, rendered spectrally
by Mitsuba 3 (pip install 'nmmm[mitsuba]'; a system libLLVM >= 17, e.g. apt-get install
libllvm19), written as spectral EXR + sRGB PNG.

    python examples/render_object.py [OUTDIR]

Without Mitsuba 3 or a recent enough libLLVM it prints one line saying what to install and
exits with status 1.
"""

import sys
from pathlib import Path

from nmmm.appearance.brdf import grey_metallic_paint
from nmmm.appearance.render import DirectionalLight, UniformEnvironment
from nmmm.appearance.render.mitsuba_paint import MitsubaUnavailableError, require_mitsuba
from nmmm.appearance.render.mitsuba_scene import render_object

try:
    require_mitsuba("llvm_ad_spectral")
except MitsubaUnavailableError as exc:
    sys.exit(f"render_object: {exc}")

out = Path(sys.argv[1] if len(sys.argv) > 1 else "render_out")
paint = grey_metallic_paint()
for shape in ("sphere", "panel"):
    (img,) = render_object(paint, shape, DirectionalLight.from_angles(40, 60, "D65"), UniformEnvironment("D65", 0.05),
                           distance_mm=400, fov_deg=24, resolution=(320, 320), spp=64)
    img.write_exr(out / f"{shape}.exr")
    img.write_png(out / f"{shape}.png", exposure=0.8)
    print(shape, "done")
