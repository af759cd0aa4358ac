"""Colorimetry speed: 10^5 reflectance spectra x 401 wavelengths -> CIELAB under D65.

Ratio against colour-science, the library a user would otherwise pick, measured in one run:
its vectorised ``msds_to_XYZ`` (method "Integration") + ``XYZ_to_Lab``, and, for scale, its
per-spectrum ``sd_to_XYZ`` on a subset (extrapolated linearly to the full count).

    python benchmarks/bench_colorimetry.py
"""

from __future__ import annotations

import time

import colour
import numpy as np

from nmmm.colour import spectra_to_lab


def best_of(fn, repeat=3):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def main(n=100_000):
    w = np.arange(380, 781, 1.0)
    R = np.random.default_rng(0).random((n, w.size))
    shape = colour.SpectralShape(380, 780, 1)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
    ill = colour.SDS_ILLUMINANTS["D65"].copy().align(shape)
    xy_w = colour.XYZ_to_xy(colour.sd_to_XYZ(colour.sd_ones(shape), cmfs, ill, method="Integration") / 100)

    spectra_to_lab(w, R[:10])  # warm the weighting-factor cache
    t_nmmm = best_of(lambda: spectra_to_lab(w, R))

    def colour_vectorised():
        xyz = colour.msds_to_XYZ(R, cmfs, ill, method="Integration", shape=shape)
        return colour.XYZ_to_Lab(xyz / 100, xy_w)

    t_colour = best_of(colour_vectorised, repeat=1)
    m = 200
    sds = [colour.SpectralDistribution(dict(zip(w, r))) for r in R[:m]]
    t = time.perf_counter()
    for sd in sds:
        colour.XYZ_to_Lab(colour.sd_to_XYZ(sd, cmfs, ill, method="Integration") / 100, xy_w)
    t_loop = (time.perf_counter() - t) * n / m

    lab_ref = colour_vectorised()
    lab = spectra_to_lab(w, R)
    print(f"{n} spectra x {w.size} wavelengths -> CIELAB (D65, CIE 1931 2°)")
    print(f"  nmmm.spectra_to_lab               {t_nmmm:8.3f} s")
    print(f"  colour.msds_to_XYZ + XYZ_to_Lab   {t_colour:8.3f} s   ratio {t_colour / t_nmmm:6.1f}x")
    print(f"  colour.sd_to_XYZ per spectrum     {t_loop:8.1f} s   ratio {t_loop / t_nmmm:6.0f}x (extrapolated from {m})")
    print(f"  max |ΔLab| against colour's vectorised path: {np.abs(lab - lab_ref).max():.2e}")


if __name__ == "__main__":
    main()
