"""Paint systems (issue 16): 4 components x 3 coats x 81 wavelengths, adding-doubling at its
automatic (1e-4) quadrature and the KM path, warm, against iadpython per slab (same thread count:
run with OMP_NUM_THREADS / OPENBLAS_NUM_THREADS set alike). Prints absolute ms and ratios."""

import time

import numpy as np

from nmmm.layers.coat_stack import Coat, CoatStack, Substrate, coat_optics, stack_reflectance
from nmmm.layers.distributions import monodisperse
from nmmm.layers.pigment_mixture import Component


def _best(f, n=5):
    f()
    t = []
    for _ in range(n):
        t0 = time.perf_counter()
        f()
        t.append(time.perf_counter() - t0)
    return min(t) * 1e3


def main():
    w = np.linspace(380.0, 780.0, 81)
    comps = [Component(3.0 + 0.3j, monodisperse(180.0), 0.04), Component(2.7 + 0j, monodisperse(230.0), 0.10),
             Component(1.6 + 0j, monodisperse(800.0), 0.05), Component(1.8 + 0.6j, monodisperse(50.0), 0.005)]
    st = CoatStack([Coat("top", 3e4, 1.52, comps), Coat("mid", 1.5e4, 1.50, comps), Coat("primer", 2.5e4, 1.55, comps)],
                   Substrate.white(0.5))
    opts = tuple(coat_optics(c, w) for c in st.coats)
    ad = _best(lambda: stack_reflectance(st, w, "ad", optics=opts))
    km = _best(lambda: stack_reflectance(st, w, "km", optics=opts))
    print(f"AD stack 4 comps x 3 coats x 81 wl: {ad:.1f} ms (target <= 50); KM: {km:.2f} ms (target <= 5)")
    try:
        import iadpython as iad
    except ImportError:
        print("iadpython not installed: no per-slab reference")
        return
    o = opts[0]
    a, tau, g = o.albedo, (o.mu_a_per_nm + o.mu_s_per_nm) * 3e4, o.g
    t = _best(lambda: iad.Sample(a=a, b=tau, g=g, n=1.52, n_above=1.52, n_below=1.52, quad_pts=16).rt(), n=2)
    print(f"iadpython one slab x 81 wl (16 points, not converged): {t:.1f} ms; AD stack / (3 iadpython slabs) = "
          f"{ad / (3 * t):.2f}; KM / (3 iadpython slabs) = {km / (3 * t):.4f}")


if __name__ == "__main__":
    main()
