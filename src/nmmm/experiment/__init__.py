"""nmmm.experiment — the two-alternative forced-choice (2AFC) visual validation experiment.

A photograph of a real painted plate and a computed image of it are shown side by side; the
participant, who does not know which is which, picks the photograph. If observers cannot do
better than chance, the prediction is visually validated.

- :mod:`nmmm.experiment.pairs` — the ``pairs.toml`` file: :func:`load_pairs`,
  :func:`make_pairs_file` (from nmmm renderings and photographs).
- :mod:`nmmm.experiment.app` — the web application (:func:`create_app`, :func:`serve`).
- :mod:`nmmm.experiment.storage` — the SQLite response database (WAL, one commit per response).
- :mod:`nmmm.experiment.stats` — proportion correct, binomial tests, d' for 2AFC, Wilson and
  Clopper-Pearson intervals, TOST equivalence, pooling over observers, plot.
- :mod:`nmmm.experiment.power_analysis` — power of the equivalence test, observers needed.
- :mod:`nmmm.experiment.export` — CSV export.
- :mod:`nmmm.experiment.simulation` — :func:`synthetic_pairs` (image pairs to try the server) and
  :func:`simulate_responses` (simulated observers). The worked example is :func:`nmmm.demo.experiment.demo`.

Command line: ``nmmm experiment serve | stats | export``.
"""

import importlib

#: public name -> module (imported on first use: the web server needs neither SciPy nor matplotlib)
_LAZY = {
    "ExperimentSettings": "pairs", "PairSet": "pairs", "StimulusPair": "pairs", "load_pairs": "pairs",
    "make_pairs_file": "pairs", "read_responses": "storage", "analyse_responses": "stats",
    "binomial_test": "stats", "critical_count": "stats", "dprime_2afc": "stats", "format_report": "stats",
    "plot_analysis": "stats", "pooled_proportion": "stats", "proportion_ci": "stats", "tost_binomial": "stats",
    "create_app": "app", "synthetic_pairs": "simulation", "simulate_responses": "simulation",
    "tost_power": "power_analysis", "tost_observers_needed": "power_analysis",
    "tost_power_analysis": "power_analysis", "PowerResult": "power_analysis",
}

__all__ = [
    "ExperimentSettings", "PairSet", "StimulusPair", "load_pairs", "make_pairs_file", "read_responses",
    "analyse_responses", "binomial_test", "critical_count", "dprime_2afc", "format_report", "plot_analysis",
    "pooled_proportion", "proportion_ci", "tost_binomial", "create_app", "synthetic_pairs", "simulate_responses",
    "tost_power", "tost_observers_needed", "tost_power_analysis", "PowerResult",
]


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(f"nmmm.experiment.{_LAZY[name]}"), name)
    raise AttributeError(f"module 'nmmm.experiment' has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + list(_LAZY))
