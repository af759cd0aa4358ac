"""``nmmm materials``: search the database, show and plot a material's n and k."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np


@click.group()
def materials():
    """Optical constants: search, show, plot."""


@materials.command()
@click.argument("text")
def search(text):
    """List database keys containing TEXT (e.g. Fe2O3)."""
    from nmmm.materials.database import search as _search

    found = _search(text)
    if not found:
        raise click.ClickException(f"no key contains {text!r}")
    for k in found:
        click.echo(k)


def _load(key):
    from nmmm.materials.database import get
    from nmmm.materials.files import read_csv, read_yaml

    p = Path(key)
    if p.suffix.lower() == ".csv":
        return read_csv(p)
    if p.suffix.lower() in (".yml", ".yaml"):
        return read_yaml(p)
    return get(key)


@materials.command()
@click.argument("key")
@click.option("--points", default=9, show_default=True, type=click.IntRange(1, 100_000),
              help="rows of n, k to print (1 to 100 000)")
def show(key, points):
    """Show KEY (database key, .csv or .yml file): range, reference, sample of n and k."""
    m = _load(key)
    lo, hi = m.range_nm
    click.echo(f"{m.name}\n  range: {lo:g}–{hi:g} nm\n  reference: {m.reference or '-'}")
    w = np.geomspace(lo, hi, points) if hi / lo > 20 else np.linspace(lo, hi, points)
    nk = m.nk(w)
    click.echo(f"  {'wavelength_nm':>14} {'n':>10} {'k':>10}")
    for wi, v in zip(w, nk):
        click.echo(f"  {wi:14.2f} {v.real:10.5f} {v.imag:10.5f}")


@materials.command()
@click.argument("keys", nargs=-1, required=True)
@click.option("-o", "--output", type=click.Path(dir_okay=False), required=True, help="PNG file")
@click.option("--range-nm", nargs=2, type=float, default=None, help="wavelength range (nm)")
def plot(keys, output, range_nm):
    """Plot n and k of one or more KEYS against wavelength into a PNG."""
    from nmmm.materials.plotting import plot_nk

    mats = [_load(k) for k in keys]
    path = plot_nk(mats, output, range_nm=range_nm)
    click.echo(f"wrote {path}")
