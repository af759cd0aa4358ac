"""Render the seed's grey metallic plate (15 cm x 10 cm, 332 x 240 flake cells) under D65
and write a spectral EXR (Fichet et al. 2021 layout) and an sRGB PNG.

    python examples/render_plate.py [OUTDIR]
"""

import sys
from pathlib import Path

from nmmm.appearance.render import (
    DirectionalLight,
    PinholeCamera,
    UniformEnvironment,
    render_plate,
    seed_metallic_plate,
)

out = Path(sys.argv[1] if len(sys.argv) > 1 else "render_out")
plate = seed_metallic_plate()
camera = PinholeCamera(position_mm=(0, -180, 420), look_at_mm=(0, 0, 0), fov_deg=24, resolution=(1024, 683))
image = render_plate(plate, camera, DirectionalLight.from_angles(35, 90, "D65"), UniformEnvironment("D65", 0.01))
print(image, image.metadata["n_glints"], "glints")
print(image.write_exr(out / "grey_metallic_plate.exr"))
print(image.write_png(out / "grey_metallic_plate.png", exposure=0.6))
