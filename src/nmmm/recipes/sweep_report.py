"""What a reader sees of a sweep: its plot and its report section.

- :func:`plot_sweep` — L* (first illuminant) against the first varied parameter, one curve per
  combination of the others, and the spectra of every point; legends in words with units
  (:func:`nmmm.recipes.figures.legend_label`), every curve its own colour and line style
  (:func:`nmmm.recipes.figures.curve_styles`); above :data:`MAX_LEGEND` spectra a colour scale
  of the first parameter replaces the legend.
- :func:`sweep_report_section` — the report section of a finished sweep: the plot first, the
  points (headers in words, folded when long; all of them in ``results.csv``), the note that
  explains a masstone unchanged over a concentration series
  (:func:`nmmm.recipes.sanity.masstone_unchanged_note`), and the command that reproduces it.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

__all__ = ["plot_sweep", "sweep_report_section", "MAX_LEGEND"]

#: most spectra given a legend entry each
MAX_LEGEND = 16


def _params(df) -> list[str]:
    return [c for c in df.columns if c.startswith("param:")]


def _point_words(r, params) -> str:
    from nmmm.recipes.figures import legend_label

    return "; ".join(legend_label(p, r[p]) for p in params)


def plot_sweep(df, path, quantity: str | None = None):
    """Save the sweep's figure at ``path`` (see the module docstring); returns ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from nmmm.recipes.figures import curve_styles, legend_label, quantity_label, save_figure

    params = _params(df)
    qty = quantity or next((c for c in df.columns if c.startswith("L_")), None)
    x = params[0]
    others = params[1:]
    groups = list(df.groupby(others)) if others else [(None, df)]
    n_spec = len(df)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.6 + 0.16 * min(max(len(groups), n_spec if n_spec <= MAX_LEGEND else 0), MAX_LEGEND)),
                                 layout="constrained")
    for (val, g), style in zip(groups, curve_styles(len(groups))):
        vals = val if isinstance(val, tuple) else (val,)
        label = "; ".join(legend_label(p, v) for p, v in zip(others, vals)) if others else None
        g = g.sort_values(x)
        a1.plot(g[x], g[qty], marker="o", label=label, **style)
    a1.set_xlabel(quantity_label(x))
    a1.set_ylabel(quantity_label(qty) if qty else "value (1)")
    a1.grid(alpha=0.3)
    if others:
        a1.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=1, frameon=False)
    if n_spec <= MAX_LEGEND:
        for (_, r), style in zip(df.iterrows(), curve_styles(n_spec)):
            a2.plot(r["wavelength_nm"], r["spectrum"], lw=1.2, label=_point_words(r, params), **style)
        a2.legend(fontsize=6.5, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=1 if n_spec <= 8 else 2,
                  frameon=False)
    else:  # many points: colour by the first parameter, a scale instead of a legend
        xs = np.asarray(df[x], float)
        norm = matplotlib.colors.Normalize(xs.min(), xs.max() if xs.max() > xs.min() else xs.min() + 1)
        cmap = matplotlib.colormaps["viridis"]
        for (_, r), xv in zip(df.iterrows(), xs):
            a2.plot(r["wavelength_nm"], r["spectrum"], lw=0.8, color=cmap(norm(xv)))
        cb = fig.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap), ax=a2)
        cb.set_label(quantity_label(x))
    a2.set_xlabel("wavelength (nm)")
    a2.set_ylabel(f"{df['primary'].iloc[0]} (1)")
    a2.grid(alpha=0.3)
    return save_figure(fig, path)


