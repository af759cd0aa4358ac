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
- :mod:`nmmm.experiment.export` — CSV export.
- :mod:`nmmm.experiment.examples` — :func:`~nmmm.experiment.examples.demo` and
  :func:`~nmmm.experiment.examples.simulate_responses`.

Command line: ``nmmm experiment serve | stats | export``.
"""

from nmmm.experiment.pairs import ExperimentSettings, PairSet, StimulusPair, load_pairs, make_pairs_file
from nmmm.experiment.stats import (
    analyse_responses,
    binomial_test,
    critical_count,
    dprime_2afc,
    format_report,
    plot_analysis,
    pooled_proportion,
    proportion_ci,
    tost_binomial,
)
from nmmm.experiment.storage import read_responses

__all__ = [
    "ExperimentSettings", "PairSet", "StimulusPair", "load_pairs", "make_pairs_file", "read_responses",
    "analyse_responses", "binomial_test", "critical_count", "dprime_2afc", "format_report", "plot_analysis",
    "pooled_proportion", "proportion_ci", "tost_binomial", "create_app",
]


def __getattr__(name):  # the web stack is imported only when needed
    if name == "create_app":
        from nmmm.experiment.app import create_app

        return create_app
    raise AttributeError(f"module 'nmmm.experiment' has no attribute {name!r}")
