"""The ``nmmm match`` result folder, written atomically (:func:`nmmm.atomic_io.atomic_output_dir`).

- :func:`write_match_outputs` — ``matched_recipe.toml`` (the recipe with the matched values,
  runnable by ``nmmm run``), ``matches.csv`` (one row per candidate, ranked: a column per varied
  key, ``dE00``, ``metamerism_index_<illuminant>``, the illuminant, ΔL*/ΔC*/ΔH*),
  ``spectra.csv`` (target and match), ``prediction.cgats`` (the matched spectrum as CGATS.17 for
  formulation / QC software), ``spectra.png`` (target and match overlaid), ``report.md`` and
  ``match.json`` (every number of the result).
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

__all__ = ["write_match_outputs"]


def _plot(res, path: Path, target_name: str):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.0), dpi=110)
    if res.target_reflectance is not None:
        ax.plot(res.wavelength_nm, res.target_reflectance, "k-", lw=2, label=f"target ({target_name})")
    ax.plot(res.wavelength_nm, res.reflectance, "C3--", lw=1.5, label=f"match (ΔE00 {res.de00:.3f}, {res.illuminant})")
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("reflectance factor (1)")
    ax.legend(loc="best", fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def write_match_outputs(res, out_dir, target_name: str = "target", plots: bool = True,
                        difference: dict | None = None) -> dict:
    """Write the result folder (module docstring); returns ``{kind: path}`` of the final folder.

    ``difference``: the reported colour difference (``method``, ``value``, ``tolerance``, ``passes`` …),
    written into match.json and report.md (the fit itself is on ΔE00).
    """
    from nmmm.atomic_io import atomic_output_dir
    from nmmm.matching.measured_files import MeasuredSpectra, write_cgats
    from nmmm.recipes.run import _dump_toml

    out = Path(out_dir)
    names = {"recipe": "matched_recipe.toml", "matches": "matches.csv", "spectra": "spectra.csv",
             "cgats": "prediction.cgats", "report": "report.md", "json": "match.json"}
    if plots:
        names["plot"] = "spectra.png"
    with atomic_output_dir(out) as tmp:
        raw = dict(res.recipe_raw)
        raw["name"] = f"{raw.get('name', 'recipe')} — matched to {target_name}"
        (tmp / names["recipe"]).write_text(
            f"# nmmm match: ΔE00 = {res.de00:.4f} under {res.illuminant} ({res.mode} match)\n" + _dump_toml(raw), encoding="utf-8")
        buf = io.StringIO()
        cols = list(res.candidates[0]) if res.candidates else []
        wr = csv.DictWriter(buf, fieldnames=["rank"] + cols)
        wr.writeheader()
        for i, row in enumerate(res.candidates, 1):
            wr.writerow({"rank": i, **{k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in row.items()}})
        (tmp / names["matches"]).write_text(buf.getvalue(), encoding="utf-8")
        lines = ["wavelength_nm,target,match"]
        for i, wl in enumerate(res.wavelength_nm):
            t = "" if res.target_reflectance is None else f"{res.target_reflectance[i]:.6f}"
            lines.append(f"{wl:g},{t},{res.reflectance[i]:.6f}")
        (tmp / names["spectra"]).write_text("\n".join(lines) + "\n", encoding="utf-8")
        write_cgats(tmp / names["cgats"], MeasuredSpectra(res.wavelength_nm, res.reflectance[None], ("match",),
                                                          res.recipe_raw.get("measurement", {}).get("geometry")))
        summary = dict(values=res.values, dE00=res.de00, dL_dC_dH=[float(v) for v in res.dlch], illuminant=res.illuminant,
                       metamerism_index=res.metamerism, spectral_rms=res.spectral_rms, target_lab=[float(v) for v in res.target_lab],
                       lab=[float(v) for v in res.lab], mode=res.mode, model_evaluations=res.evaluations, time_s=res.time_s,
                       standard_errors=res.standard_errors, noise=res.noise,
                       shares={k: dict(share=v, sigma=e) for k, (v, e) in res.shares.items()}, total=res.total,
                       active_bounds=res.active_bounds, warnings=res.warnings,
                       adding_doubling_nodes=res.quad_pts)
        if difference is not None:
            summary["difference"] = difference
        (tmp / names["json"]).write_text(json.dumps(summary, indent=1, default=float), encoding="utf-8")
        md = [f"# Match to {target_name}", "",
              f"- mode: {res.mode}; primary illuminant {res.illuminant}, CIE 1931 2°",
              f"- ΔE00 = {res.de00:.4f} (ΔL* {res.dlch[0]:+.3f}, ΔC* {res.dlch[1]:+.3f}, ΔH* {res.dlch[2]:+.3f})",
              "- metamerism index (CIE 15 change of illuminant, ΔE00, additive correction): "
              + (", ".join(f"{k} {v:.3f}" for k, v in res.metamerism.items()) or "— (CIELAB target)"),
              *_difference_lines(difference),
              f"- spectral RMS: {res.spectral_rms:.5f}" if np.isfinite(res.spectral_rms) else "- spectral RMS: — (CIELAB target)",
              f"- model evaluations: {res.evaluations}; {res.time_s:.1f} s", "",
              f"| key | value | σ linearised (noise {res.noise:g}) |" + (" share of the total ± σ |" if res.shares else ""),
              "|---|---|---|" + ("---|" if res.shares else "")]
        md += [f"| {k} | {v:.6g} | {res.standard_errors.get(k, float('nan')):.3g} |"
               + ((" {:.4g} ± {:.2g} |".format(*res.shares[k]) if k in res.shares else " — |") if res.shares else "")
               for k, v in res.values.items()]
        if res.total:
            t = res.total
            md += ["", f"Total of the matched fractions {t['total']:.4g}: 68 % profile interval {t['low']:.4g}–{t['high']:.4g}"
                   + (" (an end at the --vary bounds: the spectrum does not pin it there)"
                      if t["low_at_bound"] or t["high_at_bound"] else "") + "."]
        if res.active_bounds:
            md += ["", f"Bounds reached: {', '.join(res.active_bounds)}."]
        md += [""] + [f"**Warning:** {w}" for w in res.warnings]
        (tmp / names["report"]).write_text("\n".join(md) + "\n", encoding="utf-8")
        if plots:
            _plot(res, tmp / names["plot"], target_name)
    return {k: out / v for k, v in names.items()}


def _difference_lines(difference: dict | None) -> list[str]:
    """report.md lines of the reported colour difference and its pass/fail (none without one)."""
    if difference is None:
        return []
    line = f"- {difference['label']} = {difference['value']:.4f} under {difference['illuminant']}"
    if difference.get("tolerance") is not None:
        verdict = "**pass**" if difference["passes"] else "**fail**"
        line += f"; tolerance {difference['tolerance']:g}: {verdict}"
    return [line]
