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
    """Find database entries by formula, name, synonym or phase (e.g. hematite, Fe2O3, rutile, PMMA):
    each with its wavelength range, whether it covers 380–780 nm, and its source; and the binder table."""
    from nmmm.materials.binders import find_binders
    from nmmm.materials.database import search_entries

    found = search_entries(text)
    binders = find_binders(text)
    if not found and not binders:
        raise click.ClickException(f"nothing matches {text!r} (searched keys, titles, comments, synonyms, phases "
                                   "and the binder table); try a formula such as Fe2O3 or a mineral name")
    for h in found:
        lo, hi = h.range_nm
        vis = "covers 380–780 nm" if h.covers_visible else "not all of 380–780 nm"
        click.echo(f"{h.key}\t{lo:g}–{hi:g} nm\t{vis}\t{h.name}\t[{h.matched}]\tsource: {h.source or '-'}")
    for b in binders:
        where = f"{b.range_nm[0]:g}–{b.range_nm[1]:g} nm" if b.range_nm else "no model"
        click.echo(f"binder {b.name}\t{where}\t{b.status}\t{b.chemistry}\tsource: {b.reference}")


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
