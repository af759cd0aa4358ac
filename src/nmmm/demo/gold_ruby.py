"""Worked example of the seed paper: gold-ruby glass (and gold rods), as a demo hook.

- :func:`gold_ruby_glass` — the composite Material (Maxwell Garnett, p = 0.0005 gold spheres
  in silica, eq. 2).
- :func:`gold_ruby_demo` — writes the figures (n, k against silica — the seed's Figure 1;
  transmission of plates; colour swatches under D65 and A; gold rods; causality) and CSV
  tables into a folder, returns ``{"title", "figures", "tables", "text"}``.
- :func:`reads_red_purple`, :func:`thickness_ranges` — the colour criterion and the thickness
  runs where it holds.

Plates: :func:`nmmm.layers.thick_plate.plate_transmittance` (Beer–Lambert absorption
α = 4πk/λ and the Fresnel losses of the two faces, re-exported here).

Materials: silica main/SiO2/Malitson (210–6700 nm) and gold main/Au/Johnson (188–1937 nm)
from the refractiveindex.info database (:func:`nmmm.materials.get`).

References
----------
- I. H. Malitson, "Interspecimen comparison of the refractive index of fused silica",
  J. Opt. Soc. Am. 55, 1205 (1965).
- P. B. Johnson, R. W. Christy, "Optical constants of the noble metals",
  Phys. Rev. B 6, 4370 (1972).
- J. C. Maxwell Garnett, Phil. Trans. R. Soc. Lond. A 203, 385 (1904) — the colours of
  gold-ruby glass were the original motivation of the formula.
- M. Born, E. Wolf, Principles of Optics, §1.5 (Fresnel), §14.1 (absorbing media).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nmmm.ema.mixtures import Inclusion, mix
from nmmm.ema.shapes import Shape
from nmmm.layers.thick_plate import plate_transmittance

GOLD_KEY = "main/Au/Johnson"
SILICA_KEY = "main/SiO2/Malitson"
GOLD_FRACTION = 0.0005

#: CIELAB criterion used to say a colour "reads red-purple": hue angle h_ab within
#: [330°, 30°) (from purplish red to red), chroma C*ab >= 20 and lightness L* >= 20 (darker colours read as very dark red to black).
RED_PURPLE_HUE_DEG = (330.0, 30.0)
RED_PURPLE_MIN_CHROMA = 20.0
RED_PURPLE_MIN_LIGHTNESS = 20.0


def gold_ruby_glass(fraction: float = GOLD_FRACTION, shape: Shape | None = None, radius_nm=None, method="maxwell_garnett"):
    """Silica with gold inclusions (default spheres at p = 0.0005) as a Material."""
    from nmmm.materials import get

    return mix(get(SILICA_KEY), [Inclusion(get(GOLD_KEY), fraction, shape or Shape.sphere(), radius_nm)],
               method=method, name=f"gold-ruby glass (p = {fraction:g}{', ' + shape.name if shape else ''})")


def _colour(w, T, illuminant):
    from nmmm.colour import spectra_to_lab, spectra_to_srgb

    lab = spectra_to_lab(w, T, illuminant=illuminant)
    rgb = spectra_to_srgb(w, T, illuminant=illuminant)
    return lab, rgb


def reads_red_purple(lab) -> np.ndarray:
    """True where CIELAB colours meet the red-purple criterion (see the module constants)."""
    lab = np.asarray(lab, float)
    C = np.hypot(lab[..., 1], lab[..., 2])
    h = np.degrees(np.arctan2(lab[..., 2], lab[..., 1])) % 360
    lo, hi = RED_PURPLE_HUE_DEG
    hue_ok = (h >= lo) | (h < hi)
    return hue_ok & (C >= RED_PURPLE_MIN_CHROMA) & (lab[..., 0] >= RED_PURPLE_MIN_LIGHTNESS)


def thickness_ranges(thickness_mm, ok) -> list[tuple[float, float]]:
    """Contiguous runs of ``thickness_mm`` (sorted) where ``ok`` is True, as (first, last) pairs."""
    runs, start = [], None
    for i, flag in enumerate(ok):
        if flag and start is None:
            start = i
        if start is not None and (not flag or i == len(ok) - 1):
            end = i if flag else i - 1
            runs.append((float(thickness_mm[start]), float(thickness_mm[end])))
            start = None
    return runs


def _range_text(th_mm, ok):
    runs = thickness_ranges(th_mm, ok)
    if not runs:
        return "none of the thicknesses computed"
    return " and ".join(f"{a:.2g}–{b:.2g} mm" for a, b in runs)


def _save_figure(fig, path) -> str:
    """Lay out, write (120 dpi) and close a demo figure; returns its path."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return str(path)


