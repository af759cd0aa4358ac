"""Worked example: the seed's grey metallic plate, mono and stereo, spectral EXR + sRGB PNG.

- :func:`demo` — the demo hook (``nmmm demo``): renders the 15 cm × 10 cm grey
  metallic plate (332 × 240 flake unit cells) under D65 at reading distance, and its
  stereo pair, to PNG and spectral EXR, plus a figure of the glints seen by each eye.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

__all__ = ["demo"]


def demo(output_dir, resolution=(480, 320)) -> dict:
    """Render the grey metallic plate and its stereo pair into ``output_dir``.

    Returns ``{"title", "figures", "tables", "text", "files"}``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from nmmm.appearance.render import (
        DirectionalLight,
        PinholeCamera,
        UniformEnvironment,
        render_plate,
        render_stereo_plate,
        seed_metallic_plate,
    )

    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    plate = seed_metallic_plate()
    light = DirectionalLight.from_angles(35.0, 90.0, "D65", irradiance=1.0)
    env = UniformEnvironment("D65", radiance=0.02 / np.pi)
    cam = PinholeCamera((0.0, -180.0, 420.0), (0.0, 0.0, 0.0), fov_deg=24.0, resolution=resolution)
    mono = render_plate(plate, cam, light, env)
    files = [mono.write_exr(out / "render_plate.exr"), mono.write_png(out / "render_plate.png", exposure=0.6)]
    t_mono = time.perf_counter() - t0
    # stereo at reading distance (400 mm), a 40 mm x 27 mm window of the plate
    left, right = render_stereo_plate(plate, position_mm=(0.0, -140.0, 375.0), interocular_mm=65.0, fov_deg=6.0,
                                      resolution=resolution, lights=light, environment=env, glint_spread_deg=0.7)
    for eye, img in (("left", left), ("right", right)):
        files.append(img.write_exr(out / f"render_stereo_{eye}.exr"))
        files.append(img.write_png(out / f"render_stereo_{eye}.png", exposure=0.6))
    y_l = left.to_xyz()[..., 1]
    y_r = right.to_xyz()[..., 1]

    def glints(y):
        return y > 3 * np.median(y)

    gl, gr = glints(y_l), glints(y_r)
    jacc = float((gl & gr).sum() / max((gl | gr).sum(), 1))
    fig, ax = plt.subplots(1, 3, figsize=(13, 3.4))
    ax[0].imshow(left.to_srgb(0.6))
    ax[0].set_title("left eye")
    ax[1].imshow(right.to_srgb(0.6))
    ax[1].set_title("right eye")
    rgb = np.zeros(gl.shape + (3,))
    rgb[..., 0] = gl
    rgb[..., 1] = gr
    rgb[..., 2] = gl & gr
    ax[2].imshow(rgb)
    ax[2].set_title(f"glints: left (red), right (green), both (white)\nshared fraction {jacc:.2f}")
    for a in ax:
        a.axis("off")
    fig.tight_layout()
    fig_path = out / "render_stereo_glints.png"
    fig.savefig(fig_path, dpi=110)
    plt.close(fig)
    # a painted sphere through Mitsuba 3, when the optional extra is usable
    mitsuba_note = ""
    try:
        from nmmm.appearance.render.mitsuba_scene import render_object

        (sphere,) = render_object(plate.smooth_brdf, "sphere", light, env, distance_mm=400.0, fov_deg=20.0,
                                  resolution=(200, 200), spp=32)
        files.append(sphere.write_exr(out / "render_sphere_mitsuba.exr"))
        sphere_png = sphere.write_png(out / "render_sphere_mitsuba.png", exposure=0.6)
        files.append(sphere_png)
        figures_extra = [str(sphere_png)]
        mitsuba_note = " A sphere with the same (statistical) paint was rendered spectrally by Mitsuba 3 (nmmm_paint)."
    except Exception as exc:  # noqa: BLE001 - optional extra
        figures_extra = []
        mitsuba_note = f" Mitsuba sphere skipped ({type(exc).__name__}: {str(exc)[:120]})."
    elapsed = time.perf_counter() - t0
    text = (
        f"Grey metallic plate {plate.size_mm[0]:.1f} x {plate.size_mm[1]:.1f} mm, {plate.cells[0]} x {plate.cells[1]} "
        f"unit cells of 450 um with {len(plate.flakes)} Al flakes each, D65 light at 35 deg, 81 wavelengths. "
        f"Mono {resolution[0]}x{resolution[1]} render: {mono.metadata['n_glints']} flake glints, {t_mono:.1f} s. "
        f"Stereo pair at 400 mm, interocular 65 mm: only {jacc:.0%} of the glinting pixels are shared by both eyes."
        + mitsuba_note
    )
    return {
        "title": "Spectral rendering of the grey metallic plate (mono and stereo)",
        "figures": [str(out / "render_plate.png"), str(out / "render_stereo_left.png"),
                    str(out / "render_stereo_right.png"), str(fig_path)] + figures_extra,
        "tables": {"render": {"glints_mono": int(mono.metadata["n_glints"]), "glints_left": int(left.metadata["n_glints"]),
                              "glints_right": int(right.metadata["n_glints"]), "shared_glint_fraction": jacc,
                              "seconds": round(elapsed, 2)}},
        "text": text,
        "files": [str(f) for f in files],
    }
