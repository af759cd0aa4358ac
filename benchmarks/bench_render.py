"""Benchmark of nmmm.appearance.render.

1. The plate renderer on the seed's grey metallic plate (15 cm x 10 cm, 332 x 240 flake
   cells, ~2100 Al flakes per cell = 168 M flakes), 1024 x 683 pixels, 81 wavelengths,
   D65 sun + sky, with glints; and the per-pixel path alone (the full statistical paint
   BRDF at every pixel, coarse_step=1, no glints), reported as BRDF evaluations per second
   (pixels x wavelengths / time). Both are nmmm: no ratio between them is reported (no
   other library renders this plate; the rival-based table is benchmarks/run_all.py).
2. The Mitsuba 3 nmmm_paint BSDF against Mitsuba's built-in ``plastic`` BSDF (a smooth
   dielectric coat over a diffuse base: the comparable built-in) on the same scene,
   same spectral film and samples (target: <= 1.5x).

Run: python benchmarks/bench_render.py [--quick]
"""

from __future__ import annotations

import sys
import time

import numpy as np


def timeit(fn, repeat=3):
    fn()  # warm-up (JIT compilation, tables)
    ts = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t)
    return float(np.median(ts))


def bench_plate(quick: bool):
    from nmmm.appearance.render import (
        DirectionalLight,
        PaintedPlate,
        PinholeCamera,
        UniformEnvironment,
        render_plate,
        seed_metallic_plate,
    )

    res = (512, 341) if quick else (1024, 683)
    plate = seed_metallic_plate()
    cam = PinholeCamera((0.0, -180.0, 420.0), (0.0, 0.0, 0.0), fov_deg=24.0, resolution=res)
    light = DirectionalLight.from_angles(35.0, 90.0, "D65")
    env = UniformEnvironment("D65", 0.01)
    out = {}
    t_glint = timeit(lambda: out.setdefault("img", render_plate(plate, cam, light, env)))
    img = render_plate(plate, cam, light, env)
    smooth = PaintedPlate(plate.smooth_brdf, size_mm=plate.size_mm)
    t_brute = timeit(lambda: render_plate(smooth, cam, light, env, coarse_step=1), repeat=1 if not quick else 2)
    n_flakes = len(plate.flakes) * plate.cells[0] * plate.cells[1]
    print(f"plate {res[0]}x{res[1]} px, 81 wavelengths, {n_flakes / 1e6:.0f} M flakes, "
          f"{img.metadata['n_glints']} glints")
    print(f"  nmmm plate renderer with glints           : {t_glint:7.2f} s")
    print(f"  full paint BRDF at every pixel (no glints): {t_brute:7.2f} s")
    print(f"  per-pixel path: {res[0] * res[1] * 81 / t_brute / 1e6:.1f} M evaluations/s "
          f"({res[0]}x{res[1]} pixels x 81 wavelengths)")


def bench_mitsuba(quick: bool):
    try:
        from nmmm.appearance.render.mitsuba_paint import paint_bsdf, register_nmmm_plugins, require_mitsuba
    except Exception as exc:  # noqa: BLE001
        print(f"Mitsuba benchmark skipped: {exc}")
        return
    try:
        mi = require_mitsuba("llvm_ad_spectral")
    except Exception as exc:  # noqa: BLE001
        print(f"Mitsuba benchmark skipped: {exc}")
        return
    register_nmmm_plugins(mi)
    from nmmm.appearance.brdf import opaque_paint

    res = 128 if quick else 256
    spp = 16 if quick else 64
    paint = opaque_paint(0.5)

    def scene(bsdf):
        return mi.load_dict({
            "type": "scene", "integrator": {"type": "path", "max_depth": 4},
            "sensor": {"type": "perspective", "fov": 30,
                       "to_world": mi.ScalarTransform4f().look_at(origin=[0, -150, 400], target=[0, 0, 0], up=[0, 0, 1]),
                       "film": {"type": "hdrfilm", "width": res, "height": res, "pixel_format": "xyz"},
                       "sampler": {"type": "independent", "sample_count": spp}},
            "sky": {"type": "constant", "radiance": {"type": "d65"}},
            "sun": {"type": "directional", "direction": [0, -0.5, -0.866], "irradiance": {"type": "d65"}},
            "ball": {"type": "sphere", "radius": 60.0, "bsdf": bsdf},
        })

    s_nmmm = scene(paint_bsdf(paint))
    s_plastic = scene({"type": "plastic", "int_ior": 1.5, "diffuse_reflectance": {"type": "spectrum", "value": 0.5}})

    def run(s):
        img = mi.render(s, seed=1)
        np.asarray(img)

    t_n = timeit(lambda: run(s_nmmm))
    t_p = timeit(lambda: run(s_plastic))
    print(f"Mitsuba {mi.__version__} llvm_ad_spectral, sphere {res}x{res}, {spp} spp, path tracer")
    print(f"  nmmm_paint BSDF : {t_n:7.2f} s")
    print(f"  built-in plastic: {t_p:7.2f} s")
    print(f"  ratio nmmm_paint / plastic: {t_n / t_p:5.2f}x (target <= 1.5x)")


if __name__ == "__main__":
    quick = "--quick" in sys.argv
    bench_plate(quick)
    bench_mitsuba(quick)