def _masstone_note(df, raw) -> str:
    """The opacity explanation for a concentration series, per combination of the other params."""
    from nmmm.recipes.sanity import masstone_unchanged_note

    params = _params(df)
    frac = next((p for p in params if p.endswith("fraction")), None)
    ill = next((c[2:] for c in df.columns if c.startswith("L_")), None)
    if frac is None or ill is None or not {f"a_{ill}", f"b_{ill}"} <= set(df.columns):
        return ""
    others = [p for p in params if p != frac]
    groups = list(df.groupby(others)) if others else [(None, df)]
    thickness = (raw.get("film") or {}).get("thickness_nm") if isinstance(raw.get("film"), dict) else None
    t_um = float(thickness) / 1000.0 if thickness else (20.0 if raw.get("film") is not None else None)
    from nmmm.colour import delta_e2000
    from nmmm.recipes.figures import legend_label

    found = []  # (series in words, ΔE00 lowest -> highest fraction, note) of the series that do not change
    for key, g in groups:
        labs = g[[f"L_{ill}", f"a_{ill}", f"b_{ill}"]].to_numpy(float)
        note = masstone_unchanged_note(g[frac], labs, t_um, illuminant=ill)
        if note:
            f = g[frac].to_numpy(float)
            de = float(delta_e2000(labs[int(np.argmin(f))], labs[int(np.argmax(f))]))
            vals = key if isinstance(key, tuple) else (key,)
            found.append(("; ".join(legend_label(p, v) for p, v in zip(others, vals)), de, note))
    if not found:
        return ""
    if not others:
        return found[0][2]
    # one explanation, naming each series it holds for (another swept setting may change the masstone)
    head, rest = found[0][2].split(" (ΔE00 = ", 1)
    rest = rest.split("): ", 1)[1]
    series = "; ".join(f"{de:.2f} with {words}" for words, de, _ in found)
    text = f"{head} (ΔE00 under {ill}: {series}): {rest}"
    if len(found) < len(groups):
        text += " In the other series of this sweep the masstone does change with the fraction (see the plot)."
    return text


def _vary_arg(df, p) -> str:
    vals = list(dict.fromkeys(df[p].tolist()))
    fmt = lambda v: ("true" if v else "false") if isinstance(v, (bool, np.bool_)) else f"{v:g}" if isinstance(v, (int, float, np.number)) else str(v)
    return f"--vary {p[6:]}={','.join(fmt(v) for v in vals)}"


def sweep_report_section(df, summary, raw, out) -> dict:
    """The report section of a finished sweep (see the module docstring)."""
    from nmmm.recipes.figures import quantity_label
    from nmmm.recipes.run import _dump_toml

    out = Path(out)
    params = _params(df)
    colour_cols = [c for c in df.columns if c[:2] in ("L_", "a_", "b_") and "." not in c]
    rows = [{**{quantity_label(p): r[p] for p in params}, **{c: r[c] for c in colour_cols}} for _, r in df.iterrows()]
    text = [f"{summary['n_computed']} points computed now, {summary['n_skipped']} found on disk; "
            f"{summary['wall_s']:.1f} s wall, {summary['physics_s']:.1f} s of physics. CIELAB of the primary "
            f"spectrum ({df['primary'].iloc[0]}) under each illuminant."]
    warnings_ = []
    note = _masstone_note(df, raw)
    if note:
        warnings_.append(note)
    source = ""
    try:
        source = json.loads((out / "sweep.json").read_text()).get("recipe_source") or ""
    except (OSError, ValueError):
        pass
    recipe_arg = source or "RECIPE.toml"
    cmd = f"nmmm sweep {recipe_arg} " + " ".join(_vary_arg(df, p) for p in params) + f" -o {out}"
    nxt = [("reproduce (or resume) this sweep", cmd),
           ("every point as a table", f"{out / 'results.csv'}"),
           ("one point as a full run with its report", f"nmmm run {recipe_arg} --set {params[0][6:]}=VALUE -o out-point")]
    sec = {"title": f"Sweep of {raw.get('name', 'recipe')}: {summary['n_points']} points", "text": text,
           "figures": [summary["plot"]] if summary.get("plot") else [], "warnings": warnings_,
           "tables": {"Points (CIELAB in 1; all of them in results.csv)": rows}, "recipe": _dump_toml(raw),
           "next": nxt}
    return sec
