"""Export of a paint BRDF over Rusinkiewicz coordinates (θ_h, θ_d, φ_d) for renderers:
:func:`rusinkiewicz_to_directions`, :func:`brdf_table` (an xarray Dataset) and
:func:`write_brdf_table` (netCDF or CSV).

References
----------
- S. Rusinkiewicz, "A new change of variables for efficient BRDF representation",
  EGWR 1998 — (θ_h, θ_d, φ_d) coordinates.
- W. Matusik, H. Pfister, M. Brand, L. McMillan, ACM TOG 22(3) (2003) 759 — MERL
  tables (θ_h sampled as the square of a uniform variable).
"""

from __future__ import annotations

import numpy as np

from nmmm.appearance.brdf.paint_brdf import PaintBRDF
from nmmm.errors import InvalidInputError
from nmmm.spectra import as_wavelength_nm

__all__ = ["rusinkiewicz_to_directions", "brdf_table", "write_brdf_table"]


def rusinkiewicz_to_directions(theta_h_deg, theta_d_deg, phi_d_deg):
    """(θ_h, θ_d, φ_d) -> (wi, wo) unit vectors (..., 3), φ_h = 0 (isotropic BRDFs;
    Rusinkiewicz 1998). Pairs with a direction below the surface have z < 0."""
    th, td, pd = np.broadcast_arrays(*(np.radians(np.asarray(v, float)) for v in (theta_h_deg, theta_d_deg, phi_d_deg)))
    d = np.stack([np.sin(td) * np.cos(pd), np.sin(td) * np.sin(pd), np.cos(td)], axis=-1)
    dm = d * np.array([-1.0, -1.0, 1.0])
    c, s = np.cos(th)[..., None], np.sin(th)[..., None]

    def rot_y(v):  # rotate about the y (binormal) axis by θ_h
        return np.stack([c[..., 0] * v[..., 0] + s[..., 0] * v[..., 2], v[..., 1],
                         -s[..., 0] * v[..., 0] + c[..., 0] * v[..., 2]], axis=-1)

    return rot_y(d), rot_y(dm)


def brdf_table(brdf: PaintBRDF, wavelength_nm, n_theta_h: int = 90, n_theta_d: int = 90, n_phi_d: int = 36,
               reduce: str | None = "mean"):
    """Tabulate a BRDF over Rusinkiewicz coordinates for renderers.

    θ_h is sampled as 90°·(i/(n−1))² (MERL, Matusik et al. 2003) to resolve the specular
    peak, θ_d uniformly in [0, 90°), φ_d uniformly in [0, 180°) (isotropic, reciprocal
    BRDFs are symmetric in φ_d ↔ φ_d + 180°). With ``reduce="mean"`` the table is
    averaged over φ_d (the bivariate (θ_h, θ_d, λ) form), over the pairs above the
    surface; ``reduce=None`` keeps φ_d. Returns an :class:`xarray.Dataset` with
    ``brdf`` (1/sr) and, for a smooth coat, ``specular_reflectance`` (θ_d, λ): the weight
    of the mirror Dirac at θ_h = 0, θ_i = θ_d.
    """
    import xarray as xr

    w = as_wavelength_nm(wavelength_nm).ravel()
    for v, nm in ((n_theta_h, "n_theta_h"), (n_theta_d, "n_theta_d"), (n_phi_d, "n_phi_d")):
        if int(v) < 1:
            raise InvalidInputError(f"{nm} must be >= 1, got {v!r}")
    th = 90.0 * (np.arange(n_theta_h) / max(n_theta_h - 1, 1)) ** 2
    th = np.minimum(th, 89.9)
    td = np.linspace(0.0, 90.0, n_theta_d, endpoint=False)
    pd = np.linspace(0.0, 180.0, n_phi_d, endpoint=False)
    TH, TD, PD = np.meshgrid(th, td, pd, indexing="ij")
    wi, wo = rusinkiewicz_to_directions(TH, TD, PD)
    valid = (wi[..., 2] > 1e-9) & (wo[..., 2] > 1e-9)
    vals = np.full(TH.shape + (w.size,), np.nan)
    vals[valid] = brdf.evaluate(w, wi[valid], wo[valid])
    if reduce == "mean":
        cnt = valid.sum(axis=2)
        with np.errstate(invalid="ignore"):
            table = np.nansum(vals, axis=2) / np.where(cnt > 0, cnt, np.nan)[..., None]
        da = xr.DataArray(table, dims=("theta_h_deg", "theta_d_deg", "wavelength_nm"),
                          coords={"theta_h_deg": th, "theta_d_deg": td, "wavelength_nm": w})
    elif reduce is None:
        da = xr.DataArray(vals, dims=("theta_h_deg", "theta_d_deg", "phi_d_deg", "wavelength_nm"),
                          coords={"theta_h_deg": th, "theta_d_deg": td, "phi_d_deg": pd, "wavelength_nm": w})
    else:
        raise InvalidInputError(f"reduce must be 'mean' or None, got {reduce!r}")
    da.attrs.update(units="1/sr", description="spectral BRDF, Rusinkiewicz coordinates, phi_h = 0")
    ds = xr.Dataset({"brdf": da})
    if brdf.coat.roughness == 0:
        tdc = np.minimum(td, 89.9)
        wi_s = np.stack([np.sin(np.radians(tdc)), 0 * tdc, np.cos(np.radians(tdc))], -1)
        ds["specular_reflectance"] = xr.DataArray(brdf.specular_reflectance(w, wi_s), dims=("theta_d_deg", "wavelength_nm"),
                                                  attrs={"description": "weight of the mirror Dirac (Fresnel) at theta_h = 0"})
    ds.attrs.update(model=repr(brdf), generator="nmmm.appearance.brdf.brdf_table",
                    theta_h_sampling="90*(i/(n-1))**2 deg (MERL)")
    return ds


def write_brdf_table(path, brdf: PaintBRDF, wavelength_nm, **kwargs):
    """Write :func:`brdf_table` to ``path``: netCDF (``.nc``, h5netcdf engine) or CSV
    (``.csv``: columns theta_h_deg, theta_d_deg, wavelength_nm, brdf_per_sr)."""
    from pathlib import Path

    from nmmm.errors import DataFileError

    p = Path(path)
    if p.suffix not in (".nc", ".csv"):
        raise InvalidInputError(f"unknown table format '{p.suffix}'; use .nc or .csv")
    if not p.parent.is_dir():
        raise DataFileError(f"cannot write {p}: the directory {p.parent} does not exist; create it first")
    ds = brdf_table(brdf, wavelength_nm, **kwargs)
    if p.suffix == ".nc":
        ds.to_netcdf(p, engine="h5netcdf")
    else:
        df = ds["brdf"].to_dataframe(name="brdf_per_sr").reset_index()
        df.to_csv(p, index=False, float_format="%.6g")
    return p
