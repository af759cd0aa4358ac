"""``nmmm homogenize``: FFT homogenization from the command line.

- ``nmmm homogenize run CELL --eps 0=2.25 --eps 1=-50+20j`` — effective tensor of a
  microstructure file (TIFF/npz from ``nmmm micro generate``) for constant permittivities;
  ``--eps 1=main/Al/Rakic --wavelengths 380:780:5`` for a spectrum (``--method auto``: one
  Lanczos run per loading for a two-phase cell when cheaper, reported as a switch).
- ``nmmm homogenize demo OUTPUT_DIR`` — the hematite-coating worked example (in :mod:`nmmm.demo.cli`,
  attached to this group by :mod:`nmmm.cli`).
"""

from __future__ import annotations

import json

import click
import numpy as np


def _parse_eps(items) -> dict:
    """LABEL=EPS items: EPS a complex number (1=-50+20j) or a material of the database
    (1=main/Al/Rakic, evaluated at --wavelengths)."""
    out = {}
    for item in items:
        if "=" not in item:
            raise click.BadParameter(f"expected LABEL=EPS (e.g. 1=-50+20j or 1=main/Al/Rakic), got {item!r}")
        k, v = item.split("=", 1)
        try:
            label = int(k)
        except ValueError:
            raise click.BadParameter(f"the label of {item!r} must be an integer") from None
        if "/" in v:
            from nmmm.materials import get

            out[label] = get(v.strip())  # an unknown name: the database's NmmmError (one error: line)
            continue
        try:
            out[label] = complex(v.replace(" ", "").replace("i", "j"))
        except ValueError:
            raise click.BadParameter(f"cannot read {item!r} as LABEL=complex permittivity or LABEL=material "
                                     "(e.g. 1=main/Al/Rakic)") from None
    return out


#: The most wavelengths ``--wavelengths start:stop:step`` may make (a step typed too small).
MAX_WAVELENGTHS = 100_000


def _parse_wavelengths(text):
    """'380:780:5' (start:stop:step, inclusive, nm; finite, at most :data:`MAX_WAVELENGTHS`) or
    '450,550,650'."""
    if text is None:
        return None
    try:
        if ":" in text:
            a, b, c = (float(x) for x in text.split(":"))
            if not (np.isfinite([a, b, c]).all() and c > 0 and b >= a):
                raise ValueError
            n = int(round((b - a) / c)) + 1
            if n > MAX_WAVELENGTHS:
                raise click.BadParameter(f"--wavelengths {text!r} makes {n} wavelengths, more than "
                                         f"{MAX_WAVELENGTHS}; give a larger step")
            return np.linspace(a, a + (n - 1) * c, n)
        out = np.array([float(x) for x in text.split(",") if x.strip()])
        if out.size == 0:
            raise ValueError
        return out
    except (ValueError, OverflowError):
        raise click.BadParameter(f"--wavelengths: give 'start:stop:step' (nm, step > 0) or comma-separated "
                                 f"numbers, got {text!r}") from None


def _switch_json(sw: dict) -> dict:
    """A switch as strict JSON: numbers stay numbers, a non-finite one (a stopped solve's
    predicted_projections = inf) and anything else become strings (json.dumps would write the
    non-standard Infinity)."""
    def value(v):
        if isinstance(v, (str, bool, int)) or (isinstance(v, float) and np.isfinite(v)):
            return v
        return str(v)

    return {k: value(v) for k, v in sw.items()}


@click.group()
def homogenize():
    """FFT homogenization: effective permittivity of periodic microstructures."""


@homogenize.command("run")
@click.argument("cell", type=click.Path(exists=True, dir_okay=False))
@click.option("--eps", "eps_items", multiple=True, required=True,
              help="LABEL=EPS, e.g. 1=-50+20j, or LABEL=MATERIAL (1=main/Al/Rakic, needs --wavelengths); repeat.")
