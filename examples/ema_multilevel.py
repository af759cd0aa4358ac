"""Multi-level effective media: particles in binder -> aggregates -> in binder -> a layer.

Each level's result is a Material (``nmmm.ema.mixtures``), used as a compound of the next.

    python examples/ema_multilevel.py
"""

import numpy as np

from nmmm.ema import Inclusion, Shape, mix
from nmmm.materials import get, uniaxial_mean
from nmmm.materials.models import Cauchy

if __name__ == "__main__":
    w = np.arange(400.0, 701.0, 50.0)
    hematite = uniaxial_mean(get("main/Fe2O3/Querry-o"), get("main/Fe2O3/Querry-e"))
    binder = Cauchy(A=1.55, B=0.005, name="epoxy (Cauchy)")
    # level 1: aggregates of hematite pseudo-cubes (40 % by volume) held by binder
    aggregate = mix(binder, [Inclusion(hematite, 0.40, Shape.cube())], name="hematite aggregate")
    # level 2: aggregates dispersed in the binder: the paint layer (7 % hematite overall)
    layer = mix(binder, [Inclusion(aggregate, 0.07 / 0.40)], method="bruggeman", name="paint layer")
    for lam, nk in zip(w, layer.nk(w)):
        print(f"{lam:5.0f} nm  n = {nk.real:.4f}  k = {nk.imag:.4f}")
    print(layer.metadata)
