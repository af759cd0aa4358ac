"""Epoxy binder film on silicon: from a (synthetic, noisy) ellipsometric measurement to the
binder's optical constants.

Ψ and Δ at 55°, 65° and 75° (300–1000 nm, σΨ = 0.02°, σΔ = 0.06°) of an 850 nm Cauchy film on
Si are fitted from a start 50 nm and 0.05 in n away; thickness and Cauchy A, B, C come back
within their uncertainties. A point-by-point inversion with the fitted thickness and its
Kramers–Kronig check follow. The same steps from the shell:

    nmmm ellipsometry fit out/ellipsometry_epoxy_on_si.csv --model out/ellipsometry_epoxy_model.toml \
        -o out --save-material epoxy --point-by-point epoxy

Run: python examples/ellipsometry_epoxy_on_silicon.py [output_dir]
"""

import sys

from nmmm.demo.ellipsometry import epoxy_on_silicon

out_dir = sys.argv[1] if len(sys.argv) > 1 else "ellipsometry_out"
res = epoxy_on_silicon(out_dir)
print(res["result"].summary())
print("\nparameter               true        fitted      sigma      (fitted-true)/sigma")
for name, true, fit, sig, z in res["rows"]:
    print(f"{name:<22} {true:<11.6g} {fit:<11.6g} {sig:<10.2g} {z:+.2f}")
print("\n" + str(res["kk"]))
print(f"\nfigures: {res['fit_png']}, {res['nk_png']}\nmaterial file: {res['material_csv']}")
