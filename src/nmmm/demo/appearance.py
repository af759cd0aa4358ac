"""Worked examples of the appearance scale (seed paper examples 3 and 4).

- :func:`demo` — writes into a folder: the multi-angle colour of the grey metallic paint
  (ASTM E2539 geometries, flop index), the colour travel of interference (TiO2/mica)
  paints, in-plane BRDF plots of a solid, a metallic and an interference paint, a sparkle
  image of the metallic paint's flake deposit with its sparkle/graininess metrics, and the
  metallic BRDF exported as a (θ_h, θ_d, λ) table. Returns a summary dict for the report.

The grey metallic paint is an :class:`nmmm.appearance.effect_coat.EffectCoat` given by its
composition (:func:`nmmm.appearance.deposit.grey_metallic_coat`: a
:func:`nmmm.microstructure.flake_deposit` in the seed's 450 µm × 450 µm × 20 µm cell — the same
flakes give the discrete list (sparkle) and the statistical BRDF); it is the shipped recipe
``grey_metallic`` with the same numbers. The coloured metallic and the coloured pearl are the
shipped recipes ``red_metallic`` and ``fe2o3_mica_pearl`` built into the same EffectCoat
(:func:`nmmm.recipes.effect_schema.build_effect_coat`). For each effect coat the demo shows
composition → derived layer parameters (flakes per mm², optical depth, tilt, depth band) →
multi-angle colour, flop index and sparkle. The solid hematite paint comes from
:mod:`nmmm.demo.hematite`'s compounds.
"""

from __future__ import annotations

import csv
import time
from pathlib import Path

import numpy as np

from nmmm.appearance.deposit import grey_metallic_from_deposit

__all__ = ["demo", "grey_metallic_from_deposit"]


def _hematite_paint(w):
    """Solid rusty-red paint (seed example 2): hematite (uniaxial mean of Querry), 250 nm
    pseudo-cube diagonal, 7 % in the epoxy binder, 20 µm over a white substrate, base
    from nmmm.layers (Mie + Kubelka–Munk), epoxy clear coat."""
    from nmmm.appearance.brdf import opaque_paint_from_film
    from nmmm.demo.hematite import epoxy_binder, hematite
    from nmmm.layers.distributions import equivalent_sphere_diameter, lognormal
    from nmmm.layers.paint import PaintFilm

    d = equivalent_sphere_diameter("cube", "volume", body_diagonal_nm=250.0)
    film = PaintFilm(hematite(), epoxy_binder(), lognormal(d, 1.25, n_nodes=16), 0.07, 20e3, 0.8, 0.0)
    return opaque_paint_from_film(film, w, name="solid hematite paint (7 %)")


def _recipe_coat(name, w):
    """A shipped effect recipe's EffectCoat (the recipe path's own object)."""
    from nmmm.recipes.effect_schema import build_effect_coat
    from nmmm.recipes.run import build_materials
    from nmmm.recipes.schema import example_path, load_recipe

    r = load_recipe(example_path(name))
    return build_effect_coat(r.effect, build_materials(r, w), name=r.name)


def _composition(coat) -> str:
    f = coat.flakes
    pig = ", ".join(f"{c.name} {c.fraction:g}" for c in coat.pigments) or "none"
    mat = "layered flake (" + " / ".join(f"{getattr(la.material, 'name', 'layer')} {float(la.thickness_nm):g} nm"
                                         for la in f.material.layers) + ")" if f.layered else str(f.material)
    return (f"{mat}, {f.diameter_um:g}±{f.diameter_std_um:g} µm × {float(f.thickness_nm):g} nm, {f.fraction:g} of a "
            f"{coat.coat_thickness_nm / 1e3:g} µm basecoat, tilt s = {f.tilt_std_deg:g}°; pigments: {pig}")


def _effect_coat_rows(coats, w, wi):
    """Composition -> derived layer -> multi-angle colour, flop, sparkle, one row per coat."""
    from nmmm.appearance.multiangle import ASTM_E2194_ALL_ASPECULAR_DEG, multiangle_lab
    from nmmm.appearance.sparkle import flake_glint_image, sparkle_graininess

    rows, colours = [], []
    wo15 = np.array([-np.sin(np.radians(30.0)), 0.0, np.cos(np.radians(30.0))])
    for coat in coats:
        paint, flakes = coat.brdf(w)
        d = coat.derived()
        c = multiangle_lab(paint, w, ASTM_E2194_ALL_ASPECULAR_DEG)
        colours.append(c)
        img = flake_glint_image(paint, flakes, np.arange(400.0, 701.0, 20.0), wi, wo15, pixel_size_um=5.0,
                                acceptance_deg=1.5)
        m = sparkle_graininess(img, pixel_size_um=5.0)
        rows.append(dict(paint=coat.name, composition=_composition(coat), flakes_per_mm2=d.number_density_per_mm2,
                         optical_depth=d.optical_depth, projected_optical_depth=d.projected_optical_depth,
                         mean_tilt_deg=d.mean_tilt_deg, band=f"{d.depth_range[0]:.2f}-{d.depth_range[1]:.2f}",
                         **{f"L{g:g}": float(L) for g, L in zip(c.aspecular_deg, c.L)},
                         a45=c.lab[2, 1], b45=c.lab[2, 2], flop_index=c.flop_index(),
                         sparkles_per_mm2_15=m.density_per_mm2, sparkle_intensity_15=m.sparkle_intensity))
    return rows, colours


