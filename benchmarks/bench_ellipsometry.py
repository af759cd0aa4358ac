"""Ellipsometry: nmmm against pyElli (the library a user would otherwise pick), one run, ratios.

Cases
-----
1. Forward model: Ψ, Δ of an epoxy (Cauchy) film on Si (Green 2008), 701 wavelengths
   (300–1000 nm) × 3 angles. nmmm: one ``psi_delta`` call on the paired points; pyElli: one
   ``Structure.evaluate`` (2×2 solver) per angle, as a user would call it.
2. Fit: thickness, Cauchy A and B from noisy data of case 1. nmmm: ``EllipsometryModel.fit``;
   pyElli: its forward model inside ``scipy.optimize.least_squares`` with the same residuals,
   bounds and tolerances (pyElli's own fitting front end needs lmfit/plotly/ipywidgets, not
   installed; it wraps an equivalent least-squares call).
3. Uniaxial inversion (hematite, c axis in the surface, 2 orientations × 2 angles): nmmm's
   vectorised two-orientation inversion on 101 wavelengths against pyElli's 4×4 solver inside a
   per-wavelength ``least_squares`` loop (timed on every ``--stride``-th wavelength and scaled).

Each timing is the best of ``--repeat`` runs; the accuracy lines compare the two results.

Run:  python benchmarks/bench_ellipsometry.py [--repeat 3] [--stride 10]
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def _best(fn, repeat):
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main(repeat: int = 3, stride: int = 10) -> dict:
    import elli
    from scipy.optimize import least_squares

    from nmmm.ellipsometry.anisotropy import synthetic_uniaxial_data, uniaxial_from_two_orientations
    from nmmm.ellipsometry.data import EllipsometryData
    from nmmm.ellipsometry.forward import psi_delta
    from nmmm.ellipsometry.model import EllipsometryModel
    from nmmm.materials import get

    si = get("main/Si/Green-2008")
    w = np.linspace(300.0, 1000.0, 701)
    angles = [55.0, 65.0, 75.0]
    model = EllipsometryModel.from_dict({
        "substrate": {"material": "main/Si/Green-2008"},
        "layers": [{"name": "epoxy", "model": "cauchy", "thickness_nm": {"value": 800.0, "min": 100, "max": 3000},
                    "A": {"value": 1.54, "min": 1.3, "max": 1.8}, "B": {"value": 0.006, "min": -0.05, "max": 0.1}}]})
    truth = dict(model.values, **{"epoxy.thickness_nm": 850.0, "epoxy.A": 1.553, "epoxy.B": 0.0068})
    W, A = (x.ravel() for x in np.meshgrid(w, angles, indexing="ij"))
    stack = model.build(truth)
    si_tab = elli.IsotropicMaterial(elli.Table(lbda=w, n=si.nk(w)))

    def elli_structure(t, a, b):
        film = elli.IsotropicMaterial(elli.Cauchy(n0=a, n1=b * 1e4))
        return elli.Structure(elli.AIR, [elli.Layer(film, t)], si_tab)

    def elli_forward(t, a, b):
        s = elli_structure(t, a, b)
        res = [s.evaluate(w, ang, solver=elli.Solver2x2) for ang in angles]
        return np.stack([r.psi for r in res], axis=1).ravel(), np.stack([r.delta for r in res], axis=1).ravel()

    psi_delta(stack, W, A)  # warm-up (Numba kernels of Stack.rt)
    t_n, (pn, dn) = _best(lambda: psi_delta(stack, W, A), repeat)
    t_e, (pe, de) = _best(lambda: elli_forward(850.0, 1.553, 0.0068), repeat)
    dd = np.abs((dn - de + 180) % 360 - 180).max()
    print(f"1. forward Psi/Delta, {W.size} points: nmmm {t_n * 1e3:.1f} ms, pyElli {t_e * 1e3:.1f} ms, "
          f"ratio pyElli/nmmm = {t_e / t_n:.1f}; max |dPsi| {np.abs(pn - pe).max():.1e} deg, |dDelta| {dd:.1e} deg")

    data = EllipsometryData.from_model(stack, w, angles, 0.02, 0.06, noise_seed=1)
    t_fn, res_n = _best(lambda: model.fit(data), repeat)

    def elli_fit():
        def resid(x):
            p, d = elli_forward(*x)
            return np.concatenate([(p - data.psi_deg) / 0.02, ((d - data.delta_deg + 180) % 360 - 180) / 0.06])

        x0 = [800.0, 1.54, 0.006]
        return least_squares(resid, x0, bounds=([100, 1.3, -0.05], [3000, 1.8, 0.1]), x_scale=np.abs(x0),
                             ftol=1e-10, xtol=1e-10, gtol=1e-10)

    t_fe, res_e = _best(elli_fit, repeat)
    print(f"2. fit (3 parameters, {len(data)} points): nmmm {t_fn:.3f} s ({res_n.nfev} evaluations), "
          f"pyElli + least_squares {t_fe:.3f} s ({res_e.nfev} evaluations), ratio {t_fe / t_fn:.1f}; "
          f"thickness {res_n['epoxy.thickness_nm']:.4f} vs {res_e.x[0]:.4f} nm "
          f"(σ {res_n.stderr['epoxy.thickness_nm']:.3f} nm)")

    o, e = get("main/Fe2O3/Querry-o"), get("main/Fe2O3/Querry-e")
    wu = np.arange(300.0, 800.0 + 1e-9, 5.0)
    d_par = synthetic_uniaxial_data(o, e, wu, [60.0, 70.0], "parallel", 0.02, 0.05, noise_seed=1)
    d_perp = synthetic_uniaxial_data(o, e, wu, [60.0, 70.0], "perpendicular", 0.02, 0.05, noise_seed=2)
    t_un, res_u = _best(lambda: uniaxial_from_two_orientations(d_par, d_perp), repeat)
    rots = ([[0, 0, 1.0], [0, 1, 0], [-1, 0, 0]], [[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])

    def elli_uniaxial(indices):
        out = []
        for i in indices:
            wl = np.array([wu[i]])
            meas = []
            for dset in (d_par, d_perp):
                sel = np.isclose(dset.wavelength_nm, wu[i])
                meas.append((dset.angle_deg[sel], dset.psi_deg[sel], dset.delta_deg[sel]))

            def resid(x, wl=wl, meas=meas):
                r = []
                for rot, (angs, ps, ds) in zip(rots, meas):
                    mat = elli.UniaxialMaterial(elli.ConstantRefractiveIndex(x[0] + 1j * x[1]),
                                                elli.ConstantRefractiveIndex(x[2] + 1j * x[3]))
                    mat.set_rotation(np.array(rot))
                    s = elli.Structure(elli.AIR, [], mat)
                    for ang, p, d in zip(angs, ps, ds):
                        rr = s.evaluate(wl, ang, solver=elli.Solver4x4)
                        r += [(rr.psi[0] - p) / 0.02, ((rr.delta[0] - d + 180) % 360 - 180) / 0.05]
                return np.array(r)

            x0 = np.r_[res_u.nk_ordinary[i].real, res_u.nk_ordinary[i].imag, res_u.nk_extraordinary[i].real,
                       res_u.nk_extraordinary[i].imag] * 1.03
            out.append(least_squares(resid, x0, bounds=([1e-6, 0, 1e-6, 0], np.inf)).x)
        return np.array(out)

    idx = np.arange(0, wu.size, stride)
    t_ue, xe = _best(lambda: elli_uniaxial(idx), 1)
    t_ue_full = t_ue * wu.size / idx.size
    dev = max(np.abs(xe[:, 0] + 1j * xe[:, 1] - res_u.nk_ordinary[idx]).max(),
              np.abs(xe[:, 2] + 1j * xe[:, 3] - res_u.nk_extraordinary[idx]).max())
    print(f"3. uniaxial inversion, {wu.size} wavelengths x 2 orientations x 2 angles: nmmm {t_un:.3f} s, "
          f"pyElli 4x4 + per-wavelength least_squares {t_ue_full:.2f} s (scaled from {idx.size} wavelengths), "
          f"ratio {t_ue_full / t_un:.0f}; max |d(n+ik)| between them {dev:.1e}")
    return {"forward_ratio": t_e / t_n, "fit_ratio": t_fe / t_fn, "uniaxial_ratio": t_ue_full / t_un}


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--stride", type=int, default=10)
    args = ap.parse_args()
    main(args.repeat, args.stride)