def gold_ruby_demo(output_dir) -> dict:
    """Gold-ruby glass (seed example 1): figures and tables into ``output_dir``.

    Returns ``{"title", "figures": [paths], "tables": {name: path or dict}, "text"}``.
    The gold-rod variants' colours are shown for a 0.1 mm plate (so that they are not black);
    the sphere plate's colours are computed over a range
    of thicknesses (0.001–10 mm) to locate where the glass reads red-purple.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from nmmm.ema.causality import kk_index_change
    from nmmm.materials import get

    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    figures, tables = [], {}
    silica, gold = get(SILICA_KEY), get(GOLD_KEY)
    glass = gold_ruby_glass()

    # -- Figure 1 of the seed: n and k of the composite against silica ----------------------
    w_fig = np.arange(300.0, 1001.0, 1.0)
    nk_g, nk_s = glass.nk(w_fig), silica.nk(w_fig)
    peak_nm = float(w_fig[np.argmax(nk_g.imag)])
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.4, 6.4), sharex=True)
    a1.plot(w_fig, nk_s.real, "k--", label="silica (Malitson)")
    a1.plot(w_fig, nk_g.real, "C3", label="silica + 0.05 % gold spheres (MG)")
    a1.set_ylabel("n (1)")
    a1.legend()
    a2.plot(w_fig, nk_s.imag, "k--", label="silica")
    a2.plot(w_fig, nk_g.imag, "C3", label="composite")
    a2.axvline(peak_nm, color="0.6", lw=0.8)
    a2.set_ylabel("k (1)")
    a2.set_xlabel("wavelength (nm)")
    a2.legend()
    a1.set_title(f"Gold-ruby glass: n and k (plasmon absorption peak {peak_nm:.0f} nm)")
    figures.append(_save_figure(fig, out / "gold_ruby_nk.png"))
    p = out / "gold_ruby_nk.csv"
    np.savetxt(p, np.column_stack([w_fig, nk_s.real, nk_s.imag, nk_g.real, nk_g.imag]), delimiter=",",
               header="wavelength_nm,n_silica,k_silica,n_composite,k_composite", comments="", fmt="%.8g")
    tables["nk"] = str(p)

    # -- transmission of plates, colours under D65 and A ------------------------------------
    w = np.arange(380.0, 781.0, 5.0)
    nk = glass.nk(w)
    th_mm = np.geomspace(0.001, 10.0, 161)
    T = plate_transmittance(nk, w, th_mm[:, None] * 1e6)
    rows = []
    colours = {}
    for ill in ("D65", "A"):
        lab, rgb = _colour(w, T, ill)
        colours[ill] = (lab, rgb)
        for t, l_, r_ in zip(th_mm, lab, rgb):
            rows.append((ill, t, *l_, *r_))
    rp = {ill: reads_red_purple(colours[ill][0]) for ill in colours}
    p = out / "gold_ruby_colour_vs_thickness.csv"
    with open(p, "w") as fh:
        fh.write("illuminant,thickness_mm,L,a,b,sR,sG,sB,reads_red_purple\n")
        for (ill, t, L, a, b, r, g, bb), ok in zip(rows, np.concatenate([rp["D65"], rp["A"]])):
            fh.write(f"{ill},{t:.5g},{L:.3f},{a:.3f},{b:.3f},{r:.4f},{g:.4f},{bb:.4f},{int(ok)}\n")
    tables["colour_vs_thickness"] = str(p)

    show_mm = np.array([0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0])
    T_show = plate_transmittance(nk, w, show_mm[:, None] * 1e6)
    fig, ax = plt.subplots(figsize=(6.4, 4))
    for t, Tt in zip(show_mm, T_show):
        ax.semilogy(w, np.maximum(Tt, 1e-12), label=f"{t:g} mm")
    ax.set_ylim(1e-8, 1.2)
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("transmittance (1)")
    ax.set_title("Gold-ruby glass plates (p = 0.0005): Beer–Lambert + Fresnel")
    ax.legend(fontsize=7, ncol=2)
    figures.append(_save_figure(fig, out / "gold_ruby_transmission.png"))

    lab5 = {ill: _colour(w, plate_transmittance(nk, w, 5e6), ill)[0] for ill in ("D65", "A")}
    lab_show = {ill: _colour(w, T_show, ill) for ill in ("D65", "A")}
    fig, axes = plt.subplots(2, 1, figsize=(8, 3.2))
    for ax, ill in zip(axes, ("D65", "A")):
        lab, rgb = lab_show[ill]
        ax.imshow(rgb[None, :, :], aspect="auto", extent=(0, len(show_mm), 0, 1))
        ax.set_xticks(np.arange(len(show_mm)) + 0.5)
        ax.set_xticklabels([f"{t:g} mm\nL*={L:.0f}" for t, L in zip(show_mm, lab[:, 0])], fontsize=7)
        ax.set_yticks([])
        ax.set_ylabel(f"illuminant {ill}")
    axes[0].set_title("Gold-ruby glass in transmission (sRGB swatches)")
    figures.append(_save_figure(fig, out / "gold_ruby_swatches.png"))

    # -- gold rods (randomly oriented prolate spheroids) -------------------------------------
    ratios = [1.0, 2.0, 3.0, 4.0]
    rod_mm = 0.1
    w_rod = np.arange(380.0, 1501.0, 2.0)
    rod_rows = []
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.6), gridspec_kw={"width_ratios": [2, 1]})
    rgb_rods = []
    for ar in ratios:
        m = gold_ruby_glass(shape=Shape.spheroid(ar))
        k = m.k(w_rod)
        ax1.plot(w_rod, k, label=f"aspect ratio {ar:g}")
        Tm = plate_transmittance(m.nk(w), w, rod_mm * 1e6)
        row = {"aspect_ratio": ar, "peak_long_nm": float(w_rod[np.argmax(k)])}
        for ill in ("D65", "A"):
            lab, rgb = _colour(w, Tm, ill)
            row[f"Lab_{ill}"] = [round(float(x), 2) for x in lab]
            row[f"sRGB_{ill}"] = [round(float(x), 3) for x in rgb]
            if ill == "D65":
                rgb_rods.append(rgb)
        rod_rows.append(row)
    ax1.set_xlabel("wavelength (nm)")
    ax1.set_ylabel("k of the composite (1)")
    ax1.set_title("Gold rods in silica, p = 0.0005, random orientation")
    ax1.legend(fontsize=8)
    ax2.imshow(np.array(rgb_rods)[:, None, :], aspect="auto", extent=(0, 1, len(ratios), 0))
    ax2.set_yticks(np.arange(len(ratios)) + 0.5)
    ax2.set_yticklabels([f"AR {ar:g}" for ar in ratios])
    ax2.set_xticks([])
    ax2.set_title(f"{rod_mm:g} mm plate, D65")
    figures.append(_save_figure(fig, out / "gold_rods.png"))
    tables["gold_rods"] = rod_rows

    # -- causality: n changes with k -----------------------------------------------------------
    kk = kk_index_change(glass, silica)
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    ax.plot(kk.wavelength_nm, kk.delta_n, "C3", label="Δn = n(composite) − n(silica)")
    ax.plot(kk.wavelength_nm, kk.delta_n_kk, "k:", label="Kramers–Kronig transform of Δk")
    ax.plot(kk.wavelength_nm, kk.delta_k, "C0", alpha=0.6, label="Δk")
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("change of n or k from silica (1)")
    ax.legend(fontsize=8)
    ax.set_title(f"Causality: Δn follows from Δk (max error {100 * kk.relative_error:.1f} % of the swing)")
    figures.append(_save_figure(fig, out / "gold_ruby_kramers_kronig.png"))

    # -- bounds in the complex plane (Bergman–Milton) at the plasmon wavelength -----------------
    from nmmm.ema.bounds import bergman_milton_bounds
    from nmmm.ema.bruggeman_rule import bruggeman
    from nmmm.ema.maxwell_garnett_rule import maxwell_garnett

    ea, es = gold.eps(peak_nm), silica.eps(peak_nm)
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    for i, f in enumerate((0.1, 0.3, 0.5)):
        wi = bergman_milton_bounds(ea, es, f, kind="wiener")
        hs = bergman_milton_bounds(ea, es, f)
        ax.fill(wi.boundary.real, wi.boundary.imag, color=f"C{i}", alpha=0.12)
        ax.fill(hs.boundary.real, hs.boundary.imag, color=f"C{i}", alpha=0.35, label=f"p = {f:g}")
        mg, br = maxwell_garnett(ea, es, f), bruggeman(ea, es, f)
        ax.plot(mg.real, mg.imag, "o", color=f"C{i}", mfc="white")
        ax.plot(br.real, br.imag, "s", color=f"C{i}")
    ax.plot([], [], "ko", mfc="white", label="Maxwell Garnett (gold in silica)")
    ax.plot([], [], "ks", label="Bruggeman")
    ax.set_xlabel("Re ε (1)")
    ax.set_ylabel("Im ε (1)")
    ax.set_title(f"Gold + silica at {peak_nm:.0f} nm: Wiener (light) and HS (dark) regions")
    ax.legend(fontsize=8)
    figures.append(_save_figure(fig, out / "gold_silica_bounds.png"))

    # -- size correction (Doyle) ---------------------------------------------------------------
    size_rows = []
    w_s = np.arange(400.0, 701.0, 1.0)
    for r in (2.5, 10.0, 25.0, 40.0):
        import warnings

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            m = gold_ruby_glass(radius_nm=r, method="maxwell_garnett_mie")
            k = m.k(w_s)
        from nmmm.ema.size import neglected_multipole_fraction

        share = neglected_multipole_fraction(gold.eps(w_s), silica.eps(w_s), r, w_s)
        size_rows.append({"radius_nm": r, "peak_nm": float(w_s[np.argmax(k)]), "k_peak": float(k.max()),
                          "neglected_multipoles_max": float(share.max())})
    tables["size_correction"] = size_rows

    d65_1mm = _colour(w, plate_transmittance(nk, w, 1e6), "D65")[0]
    text = (
        f"Silica ({SILICA_KEY}) with {GOLD_FRACTION:g} (0.05 %) gold spheres ({GOLD_KEY}), Maxwell Garnett eq. (2). "
        f"The composite's k has the plasmon band at {peak_nm:.0f} nm (peak k = {nk_g.imag.max():.2e}) and n swings "
        f"by {np.ptp(nk_g.real[(w_fig > 400) & (w_fig < 700)] - nk_s.real[(w_fig > 400) & (w_fig < 700)]):.1e} around it; "
        f"Kramers–Kronig reproduces that Δn from Δk within {100 * kk.relative_error:.1f} % of the swing (causal). "
        f"Absorption at the peak is α = {4 * np.pi * nk_g.imag.max() / peak_nm * 1e6:.0f} per mm, so plates are deep: "
        f"the glass reads red-purple (CIELAB h_ab in [330°, 30°), C* ≥ 20, L* ≥ 20) for thicknesses "
        f"{_range_text(th_mm, rp['D65'])} under D65 and {_range_text(th_mm, rp['A'])} under A; "
        f"thicker plates turn orange-red, then dark red; 1 mm gives L* = {d65_1mm[0]:.1f} (D65), and a 5 mm plate is nearly black: L* = {lab5['D65'][0]:.2f} (D65), "
        f"{lab5['A'][0]:.2f} (A). Gold rods move the longitudinal resonance to "
        + ", ".join(f"{r['peak_long_nm']:.0f} nm (AR {r['aspect_ratio']:g})" for r in rod_rows)
        + "; their colours change accordingly. Size correction (Doyle 1989, first Mie coefficient): peak at "
        + ", ".join(f"{r['peak_nm']:.0f} nm for r = {r['radius_nm']:g} nm "
                    f"(neglected multipoles ≤ {100 * r['neglected_multipoles_max']:.0f} % of extinction)"
                    for r in size_rows) + "."
    )
    tables["summary"] = {
        "plasmon_peak_nm": peak_nm,
        "red_purple_D65_mm": _range_text(th_mm, rp["D65"]),
        "red_purple_A_mm": _range_text(th_mm, rp["A"]),
        "L_5mm_D65": float(lab5["D65"][0]),
        "L_5mm_A": float(lab5["A"][0]),
        "kk_relative_error": kk.relative_error,
    }
    return {"title": "Gold-ruby glass: gold nanoparticles in silica (seed example 1)",
            "figures": figures, "tables": tables, "text": text}


__all__ = ["gold_ruby_demo", "gold_ruby_glass", "plate_transmittance", "reads_red_purple", "thickness_ranges"]