def _write_csv(path, rows):
    with open(path, "w", newline="") as fh:
        wr = csv.DictWriter(fh, fieldnames=list(rows[0]))
        wr.writeheader()
        for r in rows:
            wr.writerow({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in r.items()})


def demo(output_dir) -> dict:
    """Run the appearance worked examples into ``output_dir``; returns
    ``{"title", "figures", "tables", "text"}``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from nmmm.appearance.brdf import interference_paint, write_brdf_table
    from nmmm.appearance.multiangle import ASTM_E2539_ASPECULAR_DEG, multiangle_lab, plot_colour_travel
    from nmmm.appearance.sparkle import flake_glint_image, sparkle_graininess

    t0 = time.time()
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    w = np.arange(380.0, 781.0, 10.0)
    figures, tables = [], {}

    # 1. grey metallic paint: multi-angle colour -------------------------------------
    metallic, flakes = grey_metallic_from_deposit(wavelength_nm=w)
    cm = multiangle_lab(metallic, w, ASTM_E2539_ASPECULAR_DEG)
    fi = cm.flop_index()
    rows = cm.table()
    _write_csv(out / "grey_metallic_multiangle.csv", rows)
    tables["grey metallic paint, CIELAB (D65/10°) at 45° illumination"] = rows
    p = out / "grey_metallic_multiangle.png"
    plot_colour_travel(cm, p, title=f"Grey metallic paint (Al flakes, tau={flakes.optical_depth:.2f}): flop index {fi:.1f}")
    figures.append(str(p))

    # 2. interference paints: colour travel ----------------------------------------
    inter = [interference_paint(d, 350.0, name=f"TiO2 {d:g} nm on mica") for d in (80.0, 120.0, 160.0)]
    ci = [multiangle_lab(b, w, ASTM_E2539_ASPECULAR_DEG) for b in inter]
    p = out / "interference_colour_travel.png"
    plot_colour_travel(ci, p, title="Interference (TiO2/mica) paints over a dark base: colour travel")
    figures.append(str(p))
    rows_i = [dict(paint=c.name, **r) for c in ci for r in c.table()]
    _write_csv(out / "interference_multiangle.csv", rows_i)

    # 3. in-plane BRDFs -------------------------------------------------------------
    solid = _hematite_paint(w)
    cs = multiangle_lab(solid, w, ASTM_E2539_ASPECULAR_DEG)
    th_v = np.linspace(-85, 85, 341)
    wi = np.array([np.sin(np.radians(45)), 0.0, np.cos(np.radians(45))])
    wo = np.stack([-np.sin(np.radians(th_v)), 0 * th_v, np.cos(np.radians(th_v))], -1)
    fig, axes = plt.subplots(1, 3, figsize=(14, 4), sharey=True)
    for ax, b in zip(axes, (solid, metallic, inter[1])):
        f = b(w, wi, wo)
        for lam, col in ((450.0, "tab:blue"), (550.0, "tab:green"), (650.0, "tab:red")):
            ax.semilogy(th_v, f[:, np.argmin(abs(w - lam))], color=col, label=f"{lam:g} nm")
        ax.axvline(45, color="0.6", ls=":", lw=0.8)
        ax.set_title(b.name, fontsize=9)
        ax.set_xlabel("viewing angle, specular side > 0 (deg)")
    axes[0].set_ylabel("BRDF (1/sr), illumination 45°")
    axes[0].legend(fontsize=8)
    fig.suptitle("In-plane spectral BRDFs (smooth clear coat: the mirror Dirac at 45° is not drawn)")
    fig.tight_layout()
    p = out / "brdf_in_plane.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    figures.append(str(p))

    # 4. sparkle of the flake deposit -----------------------------------------------
    wl_s = np.arange(400.0, 701.0, 20.0)
    views = {"near specular (15° aspecular)": 30.0, "flop (45° aspecular)": 0.0}
    fig, axes = plt.subplots(1, len(views), figsize=(10, 4.6))
    sp_rows = []
    vmax = None
    for ax, (label, tv) in zip(axes, views.items()):
        wo1 = np.array([-np.sin(np.radians(tv)), 0.0, np.cos(np.radians(tv))])
        img = flake_glint_image(metallic, flakes, wl_s, wi, wo1, pixel_size_um=5.0, acceptance_deg=1.5)
        m = sparkle_graininess(img, pixel_size_um=5.0)
        sp_rows.append(dict(view=label, n_sparkles=m.n_sparkles, density_per_mm2=m.density_per_mm2,
                            sparkle_intensity=m.sparkle_intensity, graininess=m.graininess))
        vmax = vmax or max(np.percentile(img, 99.9), 3 * np.median(img))  # same scale for both views
        ax.imshow(np.sqrt(np.clip(img / vmax, 0, 1)), cmap="gray", vmin=0, vmax=1,
                  extent=(0, 450, 450, 0))  # square-root display stretch
        ax.set_title(f"{label}\n{m.density_per_mm2:.0f} sparkles/mm², S={m.sparkle_intensity:.3f}", fontsize=9)
        ax.set(xlabel="x (µm)", ylabel="y (µm)")
    fig.suptitle(f"Grey metallic paint, 450 µm cell, {len(flakes)} Al flakes: glints at 45° illumination")
    fig.tight_layout()
    p = out / "grey_metallic_sparkle.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    figures.append(str(p))
    _write_csv(out / "grey_metallic_sparkle.csv", sp_rows)
    tables["sparkle of the grey metallic paint (5 µm pixels)"] = sp_rows

    # 5. effect coats from their composition: derived layer, colour, flop, sparkle -------
    from nmmm.appearance.deposit import grey_metallic_coat

    coats = [grey_metallic_coat(), _recipe_coat("red_metallic", w), _recipe_coat("fe2o3_mica_pearl", w)]
    ec_rows, ec_colours = _effect_coat_rows(coats, w, wi)
    _write_csv(out / "effect_coats.csv", ec_rows)
    tables["effect coats: composition → derived flake layer → CIELAB (D65/10°, 45° illumination), flop, sparkle"] = ec_rows
    p = out / "effect_coats_colour_travel.png"
    plot_colour_travel(ec_colours, p, title="Effect coats from their composition (ASTM E2194 angles)")
    figures.append(str(p))

    # 6. BRDF table for renderers ------------------------------------------------------
    tpath = write_brdf_table(out / "grey_metallic_brdf_table.nc", metallic, np.arange(400.0, 701.0, 20.0),
                             n_theta_h=45, n_theta_d=45, n_phi_d=12)

    ci_txt = "; ".join(f"{c.name}: h {c.hue_deg[1]:.0f}°→{c.hue_deg[-1]:.0f}° (15°→110°)" for c in ci)
    text = (
        f"Grey metallic paint (seed example 3): Al flakes (Rakić) deposited in the 450×450×20 µm cell "
        f"({len(flakes)} flakes, optical depth τ = {flakes.optical_depth:.2f}, mean tilt "
        f"{metallic.flakes.tilt.mean_tilt_deg():.1f}°) under a smooth clear coat over a grey base: "
        f"L*15 = {cm.lightness_at(15):.1f}, L*45 = {cm.lightness_at(45):.1f}, L*110 = {cm.lightness_at(110):.1f}, "
        f"flop index (Alman 1987) {fi:.1f}; the solid hematite paint (seed example 2, base from nmmm.layers) "
        f"has flop index {cs.flop_index():.2f}. "
        f"Interference paints (seed example 4) change hue with angle: {ci_txt}. "
        f"The same flake list gives the sparkle images and, averaged, the statistical BRDF. "
        f"Effect coats from their composition (flakes, pigments, binder, coat thickness -> derived flake layer): "
        + "; ".join(f"{r['paint']}: τ = {r['optical_depth']:.2f}, {r['flakes_per_mm2']:.0f} flakes/mm², "
                    f"L*15/45/110 = {r['L15']:.0f}/{r['L45']:.0f}/{r['L110']:.0f}, flop index {r['flop_index']:.1f}"
                    for r in ec_rows) + ". "
        f"BRDF table: {tpath.name} (θ_h, θ_d, λ). Runtime {time.time() - t0:.0f} s."
    )
    return {"title": "Appearance: BRDFs, multi-angle colour and sparkle of effect paints", "figures": figures,
            "tables": tables, "text": text}
