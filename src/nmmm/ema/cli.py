"""``nmmm ema`` — effective media from the command line.

- ``nmmm ema methods`` — the registered methods.
- ``nmmm ema mix --host KEY --inclusion KEY:FRACTION[:SHAPE[:RADIUS_NM]] ...`` — n, k of the
  mixture on a wavelength grid (CSV to stdout or ``-o``). SHAPE: ``sphere``, ``cube``,
  ``spheroid=ASPECT`` (random orientation).
- ``nmmm ema gold-ruby -o DIR`` — the seed's gold-ruby glass example (figures + tables; the command
  lives in :mod:`nmmm.demo.cli` and is attached to this group by :mod:`nmmm.cli`).
"""

from __future__ import annotations

import click

from nmmm.errors import InvalidInputError


def _parse_shape(text):
    from nmmm.ema.shapes import Shape

    text = text.strip().lower()
    if text in ("", "sphere"):
        return Shape.sphere()
    if text == "cube":
        return Shape.cube()
    if text.startswith("spheroid="):
        return Shape.spheroid(_number(text.split("=", 1)[1], "spheroid ASPECT_RATIO"))
    raise InvalidInputError(f"unknown shape {text!r}; use sphere, cube or spheroid=ASPECT_RATIO")


def _parse_inclusion(spec):
    from nmmm.ema.mixtures import Inclusion
    from nmmm.materials import get

    parts = spec.split(":")
    # database keys contain '/', not ':'; KEY:FRACTION[:SHAPE[:RADIUS]]
    if len(parts) < 2:
        raise click.BadParameter(f"{spec!r}: expected KEY:FRACTION[:SHAPE[:RADIUS_NM]]")
    radius = _number(parts[3], f"{spec!r}: RADIUS_NM") if len(parts) > 3 and parts[3] else None
    fraction = _number(parts[1], f"{spec!r}: FRACTION")
    return Inclusion(get(parts[0]), fraction, _parse_shape(parts[2] if len(parts) > 2 else ""), radius)


def _number(text: str, what: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise click.BadParameter(f"{what} must be a number, got {text[:20]!r} (e.g. KEY:0.05:sphere:20)",
                                 param_hint="'--inclusion'") from None


@click.group()
def ema():
    """Effective-medium approximations (Maxwell Garnett, Bruggeman, shapes, size)."""


@ema.command("methods")
def methods():
    """List the effective-medium methods of the registry."""
    from nmmm.ema.registry import EFFECTIVE_PERMITTIVITY_METHODS

    for name, fn in EFFECTIVE_PERMITTIVITY_METHODS.items():
        doc = (fn.__doc__ or "").strip().splitlines()
        click.echo(f"{name:28s} {doc[0] if doc else ''}")


@ema.command("mix")
@click.option("--host", required=True, help="database key of the host, e.g. main/SiO2/Malitson")
@click.option("--inclusion", "inclusions", multiple=True, required=True,
              help="KEY:FRACTION[:SHAPE[:RADIUS_NM]], e.g. main/Au/Johnson:0.0005:sphere")
@click.option("--method", default="maxwell_garnett", show_default=True)
@click.option("--start-nm", default=380.0, show_default=True)
@click.option("--stop-nm", default=780.0, show_default=True)
@click.option("--step-nm", default=5.0, show_default=True)
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="CSV file (default: stdout)")
def mix_cmd(host, inclusions, method, start_nm, stop_nm, step_nm, output):
    """n and k of an effective medium on a wavelength grid."""
    from nmmm.ema.mixtures import mix
    from nmmm.materials import get
    from nmmm.spectra import wavelength_grid

    m = mix(get(host), [_parse_inclusion(s) for s in inclusions], method=method)
    w = wavelength_grid(start_nm, stop_nm, step_nm)
    nk = m.nk(w)
    lines = ["wavelength_nm,n,k"] + [f"{a:g},{b.real:.8g},{b.imag:.8g}" for a, b in zip(w, nk)]
    text = "\n".join(lines) + "\n"
    if output:
        with open(output, "w") as fh:
            fh.write(text)
        click.echo(f"wrote {output} ({m.name})")
    else:
        click.echo(text, nl=False)


__all__ = ["ema"]
