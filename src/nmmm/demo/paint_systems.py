"""Worked example: real paint systems (issue 16) — a tint ladder, a white's hiding, a three-coat solid.

- :func:`rutile` — TiO2 with measured n and k over the whole grid (Siefke et al. 2016, an ALD film).
- :func:`demo` — figures, CSV tables and text for ``nmmm demo``, from :mod:`nmmm.layers.coat_stack`,
  :mod:`nmmm.layers.pigment_mixture` and :mod:`nmmm.layers.formulation`.

The three parts, with the choices made (stated so they can be changed):

1. **Tint ladder.** Hematite (Querry's o/e mean, as the hematite paint) spheres of 180 nm
   (log-normal, σg 1.25) let down with rutile spheres of 230 nm (σg 1.3) by volume — masstone
   (hematite alone), 1:1, 1:4, 1:9 — at a total PVC of 10 % in the epoxy of the hematite paint;
   opaque films (infinite thickness), de:8 (specular excluded), CIELAB D65/2°. The tinting
   strength (ISO 787-24 style, K/S at the reference's wavelength of maximum absorption,
   :func:`nmmm.layers.formulation.tinting_strength`) of a coarser hematite (400 nm) against the
   180 nm one, both 1:9 in rutile.
2. **White paint.** The same rutile in a clear binder n = 1.50 (an acrylic), PVC 5–25 %, contrast
   ratio (ISO 6504-3: Y over black / Y over a white of 0.80, D65/2°, de:8) against dry film
   thickness 3–100 µm, the hiding thickness at CR 0.98 and its spreading rate; then the contrast
   ratio of a 2.5 µm film against PVC 5–70 % with and without crowding (multi-component
   Percus–Yevick), CPVC 0.50 (above it air voids scatter: "dry hiding").
3. **Three-coat automotive solid.** Clear coat 40 µm (n 1.52) | red basecoat 15 µm (hematite 180 nm,
   8 %, n 1.50) | grey primer 25 µm (rutile 10 % + a carbon-like black n = 1.8 + 0.6i of 50 nm, 0.5 %,
   n 1.55) on steel (n = 2.5 + 3.3i), as ``three_coat_solid.toml``: adding–doubling through every
   interface (di:8 and de:8) next to Kubelka–Munk + Saunderson (Kubelka 1954 for the layers), and
   the stack without its clear coat. All grains log-normal (σg 1.25 hematite, 1.3 rutile and black).

The grid is 400–700 nm every 10 nm, inside the TiO2 data (no extrapolation). That TiO2 is a
measured film, not bulk rutile (see :func:`rutile`): its n is ≈ 0.2–0.5 lower and its band edge
weaker, so the whites hide a little less and are slightly bluer in the violet than a rutile
pigment's.

References
----------
- T. Siefke et al., Adv. Opt. Mater. 4, 1780 (2016), doi:10.1002/adom.201600250 (TiO2 n, k).
- M. R. Querry, *Optical constants*, US Army CRDC report CRDC-CR-85034 (1985) (hematite).
- ISO 6504-3:2019 (contrast ratio); ISO 787-24:1985 (tinting strength).
- P. Kubelka, "New contributions to the optics of intensely light-scattering materials. Part II:
  Nonhomogeneous layers", J. Opt. Soc. Am. 44, 330 (1954). doi:10.1364/JOSA.44.000330
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

__all__ = ["rutile", "demo"]

#: total pigment volume of the tint ladder and its hematite:rutile ratios (by volume)
TINT_PVC = 0.10
TINT_RATIOS = (("masstone", 1, 0), ("1:1", 1, 1), ("1:4", 1, 4), ("1:9", 1, 9))
WHITE_PVCS = (0.05, 0.10, 0.15, 0.20, 0.25)
WHITE_THICKNESS_UM = tuple(np.round(np.geomspace(3.0, 100.0, 12), 2))
PVC_SERIES = tuple(np.round(np.arange(0.05, 0.701, 0.05), 2))
WHITE_CPVC = 0.50
#: film thickness of the contrast ratio against PVC: thin enough not to be saturated (at 10 µm every
#: PVC above 15 % gives CR > 0.97 and hides the crowding and the jump above the CPVC)
PVC_SERIES_UM = 2.5
#: size nodes of the rutile distribution: 6 leave Mie ripples of 0.02 in a tint's reflectance, 24 do not
RUTILE_NODES = 24


def rutile():
    """TiO2 standing in for rutile: the measured n **and** k of Siefke et al. (2016), database entry
    ``main/TiO2/Siefke`` (an ALD film of 350 nm, Ratzsch et al. 2015; ellipsometry and
    spectrophotometry 0.12–125 µm fitted with Franta's universal dispersion model).

    Why not bulk rutile: the database's rutile crystals (DeVore 1951, Bond 1965) are Sellmeier fits
    of n alone starting at 430–450 nm, so a 400 nm grid would extrapolate them with k = 0 past the
    band edge (≈ 410 nm), where their n rises steeply (a false reflectance peak at 410 nm). No
    rutile set with n and k over 380–780 nm is in the database; of the sets that cover it with a
    measured k (Siefke, Franta; Sarkar's k is 0), Siefke's has the higher n (2.44 at 550 nm against
    2.65 / 2.95 for DeVore's o / e), so hiding here is lower than a rutile pigment's, and its violet
    absorption is far weaker than rutile's (k = 6e-4 at 400 nm, 4e-3 at 380 nm): tints keep some
    violet reflectance (a rose rather than salmon hue).

    Reference: T. Siefke et al., "Materials pushing the application limits of wire grid polarizers
    further into the deep ultraviolet spectral range", Adv. Opt. Mater. 4, 1780–1786 (2016),
    doi:10.1002/adom.201600250."""
    from nmmm.materials import get

    return get("main/TiO2/Siefke")


def _write_csv(path, rows):
    with open(path, "w", newline="") as fh:
        wr = csv.DictWriter(fh, fieldnames=list(rows[0]))
        wr.writeheader()
        wr.writerows(rows)
    return str(path)


def _lab_text(lab):
    return f"L* {lab[0]:.1f}\na* {lab[1]:.1f}\nb* {lab[2]:.1f}"


def _tint(w, hem, tio2, binder):
    from nmmm.layers.coat_stack import Coat, CoatStack, Substrate, stack_reflectance
    from nmmm.layers.distributions import lognormal
    from nmmm.layers.pigment_mixture import Component

    def ladder(d_hem):
        out = {}
        for label, h, r in TINT_RATIOS:
            fh, fr = TINT_PVC * h / (h + r), TINT_PVC * r / (h + r)
            comps = [Component(hem, lognormal(d_hem, 1.25, n_nodes=12), fh, "hematite")]
            if fr:
                comps.append(Component(tio2, lognormal(230.0, 1.3, n_nodes=RUTILE_NODES), fr, "rutile"))
            st = CoatStack([Coat(label, np.inf, binder, comps)], Substrate.black())
            out[label] = stack_reflectance(st, w, "ad", "de:8").reflectance
        return out

    return ladder(180.0), ladder(400.0)


def _white(w, tio2):
    from nmmm.layers.coat_stack import Coat, CoatStack, Substrate, coat_optics, stack_reflectance
    from nmmm.layers.distributions import lognormal
    from nmmm.layers.formulation import BLACK_CHART, WHITE_CHART, contrast_ratio, hiding_thickness_for

    dist = lognormal(230.0, 1.3, n_nodes=RUTILE_NODES)

    def stack(pvc, t_nm, dep=False):
        from nmmm.layers.pigment_mixture import Component

        return CoatStack([Coat("white", t_nm, 1.50, [Component(tio2, dist, pvc, "rutile")], dependent_scattering=dep,
                               cpvc=WHITE_CPVC)])

    def cr(st, opts):
        b = stack_reflectance(st.replace(substrate=Substrate(reflectance=BLACK_CHART)), w, "ad", "de:8", optics=opts)
        wh = stack_reflectance(st.replace(substrate=Substrate(reflectance=WHITE_CHART)), w, "ad", "de:8", optics=opts)
        return contrast_ratio(w, b.reflectance, wh.reflectance)

    curves, hiding = {}, {}
    for pvc in WHITE_PVCS:
        st = stack(pvc, 25e3)
        opts = (coat_optics(st.coats[0], w),)
        curves[pvc] = [cr(stack(pvc, t * 1e3), opts) for t in WHITE_THICKNESS_UM]
        hiding[pvc] = hiding_thickness_for(st, w, 0.98, "ad", "de:8", optics=opts)
    series = {}
    for dep in (False, True):
        series[dep] = [cr(st, (coat_optics(st.coats[0], w),)) for st in (stack(p, PVC_SERIES_UM * 1e3, dep) for p in PVC_SERIES)]
    return curves, hiding, series


def _three_coat(w, hem, tio2):
    from nmmm.layers.coat_stack import Coat, CoatStack, Substrate, coat_optics, stack_reflectance
    from nmmm.layers.distributions import lognormal
    from nmmm.layers.pigment_mixture import Component

    # log-normal grains as in the tint ladder (monodisperse spheres leave Mie ripples in the spectra)
    clear = Coat("clear coat", 40e3, 1.52)
    base = Coat("red basecoat", 15e3, 1.50, [Component(hem, lognormal(180.0, 1.25, n_nodes=12), 0.08, "hematite")])
    primer = Coat("grey primer", 25e3, 1.55,
                  [Component(tio2, lognormal(230.0, 1.3, n_nodes=RUTILE_NODES), 0.10, "rutile"),
                   Component(1.8 + 0.6j, lognormal(50.0, 1.3, n_nodes=6), 0.005, "black")])
    steel = Substrate(compound=2.5 + 3.3j)
    full = CoatStack([clear, base, primer], steel)
    bare = CoatStack([base, primer], steel)
    opts = tuple(coat_optics(c, w) for c in full.coats)
    spectra = {
        ("full stack", "ad", "di:8"): stack_reflectance(full, w, "ad", "di:8", optics=opts).reflectance,
        ("full stack", "ad", "de:8"): stack_reflectance(full, w, "ad", "de:8", optics=opts).reflectance,
        ("full stack", "km", "de:8"): stack_reflectance(full, w, "km", "de:8", optics=opts).reflectance,
        ("no clear coat", "ad", "de:8"): stack_reflectance(bare, w, "ad", "de:8", optics=opts[1:]).reflectance,
        ("primer alone", "ad", "de:8"): stack_reflectance(CoatStack([primer], steel), w, "ad", "de:8",
                                                          optics=opts[2:]).reflectance,
    }
    return spectra


def demo(output_dir) -> dict:
    """Tint ladder, white paint hiding, three-coat solid (module docstring).

    Writes ``tint_ladder.png``, ``white_hiding.png``, ``three_coat.png`` and three CSV tables into
    ``output_dir``; returns ``{"title", "figures", "tables", "text"}``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from nmmm.colour import delta_e2000, spectra_to_lab, spectra_to_srgb
    from nmmm.demo.hematite import epoxy_binder, hematite
    from nmmm.layers.formulation import spreading_rate_m2_per_L, tinting_strength
    from nmmm.recipes.figures import curve_styles, save_figure

    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    w = np.arange(400.0, 701.0, 10.0)
    hem, tio2, epoxy = hematite(), rutile(), epoxy_binder()

    # 1. tint ladder -----------------------------------------------------------------
    fine, coarse = _tint(w, hem, tio2, epoxy)
    labels = [t[0] for t in TINT_RATIOS]
    lab = {k: spectra_to_lab(w, fine[k]) for k in labels}
    rgb = {k: np.clip(spectra_to_srgb(w, fine[k]), 0, 1) for k in labels}
    ts = tinting_strength(w, coarse["1:9"], fine["1:9"], epoxy.nk(w).real)
    fig, (ax, axs) = plt.subplots(1, 2, figsize=(10, 4.2), gridspec_kw={"width_ratios": [1.5, 1]})
    for k, style in zip(labels, curve_styles(len(labels))):
        ax.plot(w, fine[k], lw=2, label=f"{k} (hematite:rutile)", **style)
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("reflectance, de:8 (1)")
    ax.set_title(f"Hematite 180 nm let down with rutile 230 nm, PVC {TINT_PVC:.0%}, opaque")
    ax.legend(fontsize=8)
    axs.imshow(np.stack([rgb[k] for k in labels])[None], aspect="auto", extent=(-0.5, len(labels) - 0.5, 1, 0))
    for i, k in enumerate(labels):
        c = "white" if lab[k][0] < 50 else "black"
        axs.text(i, 0.5, _lab_text(lab[k]), ha="center", va="center", color=c, fontsize=9)
    axs.set_xticks(range(len(labels)), labels)
    axs.set_yticks([])
    axs.set_title("sRGB swatches, CIELAB (D65, 2°)")
    f1 = save_figure(fig, out / "tint_ladder.png")
    tint_rows = [{"letdown (hematite:rutile)": k, "hematite fraction (1)": round(TINT_PVC * h / (h + r), 4),
                  "rutile fraction (1)": round(TINT_PVC * r / (h + r), 4), "L": round(float(lab[k][0]), 2),
                  "a": round(float(lab[k][1]), 2), "b": round(float(lab[k][2]), 2),
                  "L* with 400 nm hematite (1)": round(float(spectra_to_lab(w, coarse[k])[0]), 2)}
                 for k, h, r in TINT_RATIOS]
    t1 = _write_csv(out / "tint_ladder.csv", tint_rows)

    # 2. white paint -----------------------------------------------------------------
    curves, hiding, series = _white(w, tio2)
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 4.4))
    for pvc, style in zip(WHITE_PVCS, curve_styles(len(WHITE_PVCS))):
        ax.plot(WHITE_THICKNESS_UM, curves[pvc], marker="o", ms=3, label=f"PVC {pvc:.0%}", **style)
        if np.isfinite(hiding[pvc]) and hiding[pvc] / 1e3 <= WHITE_THICKNESS_UM[-1]:
            ax.plot([hiding[pvc] / 1e3], [0.98], "kx", ms=7)
    ax.axhline(0.98, color="0.4", lw=0.8, ls=":")
    ax.set_xscale("log")
    ax.set_xlabel("dry film thickness (µm)")
    ax.set_ylabel("contrast ratio Y_black / Y_white (1)")
    ax.set_title("Rutile white, de:8, D65/2°: ×  hiding (CR 0.98)")
    ax.legend(fontsize=8)
    pv = np.asarray(PVC_SERIES) * 100
    ax2.plot(pv, series[False], marker="o", ms=3, label="independent scattering")
    ax2.plot(pv, series[True], marker="s", ms=3, ls="--", label="crowding (Percus-Yevick)")
    ax2.axvline(WHITE_CPVC * 100, color="0.4", lw=0.8, ls=":")
    ax2.text(WHITE_CPVC * 100 + 1, min(series[False]), "CPVC: air voids\nabove it", fontsize=8, va="bottom")
    ax2.set_xlabel("pigment volume concentration (%)")
    ax2.set_ylabel(f"contrast ratio at {PVC_SERIES_UM:g} µm (1)")
    ax2.set_title("Contrast ratio against PVC")
    ax2.legend(fontsize=8, loc="center right")
    f2 = save_figure(fig, out / "white_hiding.png")
    white_rows = [{"PVC (1)": pvc, "contrast ratio at 25 µm (1)": round(float(np.interp(np.log(25.0), np.log(WHITE_THICKNESS_UM),
                                                                                  curves[pvc])), 4),
                   "hiding thickness (µm)": round(hiding[pvc] / 1e3, 2) if np.isfinite(hiding[pvc]) else "not below 10 mm",
                   "spreading rate (m²/L of dry film)": round(spreading_rate_m2_per_L(hiding[pvc]), 2) if np.isfinite(hiding[pvc]) else 0.0}
                  for pvc in WHITE_PVCS]
    t2 = _write_csv(out / "white_hiding.csv", white_rows)

    # 3. three-coat solid ------------------------------------------------------------
    spectra = _three_coat(w, hem, tio2)
    fig, (ax, axs) = plt.subplots(1, 2, figsize=(10.5, 4.2), gridspec_kw={"width_ratios": [1.6, 1]})
    keys = list(spectra)
    names = {k: f"{k[0]}, {'adding-doubling' if k[1] == 'ad' else 'KM + Saunderson'}, {k[2]}" for k in keys}
    for k, style in zip(keys, curve_styles(len(keys))):
        if k[0] == "no clear coat":  # nearly on the full stack's de:8 curve: dashed so both show
            style = dict(style, linestyle="--")
        ax.plot(w, spectra[k], lw=2, label=names[k], **style)
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("reflectance (1)")
    ax.set_title("Clear 40 µm | red base 15 µm | grey primer 25 µm | steel")
    ax.legend(fontsize=7)
    lab3 = {k: spectra_to_lab(w, spectra[k]) for k in keys}
    short = ["full\ndi:8", "full\nde:8", "full KM\nde:8", "no clear\nde:8", "primer\nde:8"]
    axs.imshow(np.clip(spectra_to_srgb(w, np.stack([spectra[k] for k in keys])), 0, 1)[None], aspect="auto",
               extent=(-0.5, len(keys) - 0.5, 1, 0))
    for i, k in enumerate(keys):
        axs.text(i, 0.5, _lab_text(lab3[k]), ha="center", va="center", color="white" if lab3[k][0] < 50 else "black",
                 fontsize=8)
    axs.set_xticks(range(len(keys)), short, fontsize=8)
    axs.set_yticks([])
    axs.set_title("sRGB swatches, CIELAB (D65, 2°)")
    f3 = save_figure(fig, out / "three_coat.png")
    de_km = float(delta_e2000(lab3[("full stack", "km", "de:8")], lab3[("full stack", "ad", "de:8")]))
    coat_rows = [{"case": names[k], "L": round(float(lab3[k][0]), 2), "a": round(float(lab3[k][1]), 2),
                  "b": round(float(lab3[k][2]), 2), "R at 650 nm (1)": round(float(np.interp(650.0, w, spectra[k])), 4)}
                 for k in keys]
    t3 = _write_csv(out / "three_coat.csv", coat_rows)

    hid = {p: hiding[p] / 1e3 for p in WHITE_PVCS}
    text = [
        f"Tint ladder (opaque, de:8): hematite alone L* {lab['masstone'][0]:.1f}, a* {lab['masstone'][1]:.1f}; "
        f"let down 1:9 with rutile L* {lab['1:9'][0]:.1f}, a* {lab['1:9'][1]:.1f}, b* {lab['1:9'][2]:.1f}. "
        f"Tinting strength (ISO 787-24 style, K/S at {ts['wavelength_nm']:.0f} nm) of a 400 nm hematite against "
        f"the 180 nm one, both 1:9: {ts['tinting_strength_percent']:.0f} %.",
        "White paint (rutile in n = 1.50, de:8): hiding thickness at CR 0.98 "
        + ", ".join(f"{hid[p]:.1f} µm at PVC {p:.0%}" for p in WHITE_PVCS if np.isfinite(hid[p]))
        + f"; the contrast ratio of a {PVC_SERIES_UM:g} µm film rises with PVC, and less with crowding (Percus-Yevick); above the CPVC "
        f"({WHITE_CPVC:.0%}) air voids (n = 1) add scattering — the voids model is crude (module docstring of "
        f"nmmm.layers.pigment_mixture).",
        f"Three-coat solid (adding-doubling through every interface): di:8 L* {lab3[keys[0]][0]:.1f}, a* "
        f"{lab3[keys[0]][1]:.1f}, b* {lab3[keys[0]][2]:.1f}; de:8 L* {lab3[keys[1]][0]:.1f}. KM + Saunderson on the same "
        f"coats differs from adding-doubling by ΔE00 {de_km:.1f} (de:8).",
    ]
    return {
        "title": "Real paint systems: tints, whites' hiding, a three-coat solid (nmmm.layers)",
        "figures": [str(f1), str(f2), str(f3)],
        "tables": {"Tint ladder (CIELAB, D65)": tint_rows, "White paint hiding": white_rows,
                   "Three-coat solid (CIELAB, D65)": coat_rows},
        "files": [t1, t2, t3],
        "text": text,
    }
