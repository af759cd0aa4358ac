"""Left/right eye images of the grey metallic plate at reading distance (400 mm): different
flakes sparkle for each eye. Writes EXR + PNG per eye and a side-by-side PNG.

    python examples/render_stereo.py [OUTDIR]
"""

import sys
from pathlib import Path

import numpy as np
from PIL import Image

from nmmm.appearance.render import DirectionalLight, UniformEnvironment, render_stereo_plate, seed_metallic_plate

out = Path(sys.argv[1] if len(sys.argv) > 1 else "render_out")
plate = seed_metallic_plate()
left, right = render_stereo_plate(plate, position_mm=(0, -140, 375), interocular_mm=65, fov_deg=8,
                                  resolution=(640, 427), lights=DirectionalLight.from_angles(35, 90, "D65"),
                                  environment=UniformEnvironment("D65", 0.01), glint_spread_deg=0.7)
for eye, img in (("left", left), ("right", right)):
    img.write_exr(out / f"stereo_{eye}.exr")
    img.write_png(out / f"stereo_{eye}.png", exposure=0.6)
pair = np.concatenate([left.to_srgb(0.6), right.to_srgb(0.6)], axis=1)
Image.fromarray(np.round(pair * 255).astype(np.uint8)).save(out / "stereo_side_by_side.png")
print("written to", out)
