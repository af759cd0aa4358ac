"""The ``nmmm`` command line.

Each scale contributes its own ``click`` group from a ``cli`` module inside its package;
this file only lists them and imports each on demand, so that ``nmmm --help`` is fast and
a problem in one package cannot break the others' commands.
"""

from __future__ import annotations

import importlib
import sys
import warnings

import click

from nmmm.errors import NmmmError

#: command name -> "module:attribute" of a click command or group
COMMANDS: dict[str, tuple[str, str]] = {
    "materials": ("nmmm.materials.cli:materials", "Optical constants: search, show, plot."),
    "ema": ("nmmm.ema.cli:ema", "Effective-medium approximations."),
    "ellipsometry": ("nmmm.ellipsometry.cli:ellipsometry", "Fit ellipsometric data (Psi, Delta)."),
    "micro": ("nmmm.microstructure.cli:micro", "Random microstructures and SEM image analysis."),
    "homogenize": ("nmmm.homogenize.cli:homogenize", "FFT homogenization of microstructures."),
    "layers": ("nmmm.layers.cli:layers", "Mie scattering, radiative transfer, thin films."),
    "appearance": ("nmmm.appearance.cli:appearance", "BRDFs and multi-angle colour."),
    "render": ("nmmm.recipes.render_cli:render", "Spectral rendering of plates and objects."),
    "experiment": ("nmmm.experiment.cli:experiment", "The 2AFC visual validation experiment."),
    "run": ("nmmm.recipes.cli:run", "Run a TOML recipe."),
    "demo": ("nmmm.demo.cli:demo", "Run the seed paper's worked examples into one report."),
    "compare": ("nmmm.recipes.cli:compare", "Compare two recipes (substitution view)."),
    "sweep": ("nmmm.recipes.cli:sweep", "Parameter sweep of a recipe on Dask."),
    "match": ("nmmm.matching.cli:match", "Match a recipe's free keys to a measured colour."),
    "calibrate": ("nmmm.matching.cli:calibrate", "Calibrate a colourant on a measured ladder."),
}


def _with_scale_tours(name, command):
    """Attach to a scale's group its worked-example commands (``nmmm ema gold-ruby``, ...): they live
    in :mod:`nmmm.demo.cli`, since a scale package never imports the demo."""
    if isinstance(command, click.Group):
        try:
            from nmmm.demo.cli import SCALE_COMMANDS
        except ImportError:  # the demo broken: the scale's own commands still work
            return command
        for sub in SCALE_COMMANDS.get(name, ()):
            if sub.name not in command.commands:
                command.add_command(sub)
    return command


class LazyGroup(click.Group):
    """A click group whose sub-commands are imported only when used."""

    def list_commands(self, ctx):
        return sorted(COMMANDS)

    def get_command(self, ctx, name):
        if name not in COMMANDS:
            return None
        target, help_text = COMMANDS[name]
        module_name, attr = target.split(":")
        try:
            module = importlib.import_module(module_name)
            return _with_scale_tours(name, getattr(module, attr))
        except (ImportError, AttributeError) as exc:
            reason = str(exc)  # `exc` itself is unbound once the except block ends

            @click.command(name=name, help=f"{help_text} (unavailable: {reason})")
            def unavailable():
                raise click.ClickException(f"'nmmm {name}' is not available: {reason}")

            return unavailable


@click.group(cls=LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="nmmm")
def cli():
    """nmmm — predictive colour and appearance, from nano to macro.

    Wavelengths are in nm, lengths in nm, angles in degrees, fractions in [0, 1].
    """


#: the prefix of every one-line usage or data error of the ``nmmm`` command
ERROR_PREFIX = "error: "
#: the prefix of every warning the ``nmmm`` command prints
WARNING_PREFIX = "warning: "


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def _os_error_line(exc: OSError) -> str:
    where = f"{exc.filename!r}: " if getattr(exc, "filename", None) else ""
    return f"{where}{exc.strerror or exc}"


def main(argv=None):
    """Entry point of the ``nmmm`` console script: one voice for every error.

    Usage and data errors (click's usage errors, every :class:`~nmmm.errors.NmmmError`, recipe
    errors included) print one line ``error: <what is wrong and what would be right>`` on stderr
    and exit with status 2. A failure of the system rather than of the input (a full disk, an
    unreadable folder, too little memory) prints one ``error:`` line too and exits with 1. A
    command's own failure status (``nmmm demo`` with a failed section) keeps its exit 1.
    A warning is one line ``warning: <message>`` on stderr (not Python's file, line and source).
    """
    with warnings.catch_warnings():  # the hook is restored when the command ends
        warnings.showwarning = _show_warning
        return _main(argv)


def _show_warning(message, category, filename, lineno, file=None, line=None):
    """``warnings.showwarning`` of the command line: one ``warning:`` line on stderr."""
    click.echo(WARNING_PREFIX + _one_line(message), err=True)


def _main(argv):
    try:
        cli.main(args=argv, standalone_mode=False)
    except click.exceptions.Abort:
        click.echo("Aborted.", err=True)
        return 1
    except click.exceptions.Exit as exc:
        return exc.exit_code
    except click.UsageError as exc:
        hint = f" (see '{exc.ctx.command_path} --help')" if exc.ctx is not None else ""
        click.echo(ERROR_PREFIX + _one_line(exc.format_message()) + hint, err=True)
        return 2
    except click.ClickException as exc:
        click.echo(ERROR_PREFIX + _one_line(exc.format_message()), err=True)
        return exc.exit_code
    except NmmmError as exc:
        click.echo(ERROR_PREFIX + _one_line(exc), err=True)
        return 2
    except MemoryError:
        click.echo(ERROR_PREFIX + "not enough memory for this input; use a coarser grid or fewer points", err=True)
        return 1
    except RecursionError:
        click.echo(ERROR_PREFIX + "an input nested too deep to read; a valid file nests a few levels", err=True)
        return 2
    except UnicodeDecodeError as exc:
        click.echo(ERROR_PREFIX + f"a file is not UTF-8 text (byte {exc.start}); save it as UTF-8", err=True)
        return 2
    except OSError as exc:
        click.echo(ERROR_PREFIX + _os_error_line(exc), err=True)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())


def run_main():
    """Console-script wrapper: exit with :func:`main`'s status."""
    sys.exit(main())
