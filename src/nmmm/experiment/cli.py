"""``nmmm experiment``: serve the 2AFC validation experiment, analyse and export its responses.

- ``nmmm experiment serve pairs.toml --db responses.sqlite [--host 127.0.0.1 --port 8000]``
  (``--check``: load every image, prepare the stimuli, open the database, then exit — a dry run
  before a session)
- ``nmmm experiment stats responses.sqlite [--plot out.png] [--delta 0.1] [--pooling cluster-robust]``
- ``nmmm experiment export responses.sqlite -o out.csv``
"""

from __future__ import annotations

import json
import os

import click


def _db_folder(db_path) -> None:
    """Create the folder of the response database (``--db out/responses.sqlite``)."""
    from pathlib import Path

    folder = Path(db_path).parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise click.BadParameter(f"cannot create the folder {str(folder)!r} of the response database: "
                                 f"{exc.strerror or exc}; give a writable --db path", param_hint="'--db'") from None


@click.group(name="experiment")
def experiment():
    """The 2AFC visual validation experiment: which image is the photograph of the real plate?"""


@experiment.command()
@click.argument("pairs_toml", type=click.Path(dir_okay=False))
@click.option("--db", "db_path", required=True, type=click.Path(dir_okay=False),
              help="SQLite response database (created if absent; WAL mode).")
@click.option("--host", default="127.0.0.1", show_default=True,
              help="Interface to listen on (0.0.0.0 to let other machines in the lab connect).")
@click.option("--port", default=8000, show_default=True, type=click.IntRange(1, 65535))
@click.option("--admin-token", default=None, envvar="NMMM_EXPERIMENT_ADMIN_TOKEN",
              help="Token of the experimenter pages (/admin); random if not given. "
                   "Env: NMMM_EXPERIMENT_ADMIN_TOKEN.")
@click.option("--log-level", default="warning", show_default=True,
              type=click.Choice(["critical", "error", "warning", "info", "debug"]))
@click.option("--check", is_flag=True,
              help="Load every image, prepare the stimuli and open the database, report, then exit "
                   "without serving (a dry run before a session).")
def serve(pairs_toml, db_path, host, port, admin_token, log_level, check):
    """Serve the experiment described by PAIRS_TOML; every response is committed to --db."""
    from nmmm.experiment.app import serve as run
    from nmmm.experiment.pairs import load_pairs

    pairset = load_pairs(pairs_toml)   # a bad experiment is refused before anything is created
    _db_folder(db_path)
    if check:
        from nmmm.experiment.app import create_app

        app = create_app(pairset, db_path, admin_token=admin_token, progress=False)
        try:
            c = app.state.stimuli.counts
            click.echo(f"nmmm experiment: {len(pairset)} pair(s), {pairset.n_trials} trial(s) per participant, "
                       f"responses in {db_path}; stimuli: {c['prepared']} prepared, {c['reused']} reused; "
                       f"ready to serve on http://{host}:{port}/ (run without --check)")
        finally:
            app.state.store.close()
        return
    run(pairs_toml, db_path, host=host, port=port, admin_token=admin_token, log_level=log_level,
        echo=lambda m: click.echo(m, err=True))


@experiment.command()
@click.argument("db_path", type=click.Path(dir_okay=False))
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False), default=None,
              help="Write the forest plot (PNG, PDF or SVG).")
@click.option("--delta", default=0.1, show_default=True, type=float,
              help="Equivalence margin in proportion correct: indistinguishable if Pc is within 0.5 ± delta.")
@click.option("--alpha", default=0.05, show_default=True, type=float)
@click.option("--confidence", default=0.95, show_default=True, type=float)
@click.option("--pooling", default="cluster-robust", show_default=True,
              type=click.Choice(["cluster-robust", "beta-binomial", "naive"]))
@click.option("--alternative", default="two-sided", show_default=True,
              type=click.Choice(["two-sided", "greater", "less"]))
@click.option("--interval", "interval_method", default="Wilson", show_default=True,
              type=click.Choice(["Wilson", "Clopper-Pearson"]))
@click.option("--complete-only", is_flag=True, help="Analyse only observers who finished all their trials.")
@click.option("--json", "as_json", is_flag=True, help="Print the analysis as JSON instead of text.")
def stats(db_path, plot_path, delta, alpha, confidence, pooling, alternative, interval_method, complete_only,
          as_json):
    """Proportion correct per observer, per pair and pooled; binomial tests, d', CIs, TOST."""
    from dataclasses import asdict

    from nmmm.experiment.stats import analyse_responses, format_report, plot_analysis
    from nmmm.experiment.storage import read_responses

    analysis = analyse_responses(read_responses(db_path), delta=delta, alpha=alpha, confidence=confidence,
                                 pooling=pooling, alternative=alternative, interval_method=interval_method,
                                 complete_only=complete_only)
    if as_json:
        click.echo(json.dumps(asdict(analysis), indent=2, default=float))
    else:
        click.echo(format_report(analysis))
    if plot_path:
        plot_analysis(analysis, plot_path)
        click.echo(f"plot written to {plot_path}", err=True)


@experiment.command()
@click.argument("db_path", type=click.Path(dir_okay=False))
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False, allow_dash=True),
              help="CSV file to write ('-' for standard output).")
def export(db_path, output):
    """Write every answered trial of DB_PATH as CSV (one row per response)."""
    from nmmm.experiment.export import write_csv

    if output == "-":
        n = write_csv(db_path, click.get_text_stream("stdout"))
    else:
        n = write_csv(db_path, output)
        click.echo(f"{n} response(s) written to {os.fspath(output)}", err=True)


__all__ = ["experiment"]
