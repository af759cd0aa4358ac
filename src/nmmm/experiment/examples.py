"""Worked example of the 2AFC validation experiment, on simulated observers.

- :func:`synthetic_pairs` — write small synthetic 'rendered' and 'photo' images and a
  ``pairs.toml`` for them (to try ``nmmm experiment serve`` without a real plate).
- :func:`simulate_responses` — fill a response database with simulated observers whose
  probability of picking the photograph varies from observer to observer (beta distribution).
- :func:`demo` — simulate the seed paper's experiment (about 40 viewers), analyse it, and
  write the report, the plot and the CSV export.

The simulated observers are not data: they show what the analysis reports for a rendering
that is nearly, but not perfectly, indistinguishable from the photograph.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from nmmm.experiment.pairs import load_pairs, make_pairs_file


def synthetic_pairs(output_dir, n_pairs: int = 10, size_px: int = 96, seed: int = 0, **settings) -> Path:
    """Write ``n_pairs`` synthetic image pairs and ``pairs.toml`` into ``output_dir``; return its path.

    Each 'photo' is a smooth colour gradient with a little grain; the 'rendered' image is the
    same gradient with slightly less grain (stand-ins for a real photograph and rendering).
    """
    from PIL import Image

    out = Path(output_dir)
    img_dir = out / "images"
    img_dir.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:size_px, 0:size_px] / size_px
    triples = []
    for i in range(n_pairs):
        base = rng.uniform(0.25, 0.75, 3)
        tilt = rng.uniform(-0.2, 0.2, 3)
        smooth = np.clip(base[None, None, :] + tilt[None, None, :] * (x + y)[..., None] / 2, 0, 1)
        photo = np.clip(smooth + rng.normal(0, 0.03, smooth.shape), 0, 1)
        render = np.clip(smooth + rng.normal(0, 0.02, smooth.shape), 0, 1)
        p_photo = img_dir / f"plate{i + 1:02d}_photo.png"
        p_render = img_dir / f"plate{i + 1:02d}_render.png"
        Image.fromarray((photo * 255).round().astype(np.uint8)).save(p_photo)
        Image.fromarray((render * 255).round().astype(np.uint8)).save(p_render)
        triples.append((p_render, p_photo, f"plate {i + 1:02d}"))
    return make_pairs_file(triples, out / "pairs.toml", **settings)


def simulate_responses(pairset, db_path, *, n_observers: int = 40, mean_pc: float = 0.55, rho: float = 0.05,
                       median_rt_ms: float = 1400.0, seed: int = 0) -> Path:
    """Fill ``db_path`` with simulated observers of the experiment ``pairset``.

    Observer ``i`` picks the photograph with probability ``p_i ~ Beta(mean_pc, rho)`` (mean
    ``mean_pc``, intra-class correlation ``rho``); response times are log-normal around
    ``median_rt_ms``. Participants, trials and responses go through
    :class:`~nmmm.experiment.storage.ResponseStore`, exactly as the web server stores them.
    """
    import uuid

    from nmmm.experiment.storage import ResponseStore

    rng = np.random.default_rng(seed)
    a = mean_pc * (1 - rho) / rho
    b = (1 - mean_pc) * (1 - rho) / rho
    with ResponseStore(db_path, synchronous="OFF") as store:
        store.register_pairs(pairset)
        for i in range(n_observers):
            part = store.create_participant(f"S{i + 1:02d}", pairset, consent_sha256="simulated",
                                            user_agent="simulation", seed=int(rng.integers(2**62)))
            p_i = rng.beta(a, b)
            pid = part["participant_id"]
            for t in range(part["n_trials"]):
                trial = store.trial(pid, t)
                correct = rng.random() < p_i
                chosen = trial["photo_slot"] if correct else 1 - trial["photo_slot"]
                rt = float(median_rt_ms * np.exp(rng.normal(0, 0.35)))
                store.record_response(pid, t, str(uuid.UUID(bytes=rng.bytes(16), version=4)), chosen, rt)
    return Path(db_path)


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
    (out / "experiment_summary.json").write_text(json.dumps(table, indent=2), encoding="utf-8")
    text = (f"Simulated 2AFC validation: 40 observers x {n_trials} trials, true mean Pc 0.55 with observer "
            f"spread (ICC 0.05). Pooled Pc {100 * p.pc:.1f} % [{100 * p.interval[0]:.1f}, "
            f"{100 * p.interval[1]:.1f}] (cluster-robust), d' = {analysis.pooled_dprime:.2f}; "
            + ("indistinguishable within ±10 %." if e.equivalent else "equivalence within ±10 % not shown."))
    return {"title": "2AFC visual validation (simulated observers)", "figures": [str(fig_path)],
            "tables": {"experiment_summary": table}, "text": text + "\n\n" + report,
            "files": [str(csv_path), str(pairs_toml), str(db)]}


__all__ = ["synthetic_pairs", "simulate_responses", "demo"]
