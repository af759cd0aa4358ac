"""``nmmm layers`` — Mie scattering, paint films and thin-film stacks from the command line.

- ``nmmm layers mie --particle 2.9+0.1j --medium 1.5 --diameter-nm 250`` — Mie efficiencies
  ``qext, qsca, qabs, qback, g`` on a wavelength grid (one row per wavelength × diameter).
- ``nmmm layers film --pigment KEY_OR_NK --binder KEY_OR_NK --diameter-nm 250
  --fraction 0.07 --thickness-um 20`` — reflectance of a pigmented film (Kubelka–Munk with
  Saunderson and adding–doubling side by side), and the CIELAB of each under D65.
- ``nmmm layers stack --layer 2.4:100 --layer 1.46:5000:i --substrate 1.52 --angle-deg 0
  --angle-deg 45`` — Rs, Rp, Ts, Tp, R, T of a layer stack (``:i`` marks an incoherent layer).
- ``nmmm layers hematite -o DIR`` — the seed's hematite paint example (figures + tables; in
  :mod:`nmmm.demo.cli`, attached to this group by :mod:`nmmm.cli`).

An index is a complex number written ``n+kj`` or ``n+ki`` (``k >= 0``) or a database key
such as ``main/TiO2/Siefke`` (:func:`nmmm.materials.get`). Results are CSV, to stdout or to
``-o FILE``.
"""

from __future__ import annotations

import click
import numpy as np

from nmmm.errors import InvalidInputError

_GRID = [
    click.option("--start-nm", default=380.0, show_default=True, help="first wavelength (nm)"),
    click.option("--stop-nm", default=780.0, show_default=True, help="last wavelength (nm)"),
    click.option("--step-nm", default=10.0, show_default=True, help="wavelength step (nm)"),
    click.option("-o", "--output", type=click.Path(dir_okay=False), help="CSV file (default: stdout)"),
]


def _grid_options(fn):
    for opt in reversed(_GRID):
        fn = opt(fn)
    return fn


def parse_index(text: str):
    """A complex index ``n+kj`` / ``n+ki`` / ``n``, or a database key (contains ``/``)."""
    text = str(text).strip()
    if "/" in text:
        from nmmm.materials import get

        return get(text)
    try:
        return complex(text.replace("i", "j").replace(" ", ""))
    except ValueError:
        raise InvalidInputError(
            f"{text!r} is neither a refractive index (e.g. 1.5 or 2.9+0.1j) nor a database key "
            "(e.g. main/TiO2/Siefke)"
        ) from None


def _emit(header, rows, output):
    lines = [",".join(header)] + [",".join(f"{v:.8g}" for v in row) for row in rows]
    text = "\n".join(lines) + "\n"
    if output:
        with open(output, "w") as fh:
            fh.write(text)
        click.echo(f"wrote {output} ({len(rows)} rows)")
    else:
        click.echo(text, nl=False)


@click.group()
def layers():
    """Mie scattering, paint films (Kubelka-Munk, adding-doubling) and thin-film stacks."""


@layers.command("mie")
@click.option("--particle", required=True, help="particle index n+kj or database key")
@click.option("--medium", default="1.0", show_default=True, help="real host index or database key")
@click.option("--diameter-nm", "diameters", multiple=True, type=float, required=True,
              help="sphere diameter (nm); repeat for several")
@_grid_options
def mie_cmd(particle, medium, diameters, start_nm, stop_nm, step_nm, output):
    """Mie efficiencies of homogeneous spheres over a wavelength grid."""
    from nmmm.layers.mie_scattering import mie
    from nmmm.spectra import wavelength_grid

    w = wavelength_grid(start_nm, stop_nm, step_nm)
    d = np.asarray(diameters, dtype=float)
    n_p, n_m = parse_index(particle), parse_index(medium)
    if hasattr(n_p, "nk"):
        n_p = n_p.nk(w)
    if hasattr(n_m, "nk"):
        n_m = n_m.nk(w)
    n_p = np.broadcast_to(np.asarray(n_p), w.shape)[:, None]
    n_m = np.broadcast_to(np.asarray(n_m), w.shape)[:, None]
    r = mie(n_p, n_m, d[None, :], w[:, None])
    rows = [
        (w[i], d[j], r.qext[i, j], r.qsca[i, j], r.qabs[i, j], r.qback[i, j], r.g[i, j])
        for i in range(w.size)
        for j in range(d.size)
    ]
    _emit(["wavelength_nm", "diameter_nm", "qext", "qsca", "qabs", "qback", "g"], rows, output)


