"""``nmmm homogenize``: FFT homogenization from the command line.

- ``nmmm homogenize run CELL --eps 0=2.25 --eps 1=-50+20j`` — effective tensor of a
  microstructure file (TIFF/npz from ``nmmm micro generate``) for constant permittivities.
- ``nmmm homogenize demo OUTPUT_DIR`` — the hematite-coating worked example (in :mod:`nmmm.demo.cli`,
  attached to this group by :mod:`nmmm.cli`).
"""

from __future__ import annotations

import json

import click
import numpy as np


def _parse_eps(items) -> dict:
    out = {}
    for item in items:
        if "=" not in item:
            raise click.BadParameter(f"expected LABEL=EPS (e.g. 1=-50+20j), got {item!r}")
        k, v = item.split("=", 1)
        try:
            out[int(k)] = complex(v.replace(" ", "").replace("i", "j"))
        except ValueError:
            raise click.BadParameter(f"cannot read {item!r} as LABEL=complex permittivity") from None
    return out


@click.group()
def homogenize():
    """FFT homogenization: effective permittivity of periodic microstructures."""


@homogenize.command("run")
@click.argument("cell", type=click.Path(exists=True, dir_okay=False))
@click.option("--eps", "eps_items", multiple=True, required=True, help="LABEL=EPS, e.g. 1=-50+20j (repeat).")
@click.option("--green", default="willot2015", show_default=True,
              type=click.Choice(["willot2015", "willot2014", "continuous"]))
@click.option("--solver", default="cocg", show_default=True,
              type=click.Choice(["cocg", "bicgstab", "gmres", "eyre_milton", "basic"]))
@click.option("--tol", type=float, default=None, help="Relative residual (default 1e-6 / 1e-5 for complex64).")
@click.option("--single", is_flag=True, help="complex64 fields (half the memory).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
@click.option("--max-memory-gb", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Refuse a solve estimated above this memory (default: half the physical memory).")
@click.option("--max-minutes", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Refuse a solve estimated above this time (default 30).")
def run(cell, eps_items, green, solver, tol, single, as_json, max_memory_gb, max_minutes):
    """Effective permittivity tensor of the microstructure in CELL."""
    from nmmm.homogenize.fft import fft_permittivity
    from nmmm.microstructure import load_microstructure

    ms = load_microstructure(cell)
    eps = _parse_eps(eps_items)
    # an InvalidInputError (a refused work estimate among them) reaches nmmm.cli.main: one
    # 'error:' line, exit 2 like every data error
    r = fft_permittivity(ms, eps, green=green, solver=solver, tol=tol,
                         dtype="complex64" if single else "complex128", max_memory_gb=max_memory_gb,
                         max_minutes=max_minutes)
    if as_json:
        click.echo(json.dumps({
            "tensor": [[[z.real, z.imag] for z in row] for row in np.asarray(r.tensor)],
            "iterations": np.asarray(r.iterations).tolist(), "fractions": r.fractions, "green": r.green,
        }))
        return
    click.echo(f"grid {r.shape}, fractions {r.fractions}, Green operator {r.green}")
    click.echo("effective permittivity tensor:")
    for row in np.asarray(r.tensor):
        click.echo("  " + "  ".join(f"{z.real:+.6f}{z.imag:+.6f}i" for z in row))
    click.echo(f"projections per loading: {np.asarray(r.iterations).tolist()}")
