"""Interference (pearlescent) pigments: TiO2-coated mica platelets in a binder.

A mica platelet (a few hundred nm thick) coated on both faces with a thin TiO2 layer
reflects a colour set by the optical thickness of the TiO2 (the seed paper's fourth
example). The platelet lies parallel to the film surface; seen at specular geometry its
reflectance is that of the layer stack

    air | binder (thick, incoherent) | TiO2 | mica | TiO2 | binder (semi-infinite)

The mica is treated as incoherent by default: its thickness varies from platelet to
platelet by much more than a wavelength/(2n), which averages its own fringes out
(Maile, Pfaff & Reynders 2005, §3; Pfaff 2008, ch. 3). The binder under the platelet is
semi-infinite, i.e. the film lies over a black background (how pearl pigments are judged).

Public functions
----------------
- :func:`muscovite` — a Cauchy model of muscovite mica, ``n(589 nm) = 1.58``.
- :func:`platelet_stack` — the :class:`~nmmm.layers.thinfilm.Stack` above.
- :func:`platelet_reflectance` — reflectance spectra against TiO2 thickness and angle.
- :func:`interference_colours` — CIELAB (D65) and sRGB of those spectra.
- :func:`demo` — spectra and sRGB swatches against TiO2 thickness, written to a folder.

References
----------
- F. J. Maile, G. Pfaff, P. Reynders, "Effect pigments — past, present and future",
  Prog. Org. Coat. 54, 150–163 (2005). doi:10.1016/j.porgcoat.2005.07.003
- G. Pfaff, *Special Effect Pigments*, 2nd ed., Vincentz Network (2008), ch. 3.
- W. A. Deer, R. A. Howie, J. Zussman, *An Introduction to the Rock-Forming Minerals*,
  2nd ed., Longman (1992) — muscovite: n_alpha 1.552–1.576, n_beta 1.582–1.615,
  n_gamma 1.587–1.618.
- A. Jolivet et al., "Structural, optical, and electrical properties of TiO2 thin films
  deposited by ALD", Appl. Surf. Sci. 608, 155214 (2023) — anatase n, k
  (refractiveindex.info ``main/TiO2/Jolivet-anatase``).
- H. A. Macleod, *Thin-Film Optical Filters*, 4th ed., CRC Press (2010), §3.2 — quarter-
  wave maxima of a high-index film, ``lambda_max = 4 n d / (2m + 1)``.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.layers.thinfilm import Layer, Stack
from nmmm.spectra import check_positive

__all__ = [
    "DEFAULT_TIO2",
    "muscovite",
    "platelet_stack",
    "platelet_reflectance",
    "interference_colours",
    "demo",
]

#: refractiveindex.info key of the default TiO2 (anatase, as on most pearl pigments)
DEFAULT_TIO2 = "main/TiO2/Jolivet-anatase"

#: default binder index (a clear acrylic / epoxy resin; any Material may be given instead)
DEFAULT_BINDER_N = 1.50


def muscovite():
    """Muscovite mica as a non-absorbing Cauchy material, ``n(589.3 nm) = 1.580``.

    ``n(λ) = A + B/λ²`` (λ in µm) with ``A = 1.5685`` and ``B = 0.0040 µm²``. The value
    1.58 is the index used for mica in the pearl-pigment literature (Maile et al. 2005;
    Pfaff 2008) and lies inside muscovite's n_beta–n_gamma range (1.582–1.618) seen at
    near-normal incidence on the cleavage plane (Deer, Howie & Zussman 1992). The
    dispersion term B is an assumption (that of a crown glass, ~0.004 µm²): no tabulated
    n(λ) of mica is in the database. Birefringence (~0.005 in the plane) is neglected.
    """
    from nmmm.materials import Cauchy

    return Cauchy(
        A=1.5685,
        B=0.0040,
        name="muscovite mica (Cauchy, n_D = 1.58)",
        reference=(
            "n_D = 1.58: Maile, Pfaff, Reynders, Prog. Org. Coat. 54, 150 (2005); Deer, Howie, Zussman "
            "(1992); Cauchy B = 0.004 um^2 assumed (crown-glass-like dispersion)"
        ),
    )


def _tio2(tio2):
    if tio2 is None:
        from nmmm.materials import get

        return get(DEFAULT_TIO2)
    if isinstance(tio2, str):
        from nmmm.materials import get

        return get(tio2)
    return tio2


def platelet_stack(
    tio2_thickness_nm,
    mica_thickness_nm: float = 400.0,
    *,
    tio2: Any = None,
    mica: Any = None,
    binder: Any = DEFAULT_BINDER_N,
    binder_thickness_nm: float | None = 20_000.0,
    mica_coherent: bool = False,
) -> Stack:
    """The layer stack of a TiO2/mica/TiO2 platelet lying flat in a binder film.

    Parameters
    ----------
    tio2_thickness_nm : float or ndarray
        Thickness of each TiO2 coating (nm, > 0); an array gives a thickness series
        (results gain its axes in front of wavelength and angle).
    mica_thickness_nm : float
        Mica substrate thickness (typical 200–500 nm).
    tio2, mica, binder : Material, key or complex
        Defaults: :data:`DEFAULT_TIO2` from the database, :func:`muscovite`, n = 1.50.
    binder_thickness_nm : float or None
        Binder above the platelet, incoherent (a film of tens of µm). ``None`` puts the
        platelet directly in a semi-infinite binder ambient (its reflectance inside the
        film, without the air/binder surface).
    mica_coherent : bool
        Treat the mica as coherent (a single, exactly flat platelet) instead of
        incoherent (default; see the module notes).
    """
    d = check_positive(tio2_thickness_nm, "tio2_thickness_nm")
    check_positive(mica_thickness_nm, "mica_thickness_nm")
    t = _tio2(tio2)
    m = muscovite() if mica is None else mica
    layers = [Layer(t, d), Layer(m, mica_thickness_nm, coherent=mica_coherent), Layer(t, d)]
    if binder_thickness_nm is None:
        return Stack(layers, ambient=binder, substrate=binder)
    return Stack([Layer(binder, binder_thickness_nm, coherent=False)] + layers, ambient=1.0, substrate=binder)


def platelet_reflectance(tio2_thickness_nm, wavelength_nm, angle_deg=0.0, **stack_kwargs):
    """Unpolarized specular reflectance of the platelet film (see :func:`platelet_stack`).

    Returns an array of shape ``tio2_thickness.shape + wavelength.shape + angle.shape``.
    ``angle_deg`` is the angle of incidence in air (or in the binder when
    ``binder_thickness_nm=None``).
    """
    return platelet_stack(tio2_thickness_nm, **stack_kwargs).rt(wavelength_nm, angle_deg).R


def interference_colours(wavelength_nm, reflectance, illuminant: str = "D65"):
    """CIELAB and encoded sRGB of reflectance spectra (last axis = wavelength).

    Uses :mod:`nmmm.colour` (CIE 1931 2° observer, explicit illuminant).
    Returns ``(lab, srgb)`` with shapes ``reflectance.shape[:-1] + (3,)``.
    """
    from nmmm.colour import spectra_to_lab, spectra_to_srgb

    lab = spectra_to_lab(wavelength_nm, reflectance, illuminant=illuminant)
    srgb = spectra_to_srgb(wavelength_nm, reflectance, illuminant=illuminant)
    return lab, srgb


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


def _check_thickness_series(d):  # pragma: no cover - kept for API symmetry
    d = check_positive(d, "tio2_thickness_nm")
    if d.ndim > 1:
        raise InvalidInputError("give a 1-D series of TiO2 thicknesses")
    return d
