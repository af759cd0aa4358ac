"""Worked example of FFT homogenization: the seed's hematite coating (demo hook).

- :func:`epoxy_resin` — the binder: SU-8-type epoxy, Cauchy n with a weak red absorption (same
  model and coefficients as :func:`nmmm.demo.hematite.epoxy_binder`).
- :func:`hematite_mean` — α-Fe2O3, the uniaxial mean of Querry's ordinary/extraordinary indices.
- :func:`hematite_coating` — hard-core pseudo-cubes (250 nm diagonal) at 5, 7, 10 % in epoxy,
  homogenized by FFT over the visible, against Maxwell Garnett, Bruggeman and the
  Hashin-Shtrikman region (:mod:`nmmm.ema`).
- :func:`contrast_table` — projections against metal contrast: COCG vs Eyre-Milton.
- :func:`demo` — figures, CSV and summary into ``output_dir`` in well under a minute.

The 250 nm grains are *not* small against λ/n (x = π d n / λ ≈ 2): what is computed is the
quasi-static (electrostatic) effective permittivity of the microstructure — the term that
size-corrected (Mie-based) effective media start from. The demo says so in its text.

References
----------
- Couka, E., Willot, F., Jeulin, D., et al. (2015). J. Nanosci. Nanotechnol. 15(5), 3515.
- Querry, M. R. (1985). Optical constants. Report CRDC-CR-85034 (hematite o/e).
- Maxwell Garnett, J. C. (1904). Phil. Trans. R. Soc. Lond. 203, 385.
- Bruggeman, D. A. G. (1935). Ann. Phys. 416, 636.
"""

from __future__ import annotations

import csv
import time
import warnings
from pathlib import Path

import numpy as np

FRACTIONS = (0.05, 0.07, 0.10)


def epoxy_resin():
    """Epoxy binder: Cauchy A=1.566, B=0.00796 µm², C=0.00014 µm⁴ (MicroChem SU-8 2000 data
    sheet), with k = 1e-7 at 700 nm rising to the red (seed: slightly absorbing in the red)."""
    from nmmm.materials.material import HC_EV_NM
    from nmmm.materials.models import Cauchy

    return Cauchy(A=1.566, B=0.00796, C=0.00014, k_amplitude=1e-7, k_exponent=-2.5,
                  band_edge_ev=HC_EV_NM / 700.0, name="epoxy (SU-8 Cauchy)",
                  reference="MicroChem SU-8 2000 data sheet (2011)")


def hematite_mean():
    """α-Fe2O3: uniaxial mean of Querry (1985) main/Fe2O3/Querry-o and -e."""
    from nmmm.materials import get, uniaxial_mean

    return uniaxial_mean(get("main/Fe2O3/Querry-o"), get("main/Fe2O3/Querry-e"))


def hematite_coating(n: int = 32, wavelength_nm=None, fractions=FRACTIONS, seed: int = 1, voxel_nm: float = 35.0):
    """Homogenize hard-core hematite pseudo-cubes in epoxy at each fraction.

    Returns a dict with wavelengths, the FFT tensors' orientation means, MG, Bruggeman, the HS
    region containment, iteration counts and the microstructures.
    """
    from nmmm.ema import bruggeman, maxwell_garnett
    from nmmm.ema.bounds import bergman_milton_bounds
    from nmmm.homogenize.material import homogenize
    from nmmm.microstructure import hardcore_pseudocubes

    w = np.arange(400.0, 701.0, 50.0) if wavelength_nm is None else np.asarray(wavelength_nm, float)
    host, pig = epoxy_resin(), hematite_mean()
    eh, ep = host.eps(w), pig.eps(w)
    out = {"wavelength_nm": w, "eps_host": eh, "eps_hematite": ep, "cases": []}
    for f in fractions:
        ms = hardcore_pseudocubes((n, n, n), voxel_nm, diagonal_nm=250.0, fraction=f, seed=seed)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            mat = homogenize(ms, {"matrix": host, "hematite": pig}, wavelength_nm=w, progress=False)
        qs = [str(c.message) for c in caught if "size parameter" in str(c.message)]
        p = ms.volume_fraction(1)
        fft = mat.eps(w)
        mg = maxwell_garnett(ep, eh, p)
        br = bruggeman(ep, eh, p)
        inside = np.array([bool(bergman_milton_bounds(ep[i], eh[i], p, kind="hashin_shtrikman").contains(fft[i]))
                           for i in range(w.size)])
        aniso = np.max(np.abs(np.diagonal(mat.tensor_nodes, axis1=1, axis2=2) - fft[:, None]) / np.abs(fft[:, None]))
        out["cases"].append({"fraction": p, "nominal": f, "fft": fft, "mg": mg, "bruggeman": br,
                             "inside_hs": inside, "iterations": np.asarray(mat.result.iterations),
                             "anisotropy": float(aniso), "microstructure": ms, "quasistatic_warning": qs[:1]})
    return out


