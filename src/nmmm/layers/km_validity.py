"""Where Kubelka–Munk is safe: its disagreement with converged adding–doubling (issue 24 item 5).

- :func:`km_ad_disagreement` — KM (Gate 1974 K, S) + Saunderson against adding–doubling (HG phase
  function, auto-converged to 1e-4) for the same slab, on any broadcast grid of single-scattering
  albedo × optical thickness × g × binder index × substrate: both reflectances, their difference
  and the CIEDE2000 between the two achromatic colours they read as (Y = R, white Y = 1).
- :class:`KMADMap` — that result.
- :func:`check_km_film` — a :class:`~nmmm.layers.paint.PaintFilm` on a wavelength grid: warns
  (:class:`KMAccuracyWarning`) when KM's spectrum is more than ``max_delta_e00`` from AD's, with the
  worst wavelength and its (albedo, τ, g); returns the ΔE00 of the two spectra under D65.
- :func:`plot_km_ad_map` — the map as a figure (ΔE00 over albedo × optical thickness, one panel
  per g) for the documentation.

Both solvers treat the same physics here (a slab of the binder's index over a Lambertian
substrate, diffuse-out reading, specular excluded), so the difference is KM's two-flux
approximation alone. It is largest for thin, absorbing, forward-scattering films (albedo
0.5–0.95, τ ~ 1–10, g ≥ 0.5) and vanishes for opaque, weakly absorbing white films.

References
----------
- P. Kubelka, F. Munk, Z. Tech. Phys. 12, 593 (1931); L. F. Gate, Appl. Opt. 13, 236 (1974).
- J. L. Saunderson, J. Opt. Soc. Am. 32, 727 (1942).
- S. A. Prahl, "The adding-doubling method", in A. J. Welch, M. J. C. van Gemert (eds.),
  *Optical-Thermal Response of Laser-Irradiated Tissue*, Plenum (1995), ch. 5.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.layers.adding_doubling_method import adding_doubling
from nmmm.layers.kubelka_munk import km_coefficients, km_reflectance, saunderson, saunderson_k1, saunderson_k2

__all__ = ["KMADMap", "KMAccuracyWarning", "check_km_film", "km_ad_disagreement", "plot_km_ad_map"]

#: default largest ΔE00 between KM and AD before :func:`check_km_film` warns
KM_MAX_DELTA_E00 = 1.0


class KMAccuracyWarning(UserWarning):
    """Kubelka–Munk differs from adding–doubling by more than the stated ΔE00 for this film."""


@dataclass(frozen=True)
class KMADMap:
    """KM and AD body reflectances (specular excluded) on the broadcast grid of the inputs."""

    albedo: np.ndarray
    optical_thickness: np.ndarray
    g: np.ndarray
    n_binder: np.ndarray
    r_km: np.ndarray
    r_ad: np.ndarray

    @property
    def delta_r(self) -> np.ndarray:
        """R_KM − R_AD."""
        return self.r_km - self.r_ad

    @property
    def delta_e00(self) -> np.ndarray:
        """CIEDE2000 between the greys Y = R_KM and Y = R_AD (white Y = 1)."""
        from nmmm.colour import delta_e2000

        def lab(y):
            y = np.clip(y, 0.0, 1.0)
            f = np.where(y > (6 / 29) ** 3, np.cbrt(y), y / (3 * (6 / 29) ** 2) + 4 / 29)
            L = 116 * f - 16
            return np.stack([L, np.zeros_like(L), np.zeros_like(L)], axis=-1)

        return np.asarray(delta_e2000(lab(self.r_km), lab(self.r_ad)))


def km_ad_disagreement(albedo, optical_thickness, g, n_binder=1.5, substrate_reflectance=0.0,
                       km_method: str = "gate") -> KMADMap:
    """KM + Saunderson against converged adding–doubling for slabs given by their dimensionless
    transport parameters (all arguments broadcast; ``optical_thickness`` may be ``np.inf``).

    >>> m = km_ad_disagreement(0.999, np.inf, 0.0)   # an opaque, nearly lossless white
    >>> bool(m.delta_e00 < 1.0)
    True
    """
    a, tau, gg, nb, rho = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in
                                               (albedo, optical_thickness, g, n_binder, substrate_reflectance)))
    if np.any((a < 0) | (a > 1)) or np.any(tau < 0) or np.any(np.abs(gg) >= 1) or np.any(nb < 1):
        raise InvalidInputError("need 0 <= albedo <= 1, optical_thickness >= 0 (inf: opaque), |g| < 1, n_binder >= 1")
    # per unit thickness: mu_t = 1 (tau = thickness), or a huge thickness for an opaque slab
    thick = np.where(np.isfinite(tau), tau, 1e12)
    K, S = km_coefficients(1.0 - a, a, gg, method=km_method)
    rb = km_reflectance(K, S, thick, rho)
    r_km = saunderson(rb, saunderson_k1(nb), saunderson_k2(nb), specular="excluded")
    r_ad = adding_doubling(a, tau, gg, n_slab=nb, substrate_reflectance=rho).body_reflectance
    return KMADMap(a, tau, gg, nb, np.asarray(r_km), np.asarray(r_ad))


def check_km_film(film, wavelength_nm, max_delta_e00: float = KM_MAX_DELTA_E00, stacklevel: int = 2) -> float:
    """ΔE00 (D65, 2°) between the KM and AD spectra of ``film`` (HG phase function, specular excluded);
    warns :class:`KMAccuracyWarning` when it exceeds ``max_delta_e00``, naming the worst wavelength."""
    from nmmm.colour import delta_e2000, spectra_to_lab
    from nmmm.layers.paint import paint_reflectance

    w = np.asarray(wavelength_nm, dtype=float)
    r_km = paint_reflectance(film, w, solver="km", specular="excluded").reflectance
    r_ad = paint_reflectance(film, w, solver="ad", specular="excluded", phase_function="hg").reflectance
    de = float(delta_e2000(spectra_to_lab(w, r_km), spectra_to_lab(w, r_ad)))
    if de > max_delta_e00:
        from nmmm.layers.paint import film_coefficients

        co = film_coefficients(film, w)
        i = int(np.argmax(np.abs(r_km - r_ad)))
        mu_t = co.mu_a_per_nm[i] + co.mu_s_per_nm[i]
        tau = mu_t * film.thickness_nm
        warnings.warn(
            f"Kubelka-Munk differs from adding-doubling by dE00 = {de:.2f} (> {max_delta_e00:g}) for this film; worst at "
            f"{w[i]:g} nm: R_KM = {r_km[i]:.4f}, R_AD = {r_ad[i]:.4f} (albedo {co.mu_s_per_nm[i] / mu_t:.3f}, "
            f"optical thickness {tau:.3g}, g {co.g[i]:.2f}): use solver='ad' for this recipe",
            KMAccuracyWarning, stacklevel=stacklevel)
    return de


def plot_km_ad_map(path, g_values=(0.0, 0.5, 0.8), n_binder: float = 1.5, substrate_reflectance: float = 0.0):
    """Figure of ΔE00(KM, AD) over albedo × optical thickness, one panel per g; returns ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    albedo = np.linspace(0.0, 0.999, 41)
    tau = np.geomspace(0.05, 200.0, 41)
    fig, axes = plt.subplots(1, len(g_values), figsize=(4.4 * len(g_values), 3.8), sharey=True, layout="constrained")
    for ax, g in zip(np.atleast_1d(axes), g_values):
        m = km_ad_disagreement(albedo[None, :], tau[:, None], g, n_binder, substrate_reflectance)
        pc = ax.pcolormesh(albedo, tau, m.delta_e00, shading="auto", vmin=0, vmax=10, cmap="magma_r")
        cs = ax.contour(albedo, tau, m.delta_e00, levels=[1.0, 3.0], colors=["white", "cyan"], linewidths=1)
        ax.clabel(cs, fmt={1.0: "ΔE00 1", 3.0: "ΔE00 3"}, fontsize=7)
        ax.set_yscale("log")
        ax.set_xlabel("single-scattering albedo (1)")
        ax.set_title(f"g = {g:g}, n = {n_binder:g}, substrate R = {substrate_reflectance:g}")
    np.atleast_1d(axes)[0].set_ylabel("optical thickness τ (1)")
    fig.colorbar(pc, ax=axes, label="ΔE00 KM + Saunderson vs adding-doubling (1)")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