@click.option("--wavelengths", default=None, help="start:stop:step or list (nm), for materials given by name.")
@click.option("--green", default="auto", show_default=True,
              type=click.Choice(["auto", "willot2015", "willot2014", "continuous"]))
@click.option("--solver", default="cocg", show_default=True,
              type=click.Choice(["cocg", "bicgstab", "gmres", "eyre_milton", "basic"]))
@click.option("--method", default="auto", show_default=True, type=click.Choice(["auto", "per-wavelength", "lanczos"]),
              help="Spectrum: per-wavelength solves, one Lanczos run per loading (two phases), or the cheaper.")
@click.option("--tol", type=float, default=None, help="Relative residual (default 1e-6 / 1e-5 for complex64).")
@click.option("--maxiter", type=click.IntRange(min=1), default=5000, show_default=True,
              help="Projections per loading.")
@click.option("--single", is_flag=True, help="complex64 fields (half the memory).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
@click.option("--max-memory-gb", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Refuse a solve estimated above this memory (default: half the physical memory).")
@click.option("--max-minutes", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Refuse a solve estimated above this time (default 30).")
def run(cell, eps_items, wavelengths, green, solver, method, tol, maxiter, single, as_json, max_memory_gb,
        max_minutes):
    """Effective permittivity tensor of the microstructure in CELL."""
    from nmmm.homogenize.fft import fft_permittivity
    from nmmm.microstructure import load_microstructure

    ms = load_microstructure(cell)
    eps = _parse_eps(eps_items)
    wl = _parse_wavelengths(wavelengths)
    named = [k for k, v in eps.items() if not isinstance(v, complex)]
    if named and wl is None:
        raise click.BadParameter(f"--eps {named[0]}={eps[named[0]].name if hasattr(eps[named[0]], 'name') else '...'} "
                                 "is a material: give the wavelengths to evaluate it at, e.g. --wavelengths 380:780:10")
    # an InvalidInputError (a refused work estimate among them) reaches nmmm.cli.main: one
    # 'error:' line, exit 2 like every data error
    r = fft_permittivity(ms, eps, green=None if green == "auto" else green, solver=solver, tol=tol,
                         maxiter=maxiter, method=method, wavelength_nm=wl,
                         dtype="complex64" if single else "complex128", max_memory_gb=max_memory_gb,
                         max_minutes=max_minutes)
    tensors = np.asarray(r.tensor)
    spectrum = tensors.ndim == 3
    if as_json:
        out = {
            "tensor": [[[[z.real, z.imag] for z in row] for row in t] for t in tensors] if spectrum
            else [[[z.real, z.imag] for z in row] for row in tensors],
            "iterations": np.asarray(r.iterations).tolist(), "fractions": r.fractions, "green": r.green,
            "method": r.metadata.get("method"), "switches": [_switch_json(sw) for sw in r.switches],
        }
        if spectrum and wl is not None:
            out["wavelength_nm"] = np.asarray(wl).tolist()
        click.echo(json.dumps(out))
        return
    click.echo(f"grid {r.shape}, fractions {r.fractions}, Green operator {r.green}, method {r.metadata.get('method')}")
    for sw in r.switches:
        click.echo(f"switch: {sw['what']} {sw['from']} -> {sw['to']}: {sw['reason']}")
    if spectrum:
        click.echo("wavelength_nm  " + "  ".join(f"eps_{j}{j}" for j in range(tensors.shape[-1])))
        lam = np.arange(tensors.shape[0]) if wl is None else np.broadcast_to(wl, tensors.shape[:1])
        for w, t in zip(lam, tensors):
            click.echo(f"{w:10.1f}  " + "  ".join(f"{z.real:+.6f}{z.imag:+.6f}i" for z in np.diagonal(t)))
    else:
        click.echo("effective permittivity tensor:")
        for row in tensors:
            click.echo("  " + "  ".join(f"{z.real:+.6f}{z.imag:+.6f}i" for z in row))
    click.echo(f"projections per loading: {np.asarray(r.iterations).tolist()}")