@layers.command("film")
@click.option("--pigment", required=True, help="pigment index n+kj or database key")
@click.option("--binder", default="1.5", show_default=True, help="binder index n+kj or database key")
@click.option("--diameter-nm", required=True, type=float, help="(median) equivalent-sphere diameter (nm)")
@click.option("--geometric-std", default=1.0, show_default=True, help="log-normal sigma_g (1 = monodisperse)")
@click.option("--fraction", required=True, type=float, help="pigment volume fraction in [0, 1]")
@click.option("--thickness-um", default=float("inf"), show_default=True, help="film thickness (um); inf = opaque")
@click.option("--substrate-reflectance", default=0.0, show_default=True, help="Lambertian substrate under the film")
@click.option("--clear-coat-um", default=0.0, show_default=True, help="clear coat of the binder on top (um)")
@click.option("--dependent", is_flag=True, help="Percus-Yevick dependent-scattering correction")
@_grid_options
def film_cmd(pigment, binder, diameter_nm, geometric_std, fraction, thickness_um, substrate_reflectance,
             clear_coat_um, dependent, start_nm, stop_nm, step_nm, output):
    """Reflectance of a pigmented film: Kubelka-Munk/Saunderson and adding-doubling."""
    from nmmm.layers.distributions import lognormal
    from nmmm.layers.paint import PaintFilm, compare_km_ad
    from nmmm.spectra import wavelength_grid

    w = wavelength_grid(start_nm, stop_nm, step_nm)
    film = PaintFilm(
        parse_index(pigment),
        parse_index(binder),
        lognormal(diameter_nm, geometric_std),
        fraction,
        thickness_um * 1e3,
        substrate_reflectance=substrate_reflectance,
        clear_coat_thickness_nm=clear_coat_um * 1e3,
        dependent_scattering=dependent,
    )
    c = compare_km_ad(film, w)
    _emit(["wavelength_nm", "R_km", "R_ad"], list(zip(w, c["km"], c["ad"])), output)
    for name in ("km", "ad"):
        L, a, b = np.asarray(c[f"lab_{name}"], dtype=float).ravel()[:3]
        click.echo(f"# CIELAB (D65, 2 deg) {name}: L*={L:.2f} a*={a:.2f} b*={b:.2f}", err=True)
    click.echo(
        f"# KM vs AD: max |dR| = {c['max_abs_difference']:.4f} at {c['at_wavelength_nm']:g} nm, "
        f"dE00 = {c['delta_e2000']:.2f}",
        err=True,
    )


def _parse_layer(spec: str):
    parts = spec.split(":")
    if len(parts) not in (2, 3):
        raise click.BadParameter(f"{spec!r}: expected INDEX:THICKNESS_NM[:i]")
    coherent = True
    if len(parts) == 3:
        if parts[2] not in ("c", "i"):
            raise click.BadParameter(f"{spec!r}: the third field must be 'c' (coherent) or 'i' (incoherent)")
        coherent = parts[2] == "c"
    try:
        thickness = float(parts[1])
    except ValueError:
        raise click.BadParameter(f"{spec!r}: thickness {parts[1]!r} is not a number (nm)") from None
    return (parse_index(parts[0]), thickness, coherent)


@layers.command("stack")
@click.option("--layer", "layer_specs", multiple=True,
              help="INDEX:THICKNESS_NM[:i], top first; ':i' = incoherent (thick) layer")
@click.option("--ambient", default="1.0", show_default=True, help="incidence medium")
@click.option("--substrate", default="1.52", show_default=True, help="exit medium")
@click.option("--angle-deg", "angles", multiple=True, type=float, default=(0.0,), show_default=True,
              help="angle of incidence (deg); repeat for several")
@_grid_options
def stack_cmd(layer_specs, ambient, substrate, angles, start_nm, stop_nm, step_nm, output):
    """Reflectance and transmittance (s, p, unpolarized) of a layer stack."""
    from nmmm.layers.thinfilm import Stack
    from nmmm.spectra import wavelength_grid

    w = wavelength_grid(start_nm, stop_nm, step_nm)
    a = np.asarray(angles, dtype=float)
    st = Stack([_parse_layer(s) for s in layer_specs], ambient=parse_index(ambient), substrate=parse_index(substrate))
    r = st.rt(w, a)
    rows = [
        (w[i], a[j], r.Rs[i, j], r.Rp[i, j], r.Ts[i, j], r.Tp[i, j], r.R[i, j], r.T[i, j])
        for i in range(w.size)
        for j in range(a.size)
    ]
    _emit(["wavelength_nm", "angle_deg", "Rs", "Rp", "Ts", "Tp", "R", "T"], rows, output)


__all__ = ["layers", "parse_index"]