def contrast_table(n: int = 64, seed: int = 1, metals=(-50 + 20j, -50 + 5j)):
    """Projections to 1e-6 for COCG and Eyre-Milton on a 2-D Boolean model (p = 0.3) of a metal in 2.25."""
    from nmmm.homogenize import fft_permittivity
    from nmmm.homogenize.geometries import boolean_spheres

    lab = boolean_spheres(n, 0.3, n / 16, ndim=2, seed=seed)
    rows = []
    for em in metals:
        row = {"eps_metal": str(em)}
        for s in ("cocg", "eyre_milton"):
            r = fft_permittivity(lab, {0: 2.25, 1: em}, solver=s, fallback=False, maxiter=5000, directions=[0])
            row[s] = int(r.iterations[0])
            row[f"eps_xx_{s}"] = complex(np.round(r.tensor[0, 0], 5))
        root = np.sqrt(em / 2.25 + 0j)
        row["eyre_milton_rate"] = float(abs(1 - root) / abs(1 + root))
        rows.append(row)
    return rows


def demo(output_dir) -> dict:
    """Hematite coating at 5/7/10 %: FFT against Maxwell Garnett, Bruggeman and the HS region.

    Writes ``homogenize_hematite_nk.png``, ``homogenize_hematite_complex_plane.png``,
    ``homogenize_hematite_section.png`` and ``homogenize_hematite.csv`` into ``output_dir``
    and returns ``{"title", "figures", "tables", "text"}``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from nmmm.ema.bounds import bergman_milton_bounds
    from nmmm.materials.material import eps_to_nk

    t0 = time.perf_counter()
    out_dir = Path(output_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    res = hematite_coating()
    w = res["wavelength_nm"]
    colours = {0.05: "tab:orange", 0.07: "tab:red", 0.10: "darkred"}
    figs = []

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    nk_host = eps_to_nk(res["eps_host"])
    for case in res["cases"]:
        c = colours.get(case["nominal"], "k")
        lab = f"{100 * case['fraction']:.1f} %"
        for ax, part in zip(axes, ("real", "imag")):
            for key, style in (("fft", "-o"), ("mg", "--"), ("bruggeman", ":")):
                nk = eps_to_nk(case[key])
                ax.plot(w, getattr(nk, part), style, color=c, ms=3,
                        label=f"{key.upper() if key != 'bruggeman' else 'Bruggeman'} {lab}" if key == "fft" or case["nominal"] == 0.10 else None)
    axes[0].plot(w, nk_host.real, "k-", lw=0.8, label="epoxy")
    axes[0].set(xlabel="wavelength (nm)", ylabel="n (1)", title="effective n: FFT (o), MG (--), Bruggeman (:)")
    axes[1].set(xlabel="wavelength (nm)", ylabel="k (1)", title="effective k")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    p = out_dir / "homogenize_hematite_nk.png"
    fig.savefig(p, dpi=120)
    plt.close(fig)
    figs.append(str(p))

    i550 = int(np.argmin(np.abs(w - 550)))
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    for case in res["cases"]:
        c = colours.get(case["nominal"], "k")
        reg = bergman_milton_bounds(res["eps_hematite"][i550], res["eps_host"][i550], case["fraction"],
                                    kind="hashin_shtrikman")
        b = reg.boundary
        ax.fill(b.real, b.imag, color=c, alpha=0.15)
        ax.plot(b.real, b.imag, color=c, lw=0.8)
        ax.plot(case["fft"][i550].real, case["fft"][i550].imag, "o", color=c, label=f"FFT {100 * case['fraction']:.1f} %")
        ax.plot(case["mg"][i550].real, case["mg"][i550].imag, "s", mfc="none", color=c)
        ax.plot(case["bruggeman"][i550].real, case["bruggeman"][i550].imag, "^", mfc="none", color=c)
    ax.set(xlabel="Re ε (1)", ylabel="Im ε (1)", title=f"ε_eff at {w[i550]:.0f} nm: FFT (●), MG (□), Bruggeman (△)\n"
           "shaded: Hashin-Shtrikman region (Bergman-Milton)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    p = out_dir / "homogenize_hematite_complex_plane.png"
    fig.savefig(p, dpi=120)
    plt.close(fig)
    figs.append(str(p))

    fig, axes = plt.subplots(1, 3, figsize=(9, 3.2))
    for ax, case in zip(axes, res["cases"]):
        lab = case["microstructure"].labels
        ax.imshow(lab[:, :, lab.shape[2] // 2].T, origin="lower", cmap="Reds", vmin=0, vmax=1.5)
        ax.set(title=f"hematite {100 * case['fraction']:.1f} %", xticks=[], yticks=[])
    fig.suptitle("sections of the 32³ cells (voxel 35 nm, pseudo-cubes of 250 nm diagonal)", fontsize=9)
    fig.tight_layout()
    p = out_dir / "homogenize_hematite_section.png"
    fig.savefig(p, dpi=120)
    plt.close(fig)
    figs.append(str(p))

    rows = []
    for case in res["cases"]:
        for i, wl in enumerate(w):
            rows.append({"fraction": round(case["fraction"], 4), "wavelength_nm": wl,
                         "eps_fft": complex(np.round(case["fft"][i], 5)), "eps_mg": complex(np.round(case["mg"][i], 5)),
                         "eps_bruggeman": complex(np.round(case["bruggeman"][i], 5)),
                         "inside_hs": bool(case["inside_hs"][i]),
                         "projections_per_loading": float(np.mean(case["iterations"][i]))})
    p = out_dir / "homogenize_hematite.csv"
    with open(p, "w", newline="") as fh:
        wr = csv.DictWriter(fh, fieldnames=list(rows[0]))
        wr.writeheader()
        wr.writerows(rows)
    contrast = contrast_table()

    n_in = sum(int(c["inside_hs"].sum()) for c in res["cases"])
    n_all = sum(c["inside_hs"].size for c in res["cases"])
    dev_mg = max(float(np.max(np.abs(c["fft"] / c["mg"] - 1))) for c in res["cases"])
    qs = next((c["quasistatic_warning"][0] for c in res["cases"] if c["quasistatic_warning"]), "")
    text = (
        "FFT homogenization (Galerkin/COCG, Willot 2015 rotated Green operator) of hard-core hematite "
        "pseudo-cubes (250 nm diagonal, random orientations) in epoxy at 5, 7 and 10 % on 32³ periodic cells. "
        f"{n_in} of {n_all} FFT values lie inside the Hashin-Shtrikman (Bergman-Milton) region; the largest "
        f"relative deviation from Maxwell Garnett is {100 * dev_mg:.1f} % — at these fractions the "
        "microstructure barely matters for ε_eff, and MG is the HS bound it coincides with. "
        "COCG needs far fewer projections than Eyre-Milton at metal contrast: "
        + "; ".join(f"ε = {r['eps_metal']}: {r['cocg']} vs {r['eyre_milton']}" for r in contrast)
        + ". Validity: " + (qs.split(";")[0] + "." if qs else "quasi-static.")
        + " The result is the quasi-static term that size-corrected (Mie) effective media and the "
        "layers package's scattering model build on; it does not capture the grain-size darkening."
    )
    return {
        "title": "FFT homogenization of the hematite coating (5/7/10 %)",
        "figures": figs,
        "tables": {"hematite": rows, "iterations_vs_contrast": contrast},
        "text": text,
        "runtime_s": round(time.perf_counter() - t0, 1),
    }


__all__ = ["demo", "hematite_coating", "contrast_table", "epoxy_resin", "hematite_mean"]
