"""Benchmark of nmmm.appearance.render.

1. The plate renderer, 1024 x 683 pixels x 81 wavelengths (512 x 341 with --quick), for every
   kind of paint: a solid paint (opaque_paint 0.4), the seed's grey metallic plate with glints
   (15 cm x 10 cm, 332 x 240 cells of ~2100 Al flakes = 168 M flakes) and an interference
   pearl with glints (TiO2 on mica, same cell tiling), each in two scenes: a D65 sun (35 deg)
   with a uniform sky, and the viewing booth (45 deg D65 source sphere + the booth's grey walls
   as a 512 x 256 spectral lat-long map that the coat mirrors and that fills the background).
   Wall time (median of --repeat runs after one warm-up) and the process CPU time (all
   threads) per render; the machine's load average is printed (on a shared machine the wall
   time measures the load as much as the code).
2. The per-pixel path: the full statistical paint BRDF at every pixel (coarse_step=1, no
   glints, sun + sky) as BRDF evaluations per second (pixels x wavelengths / time), against
   the fused BRDF kernel's own rate on the same pixel pairs (the kernel writing into a
   preallocated float32 array): how much of the kernel's speed the renderer keeps (the
   issue's measure, target >= 60 M evaluations/s). No other library renders this plate: the
   rival-based table is benchmarks/run_all.py (its "render" row is this per-pixel case).
3. The Mitsuba 3 nmmm_paint BSDF against Mitsuba's built-in ``plastic`` BSDF (a smooth
   dielectric coat over a diffuse base: the comparable built-in) on the same scene,
   same spectral film and samples (target: <= 1.5x).

Run: python benchmarks/bench_render.py [--quick] [--repeat N]
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np


def timeit(fn, repeat=3):
    """Median wall seconds of ``repeat`` calls after one warm-up (JIT compilation, tables)."""
    return timings(fn, repeat)[0]


def timings(fn, repeat=3):
    """(median wall s, median process CPU s) of ``repeat`` calls after one warm-up."""
    fn()
    ts, cs = [], []
    for _ in range(repeat):
        t, c = time.perf_counter(), time.process_time()
        fn()
        ts.append(time.perf_counter() - t)
        cs.append(time.process_time() - c)
    return float(np.median(ts)), float(np.median(cs))


def plates():
    """{kind: PaintedPlate}: solid, grey metallic with flakes, interference pearl with flakes."""
    from nmmm.appearance.brdf import interference_paint, opaque_paint
    from nmmm.appearance.flakes import FlakeList
    from nmmm.appearance.render import PaintedPlate, seed_metallic_plate

    metallic = seed_metallic_plate()
    pearl = interference_paint()
    cell = 450e3
    n = int(round(pearl.flakes.optical_depth * cell * cell / (np.pi * 15e3 ** 2 / 4 * 1.09)))
    fl = FlakeList.random(pearl.flakes.optics, pearl.flakes.tilt, n, region_nm=(cell, cell), mean_diameter_nm=15e3,
                          diameter_cv=0.3, depth_range_nm=(2e3, 18e3), n_binder=1.5, rng=0)
    return {"solid": PaintedPlate(opaque_paint(0.4), None, metallic.size_mm), "metallic (glints)": metallic,
            "pearl (glints)": PaintedPlate(pearl, fl, metallic.size_mm)}


def camera(res):
    from nmmm.appearance.render import PinholeCamera

    return PinholeCamera((0.0, -180.0, 420.0), (0.0, 0.0, 0.0), fov_deg=24.0, resolution=res)


def scenes(plate, w):
    from nmmm.appearance.render import DirectionalLight, UniformEnvironment, ViewingBooth

    sun = dict(lights=DirectionalLight.from_angles(35.0, 90.0, "D65"), environment=UniformEnvironment("D65", 0.01))
    booth = ViewingBooth(size_mm=(1000.0, 1000.0, 800.0))
    return {"sun + sky": sun, "booth": booth.scene(plate, w)}


def bench_plate(quick: bool, repeat: int = 5):
    from nmmm.appearance.render import render_plate

    res = (512, 341) if quick else (1024, 683)
    w = np.linspace(380.0, 780.0, 81)
    cam = camera(res)
    print(f"plate renderer {res[0]}x{res[1]} px x 81 wavelengths, median of {repeat} (load average "
          f"{' '.join(f'{x:.1f}' for x in os.getloadavg())} on {os.cpu_count()} cores)")
    rows = {}
    for kind, plate in plates().items():
        for sname, kw in scenes(plate, w).items():
            out = {}
            t, c = timings(lambda: out.__setitem__("img", render_plate(plate, cam, wavelength_nm=w, **kw)), repeat)
            rows[(kind, sname)] = (t, c)
            print(f"  {kind:18s} {sname:10s}: {t:6.2f} s wall, {c:6.2f} s CPU, {out['img'].metadata['n_glints']} glints")
    return rows


def per_pixel_pair(res):
    """``(path, kernel, n)`` for the per-pixel measure at resolution ``res``: ``path()`` renders the
    whole image (geometry, metallic BRDF at every pixel, sky, background, white reference) and
    ``kernel()`` runs the fused BRDF kernel alone on the same pixel pairs into a preallocated array;
    ``n`` BRDF evaluations each (shared with ``run_all.py``'s ``render`` row)."""
    from nmmm.appearance.brdf.paint_brdf import _check_components
    from nmmm.appearance.render import DirectionalLight, PaintedPlate, UniformEnvironment, render_plate, seed_metallic_plate
    from nmmm.appearance.render.plate.renderer import _plate_hits

    w = np.linspace(380.0, 780.0, 81)
    cam = camera(res)
    metallic = seed_metallic_plate(cells=(4, 4))  # only its smooth BRDF is used: no glints
    smooth = PaintedPlate(metallic.smooth_brdf, size_mm=(150.0, 100.0))
    light = DirectionalLight.from_angles(35.0, 90.0, "D65")
    sky = UniformEnvironment("D65", 0.01)
    dirs = cam.pixel_directions().reshape(-1, 3)
    hit, _ = _plate_hits(cam, dirs)
    wo = -dirs
    wo[~hit] = (0.0, 0.0, 1.0)
    wo[:, 2] = np.maximum(wo[:, 2], 0.0)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi = np.ascontiguousarray(np.broadcast_to(np.asarray(light.direction), wo.shape))
    tab = smooth.brdf.prepare(w)
    out = np.empty((wo.shape[0], w.size), np.float32)
    comps = _check_components(("specular", "flakes", "base", "multiple"))

    def path():
        return render_plate(smooth, cam, light, sky, wavelength_nm=w, coarse_step=1)

    def kernel():
        tab.evaluate_fast(wi, wo, comps, out)

    return path, kernel, res[0] * res[1] * w.size


def per_pixel(quick: bool, repeat: int = 5):
    """(per-pixel path evaluations/s, kernel evaluations/s) on the same pixel pairs."""
    res = (512, 341) if quick else (1024, 683)
    path, kernel, n = per_pixel_pair(res)
    t_path, _ = timings(path, repeat)
    t_kernel, _ = timings(kernel, repeat)
    print(f"  per-pixel path ({res[0]}x{res[1]} pixels x 81 wavelengths, metallic BRDF at every pixel, no glints): "
          f"{t_path:6.2f} s = {n / t_path / 1e6:6.1f} M evaluations/s")
    print(f"  the fused BRDF kernel alone on the same pairs          : {t_kernel:6.2f} s = {n / t_kernel / 1e6:6.1f} M "
          f"evaluations/s (the path keeps {t_kernel / t_path:.0%} of it)")
    return n / t_path, n / t_kernel


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
    rep = int(sys.argv[sys.argv.index("--repeat") + 1]) if "--repeat" in sys.argv else (3 if quick else 5)
    bench_plate(quick, rep)
    per_pixel(quick, rep)
    bench_mitsuba(quick)
