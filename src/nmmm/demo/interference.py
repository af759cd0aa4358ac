"""Worked example of the seed paper: interference (mica) pigments (seed example 4), as a demo hook.

- :func:`demo` — colour of TiO2-on-mica platelets against TiO2 thickness (spectra, sRGB swatches,
  colour travel with angle, a CSV table), from :mod:`nmmm.layers.interference`.
"""

from __future__ import annotations

import os

import numpy as np

from nmmm.layers.interference import interference_colours, platelet_reflectance

__all__ = ["demo"]


def demo(output_dir) -> dict:
    """Seed example 4: colour of TiO2-on-mica pigments against TiO2 thickness.

    Writes ``interference_spectra.png`` (reflectance spectra and sRGB swatches for TiO2
    thicknesses 20–220 nm, normal incidence), ``interference_angle.png`` (colour travel
    with angle for three pigments) and ``interference_colours.csv`` into ``output_dir``;
    returns ``{"title", "figures", "tables", "text"}``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(output_dir, exist_ok=True)
    wl = np.arange(380.0, 781.0, 5.0)
    d = np.arange(20.0, 221.0, 10.0)
    R = platelet_reflectance(d, wl, 0.0)  # (n_d, n_wl): a scalar angle adds no axis
    lab, srgb = interference_colours(wl, R)
    R_in = platelet_reflectance(d, wl, 0.0, binder_thickness_nm=None)
    lab_in, srgb_in = interference_colours(wl, R_in)

    fig, (ax, axs) = plt.subplots(2, 1, figsize=(8, 7.5), gridspec_kw={"height_ratios": [3, 1.2]})
    for i in range(0, d.size, 2):
        ax.plot(wl, R[i], color=np.clip(srgb_in[i], 0, 1), lw=2, label=f"{d[i]:.0f} nm")
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("specular reflectance (from air)")
    ax.set_title("TiO2 (anatase) / mica 400 nm / TiO2 in binder n=1.50, normal incidence")
    ax.legend(title="TiO2 thickness", ncol=2, fontsize=8)
    swatches = np.stack([srgb, srgb_in])
    axs.imshow(np.clip(swatches, 0, 1), aspect="auto", extent=(d[0] - 5, d[-1] + 5, 2, 0))
    axs.set_yticks([0.5, 1.5], ["from air", "in binder"])
    axs.set_xlabel("TiO2 thickness (nm)")
    axs.set_title("sRGB swatches (D65)")
    fig.tight_layout()
    f1 = os.path.join(output_dir, "interference_spectra.png")
    fig.savefig(f1, dpi=110)
    plt.close(fig)

    angles = np.arange(0.0, 80.0, 5.0)
    picks = np.array([80.0, 120.0, 160.0])
    Ra = platelet_reflectance(picks, wl, angles)  # (3, n_wl, n_ang)
    lab_a, srgb_a = interference_colours(wl, np.moveaxis(Ra, -1, -2))  # (3, n_ang, 3)
    fig, ax = plt.subplots(figsize=(7, 2.8))
    ax.imshow(np.clip(srgb_a, 0, 1), aspect="auto", extent=(angles[0] - 2.5, angles[-1] + 2.5, 3, 0))
    ax.set_yticks([0.5, 1.5, 2.5], [f"{p:.0f} nm" for p in picks])
    ax.set_xlabel("angle of incidence = viewing angle (deg, specular)")
    ax.set_title("colour travel with angle (sRGB, D65)")
    fig.tight_layout()
    f2 = os.path.join(output_dir, "interference_angle.png")
    fig.savefig(f2, dpi=110)
    plt.close(fig)

    rows = ["tio2_nm,L,a,b,L_in_binder,a_in_binder,b_in_binder,R_max,wavelength_of_R_max_nm"]
    for i in range(d.size):
        rows.append(
            f"{d[i]:.0f},{lab[i, 0]:.2f},{lab[i, 1]:.2f},{lab[i, 2]:.2f},"
            f"{lab_in[i, 0]:.2f},{lab_in[i, 1]:.2f},{lab_in[i, 2]:.2f},{R[i].max():.4f},{wl[np.argmax(R[i])]:.0f}"
        )
    f3 = os.path.join(output_dir, "interference_colours.csv")
    with open(f3, "w") as fh:
        fh.write("\n".join(rows) + "\n")
    table = {
        "tio2_nm": d.tolist(),
        "L": lab[:, 0].round(2).tolist(),
        "a": lab[:, 1].round(2).tolist(),
        "b": lab[:, 2].round(2).tolist(),
    }
    hue = np.degrees(np.arctan2(lab_in[:, 2], lab_in[:, 1])) % 360
    text = (
        "TiO2-coated mica platelets (anatase, Jolivet et al.; muscovite n_D = 1.58) lying flat in a binder "
        "(n = 1.50) over a black background, by transfer matrices with the mica and the 20 um binder "
        "incoherent. With growing TiO2 thickness the interference colour runs through the sequence known "
        "for pearl pigments (silver, gold, red, violet, blue, green; Maile et al. 2005): hue angle in the "
        "binder " + ", ".join(f"{d[i]:.0f} nm: {hue[i]:.0f} deg" for i in range(0, d.size, 4)) + ". "
        "Colours shift to shorter wavelengths as the viewing angle grows (second figure)."
    )
    return {
        "title": "Interference (mica) pigments: colour against TiO2 thickness",
        "figures": [f1, f2],
        "tables": {"interference_colours": table, "csv": f3},
        "text": text,
    }
