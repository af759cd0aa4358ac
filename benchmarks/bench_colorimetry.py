"""Colorimetry speed: 10^5 reflectance spectra x 401 wavelengths -> CIELAB under D65.

Measured in one run, medians of repeats after a warm-up call: nmmm ``spectra_to_lab`` against
colour-science's vectorised ``msds_to_XYZ`` (method "Integration") + ``XYZ_to_Lab`` — the
library a user would otherwise pick, at its fastest — and against the floor: the matrix
product with nmmm's own weighting factors plus the CIELAB formula in NumPy. At 1 and 2
threads, with every other kernel: benchmarks/run_all.py.

    python benchmarks/bench_colorimetry.py
"""

from __future__ import annotations

import time

import colour
import numpy as np

from nmmm.colour import spectra_to_lab, weighting_factors


def median_of(fn, repeat=5):
    fn()
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return float(np.median(times))


def main(n=100_000):
    w = np.arange(380, 781, 1.0)
    R = np.random.default_rng(0).random((n, w.size))
    shape = colour.SpectralShape(380, 780, 1)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
    ill = colour.SDS_ILLUMINANTS["D65"].copy().align(shape)
    xy_w = colour.XYZ_to_xy(colour.sd_to_XYZ(colour.sd_ones(shape), cmfs, ill, method="Integration") / 100)

    W = np.ascontiguousarray(weighting_factors(w))
    white = W.sum(0)

    def colour_vectorised():
        xyz = colour.msds_to_XYZ(R, cmfs, ill, method="Integration", shape=shape)
        return colour.XYZ_to_Lab(xyz / 100, xy_w)

    def numpy_floor():
        t = (R @ W) / white
        f = np.where(t > (6 / 29) ** 3, np.cbrt(t), t / (3 * (6 / 29) ** 2) + 4 / 29)
        return np.stack([116 * f[:, 1] - 16, 500 * (f[:, 0] - f[:, 1]), 200 * (f[:, 1] - f[:, 2])], -1)

    t_nmmm = median_of(lambda: spectra_to_lab(w, R))
    t_colour = median_of(colour_vectorised, 3)
    t_floor = median_of(numpy_floor)
    lab = spectra_to_lab(w, R)
    print(f"{n} spectra x {w.size} wavelengths -> CIELAB (D65, CIE 1931 2°), medians")
    print(f"  nmmm.spectra_to_lab               {t_nmmm:8.3f} s")
    print(f"  colour.msds_to_XYZ + XYZ_to_Lab   {t_colour:8.3f} s   ratio {t_colour / t_nmmm:6.2f}   "
          f"max |ΔLab| {np.abs(lab - colour_vectorised()).max():.1e} (E308 weights vs integration)")
    print(f"  floor: R @ W + CIELAB in NumPy    {t_floor:8.3f} s   ratio {t_floor / t_nmmm:6.2f}   "
          f"max |ΔLab| {np.abs(lab - numpy_floor()).max():.1e}")


if __name__ == "__main__":
    main()
