"""Discrete flakes under the paint's coat ↔ the statistical flake lobe: each flake's mirror
direction and spectral power (:func:`flake_list_reflection`), and the BRDF estimated from
them on angular bins (:func:`binned_flake_brdf`), whose mean over many flakes is the
``"flakes"`` term of :class:`~nmmm.appearance.brdf.PaintBRDF`.
"""

from __future__ import annotations

import numpy as np

from nmmm.appearance.brdf.interpolation import _NT, _deg, _lerp1, _lerp_table
from nmmm.appearance.brdf.paint_brdf import PaintBRDF
from nmmm.appearance.flakes import FlakeList, check_directions, refract_in, refract_out
from nmmm.errors import InvalidInputError

__all__ = ["flake_list_reflection", "binned_flake_brdf"]


def flake_list_reflection(paint: PaintBRDF, flakes: FlakeList, wavelength_nm, wi):
    """Reflection of light from ``wi`` by each flake of a :class:`FlakeList` under the
    paint's clear coat.

    Returns ``(wo, power, escapes)``: the external mirror directions (N, 3), the fraction
    of the irradiance on the patch that each flake sends out (N, L) — coat transmission
    in and out, flake reflectance at its local angle, projected area, and mean-field
    attenuation exp(−S τ_above) by the flakes above it (τ_above the flake area above the
    flake's depth per unit area, :meth:`FlakeList.optical_depth_above`; for flakes that
    transmit S is the paint's extinction per direction, a(μ)(1 − T̄(μ, λ))/μ in and out, the
    BRDF's ``_Tables.optical_path`` / τ) — and the mask of flakes whose light leaves the coat.
    Because Σ_k A_k exp(−S τ_above,k) / area → (1 − e^{−Sτ})/S whatever the depth
    distribution, the mean of the discrete flakes is the statistical flake lobe.
    The average of these contributions over many flakes is the ``"flakes"`` term of the
    statistical BRDF built from ``flakes.to_flake_layer()``.
    """
    tab = paint.prepare(wavelength_nm)
    wi = check_directions(np.asarray(wi, float).reshape(3), "wi")
    if abs(tab.n - flakes.n_binder) > 1e-6:
        raise InvalidInputError(
            f"the flake list's binder index ({flakes.n_binder}) differs from the coat's ({tab.n:.6g}); "
            "use the same medium"
        )
    n = tab.n
    ip = refract_in(wi, n)
    c = flakes.normals @ ip
    op = 2 * c[:, None] * flakes.normals - ip
    wo, esc = refract_out(op, n)
    esc = esc & (c > 0)
    Ti = _lerp_table(tab.Tc, np.atleast_1d(_deg(wi[2])), tab.step)[0]
    To = _lerp_table(tab.Tc, _deg(np.clip(wo[:, 2], 0, 1)), tab.step)
    R, _ = flakes.optics.rt(np.clip(c, 1e-6, 1), tab.w, n)
    tau_above = flakes.optical_depth_above()
    tilt = flakes.tilt
    if tilt is None:
        tilt = flakes.to_flake_layer().tilt
    if tab.has_flakes and tilt is tab.tilt:
        a_tab = tab.a_tab
    else:
        a_tab = np.asarray(tilt.projected_mean(np.cos(np.radians(np.linspace(0.0, 90.0, _NT)))), float)
    opz = np.clip(op[:, 2], 1e-6, 1)
    if paint.flakes is not None and tab.has_flakes and not tab.tau_e_const:
        # flakes that transmit: the paint's flake-layer optical depth along μi' and μo' per unit τ
        # (τ a(μ) (1 − T̄(μ, λ)) / μ, the BRDF's _Tables.optical_path), times the depth τ_above
        X = (tab.optical_path(np.atleast_1d(ip[2])) + tab.optical_path(opz)) / tab.tau  # (N, L)
        att = np.exp(-tau_above[:, None] * X)
    else:
        S = _lerp1(a_tab, np.atleast_1d(_deg(ip[2])), tab.step)[0] / ip[2] + _lerp1(a_tab, _deg(opz), tab.step) / opz
        if paint.flakes is not None:
            # τ_e/τ from the paint's tables (opaque flakes: 1)
            ratio = tab.tau_e / tab.tau if tab.tau > 0 else np.ones(tab.L)
        else:
            ratio = np.ones(tab.L)
        att = np.exp(-np.outer(S * tau_above, ratio))
    area = flakes.region_nm[0] * flakes.region_nm[1]
    power = (flakes.areas_nm2 * np.abs(c) / ip[2] / area)[:, None] * R * att * Ti * To
    power[~esc] = 0.0
    return wo, power, esc


def binned_flake_brdf(paint: PaintBRDF, flakes: FlakeList, wavelength_nm, wi, theta_edges_deg, phi_edges_deg):
    """The BRDF estimated from a discrete flake list on angular bins of outgoing
    directions: Σ (flake power in the bin) / ∫_bin cos θ dω -> (nθ, nφ, L). Compare with
    ``paint.bin_average(..., components="flakes")``."""
    wo, power, esc = flake_list_reflection(paint, flakes, wavelength_nm, wi)
    te = np.asarray(theta_edges_deg, float)
    pe = np.asarray(phi_edges_deg, float)
    th = _deg(wo[:, 2])
    ph = np.degrees(np.arctan2(wo[:, 1], wo[:, 0])) % 360.0
    it = np.searchsorted(te, th, side="right") - 1
    ip_ = np.searchsorted(pe, ph, side="right") - 1
    ok = esc & (it >= 0) & (it < te.size - 1) & (ip_ >= 0) & (ip_ < pe.size - 1)
    L = power.shape[1]
    out = np.zeros((te.size - 1, pe.size - 1, L))
    np.add.at(out, (it[ok], ip_[ok]), power[ok])
    tr = np.radians(te)
    proj = 0.5 * (np.sin(tr[1:]) ** 2 - np.sin(tr[:-1]) ** 2)  # ∫ cos θ sin θ dθ
    dphi = np.radians(np.diff(pe))
    return out / (proj[:, None] * dphi[None, :])[..., None]
