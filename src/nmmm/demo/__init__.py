"""nmmm.demo — ``nmmm demo``: the seed paper's worked examples, one module each, into one report.

The top floor but one (it may import from every scale; no scale imports it):

- :mod:`~nmmm.demo.sections` — the registry: the shipped recipes run and the hooks below.
- :mod:`~nmmm.demo.runner` — :func:`run_demo` / :func:`run_sections`: every section guarded, one
  self-contained HTML report; failures told with what to install.
- :mod:`~nmmm.demo.cli` — the ``nmmm demo`` command and the scales' tour commands.

Seed examples: :mod:`~nmmm.demo.gold_ruby` (1, gold-ruby glass), :mod:`~nmmm.demo.hematite`
(2, hematite paint), :mod:`~nmmm.demo.interference` (4, mica pigments), :mod:`~nmmm.demo.experiment`
(5, 2AFC validation). Tours of the scales: :mod:`~nmmm.demo.materials`,
:mod:`~nmmm.demo.microstructure`, :mod:`~nmmm.demo.homogenization`, :mod:`~nmmm.demo.ellipsometry`,
:mod:`~nmmm.demo.appearance` (3 and 4, effect paints), :mod:`~nmmm.demo.rendering` (3, the grey
metallic plate).

Each hook is ``hook(output_dir) -> {"title", "figures", "tables", "text"}`` (those that draw progress
bars also take ``progress``).
"""


def __getattr__(name):  # the runner on demand (keeps `import nmmm.demo` light)
    if name in ("run_demo", "run_sections"):
        from nmmm.demo import runner

        return getattr(runner, name)
    raise AttributeError(f"module 'nmmm.demo' has no attribute {name!r}")


__all__ = ["run_demo", "run_sections"]
