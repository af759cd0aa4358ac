"""Click commands of the demo (mapped from :mod:`nmmm.cli`).

- ``nmmm demo`` (:func:`demo`) — every section into one HTML report; after it, one block per failed
  section (its title, the exception's last line, what to install) and exit status 1.
- The scales' tours, attached to their groups by :mod:`nmmm.cli` (a scale package never imports
  the demo): ``nmmm ema gold-ruby``, ``nmmm layers hematite``, ``nmmm homogenize demo``,
  ``nmmm appearance demo``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import click

__all__ = ["demo", "gold_ruby", "hematite", "homogenize_demo", "appearance_demo", "SCALE_COMMANDS"]


def failure_report(failures) -> str:
    """The terminal text telling each failed section: title, the exception's last line, a hint."""
    blocks = []
    for f in failures:
        lines = [f"FAILED  {f.title}", f"  error: {f.error}"]
        lines.append(f"  hint:  {f.hint}" if f.hint else f"  hint:  see the error box of this section in the report "
                                                           f"(hook {f.target})")
        blocks.append("\n".join(lines))
    return "\n\n".join(blocks)


@click.command("demo")
@click.option("-o", "--output", "output", default="nmmm-demo", show_default=True, help="Output folder.")
@click.option("--quick", is_flag=True, help="Only the shipped recipes (skip the packages' demo hooks).")
@click.option("--only", multiple=True, help="Run only sections whose name contains this text (repeatable).")
@click.option("--no-progress", is_flag=True, help="Hide progress messages.")
def demo(output, quick, only, no_progress):
    """Run the seed paper's worked examples into one HTML report."""
    from nmmm.demo.runner import run_sections
    from nmmm.recipes.cli import _output_dir

    run = run_sections(_output_dir(output), quick=quick, only=only or None, progress=not no_progress)
    click.echo(f"report: {Path(run.report).resolve()}")
    if run.skipped:
        click.echo("not available: " + ", ".join(run.skipped))
    if run.failures:
        click.echo("\n" + failure_report(run.failures) + "\n", err=True)
        click.echo(f"{len(run.failures)} section(s) failed: " + "; ".join(run.failed), err=True)
        sys.exit(1)


def _echo_summary(out, prefix):
    click.echo(out["text"])
    for p in out["figures"]:
        click.echo(f"{prefix}{p}")


@click.command("gold-ruby")
@click.option("-o", "--output-dir", default="gold_ruby", show_default=True, type=click.Path(file_okay=False))
def gold_ruby(output_dir):
    """The seed's gold-ruby glass example: n, k vs silica, transmission, colours, rods."""
    from nmmm.demo.gold_ruby import gold_ruby_demo

    _echo_summary(gold_ruby_demo(output_dir), "figure: ")


@click.command("hematite")
@click.option("-o", "--output-dir", default="hematite", show_default=True, type=click.Path(file_okay=False))
def hematite(output_dir):
    """The seed's hematite paint: 5/7/10 %, grain-size darkening, KM vs AD (figures + tables)."""
    from nmmm.demo.hematite import hematite_demo

    _echo_summary(hematite_demo(output_dir), "figure: ")


@click.command("demo")
@click.argument("output_dir", type=click.Path(file_okay=False))
def homogenize_demo(output_dir):
    """Hematite coating at 5/7/10 %: FFT vs Maxwell Garnett, Bruggeman, HS bounds."""
    from nmmm.demo.homogenization import demo as run

    _echo_summary(run(output_dir), "wrote ")


@click.command("demo")
@click.argument("output_dir", type=click.Path(file_okay=False))
def appearance_demo(output_dir):
    """Worked examples: multi-angle colour, colour travel, BRDF plots, sparkle."""
    from nmmm.demo.appearance import demo as run

    _echo_summary(run(output_dir), "  ")


#: scale group -> the tour commands :mod:`nmmm.cli` attaches to it
SCALE_COMMANDS = {
    "ema": (gold_ruby,),
    "layers": (hematite,),
    "homogenize": (homogenize_demo,),
    "appearance": (appearance_demo,),
}
