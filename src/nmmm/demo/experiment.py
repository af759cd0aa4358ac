"""Worked example of the 2AFC validation experiment, on simulated observers (seed example 5).

- :func:`demo` — simulate the seed paper's experiment (about 40 viewers), analyse it, and
  write the report, the plot and the CSV export.

The simulated observers are not data: they show what the analysis reports for a rendering
that is nearly, but not perfectly, indistinguishable from the photograph. They come from
:mod:`nmmm.experiment.simulation` (:func:`synthetic_pairs`, :func:`simulate_responses`, re-exported
here).
"""

from __future__ import annotations

import json
from pathlib import Path

from nmmm.experiment.pairs import load_pairs
from nmmm.experiment.simulation import simulate_responses, synthetic_pairs


def demo(output_dir) -> dict:
    """Simulate a 40-observer experiment, analyse it, write plot, report and CSV into ``output_dir``.

    Returns ``{"title", "figures", "tables", "text"}`` for the nmmm report.
    """
    from nmmm.experiment.export import write_csv
    from nmmm.experiment.stats import analyse_responses, critical_count, format_report, plot_analysis
    from nmmm.experiment.storage import read_responses

    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    pairs_toml = synthetic_pairs(out / "experiment_pairs", n_pairs=10, repetitions=2)
    pairset = load_pairs(pairs_toml)
    db = out / "experiment_responses.sqlite"
    for suffix in ("", "-wal", "-shm"):
        Path(f"{db}{suffix}").unlink(missing_ok=True)
    simulate_responses(pairset, db, n_observers=40, mean_pc=0.55, rho=0.05, seed=7)
    rows = read_responses(db)
    analysis = analyse_responses(rows, delta=0.1)
    report = format_report(analysis)
    fig_path = out / "experiment_2afc.png"
    plot_analysis(analysis, fig_path)
    csv_path = out / "experiment_responses.csv"
    write_csv(db, csv_path)
    (out / "experiment_report.txt").write_text(report + "\n", encoding="utf-8")
    p, e = analysis.pooled, analysis.equivalence
    n_trials = pairset.n_trials
    table = {
        "observers": len(analysis.observers), "trials per observer": n_trials,
        "critical count (one-sided, alpha 0.05)": critical_count(n_trials),
        "pooled Pc": round(p.pc, 4), "pooled 95% CI": [round(x, 4) for x in p.interval],
        "pooled p (two-sided)": float(f"{p.p_value:.4g}"), "pooled d'": round(analysis.pooled_dprime, 3),
        "intra-class correlation": None if p.rho is None else round(float(p.rho), 4),
        "TOST p (delta 0.1)": float(f"{e.p_value:.4g}"), "equivalent within ±0.1": bool(e.equivalent),
        "observers above chance": sum(g.significant and g.pc > 0.5 for g in analysis.observers),
    }
    pw = analysis.power
    if pw is not None:  # how many viewers are enough (issue 20): the seed's 40 volunteers x 20 trials
        table[f"TOST power, {pw.n_observers} x {pw.n_trials} (delta {pw.delta:g}, true Pc 0.5, ICC {pw.rho:.3g})"] = \
            round(pw.power, 3)
        table[f"observers needed for {100 * pw.target_power:.0f} % power"] = pw.observers_needed
    (out / "experiment_summary.json").write_text(json.dumps(table, indent=2), encoding="utf-8")
    text = (f"Simulated 2AFC validation: 40 observers x {n_trials} trials, true mean Pc 0.55 with observer "
            f"spread (ICC 0.05). Pooled Pc {100 * p.pc:.1f} % [{100 * p.interval[0]:.1f}, "
            f"{100 * p.interval[1]:.1f}] (cluster-robust), d' = {analysis.pooled_dprime:.2f}; "
            + ("indistinguishable within ±10 %." if e.equivalent else "equivalence within ±10 % not shown."))
    return {"title": "2AFC visual validation (simulated observers)", "figures": [str(fig_path)],
            "tables": {"experiment_summary": table}, "text": text + "\n\n" + report,
            "files": [str(csv_path), str(pairs_toml), str(db)]}


__all__ = ["synthetic_pairs", "simulate_responses", "demo"]
