"""Figures of ellipsometry: data against model, optical constants.

- :func:`plot_fit` — Ψ and Δ against wavelength at each angle, data (points, with σ) and model
  (lines), and the weighted residuals.
- :func:`plot_nk` — n and k of one or more materials / inversions, with uncertainty bands.

Every axis is labelled with its quantity and unit (``(1)`` for n, k and σ-weighted residuals),
as :func:`nmmm.recipes.figures.missing_axis_labels` checks.

Matplotlib with the Agg backend (files, no display).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nmmm.ellipsometry.forward import wrap_delta

__all__ = ["plot_fit", "plot_nk"]


def _plt():
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def plot_fit(data, psi_model, delta_model, path, title: str | None = None) -> Path:
    """Save a figure of Ψ, Δ data vs model (per angle) and the weighted residuals to ``path``."""
    plt = _plt()
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 8.5), sharex=True,
                             gridspec_kw={"height_ratios": [3, 3, 1.6]})
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    # show Δ of the model on the branch nearest the data
    delta_plot_model = data.delta_deg + wrap_delta(np.asarray(delta_model) - data.delta_deg)
    sp = data.sigma_psi_deg if data.has_sigma else np.ones(len(data))
    sd = data.sigma_delta_deg if data.has_sigma else np.ones(len(data))
    for i, ang in enumerate(data.angles_deg):
        sel = np.flatnonzero(np.isclose(data.angle_deg, ang))
        sel = sel[np.argsort(data.wavelength_nm[sel])]
        c = colors[i % len(colors)]
        w = data.wavelength_nm[sel]
        for ax, y, ym, s in ((axes[0], data.psi_deg, psi_model, data.sigma_psi_deg),
                             (axes[1], data.delta_deg, delta_plot_model, data.sigma_delta_deg)):
            if s is not None:
                ax.errorbar(w, y[sel], yerr=s[sel], fmt="o", ms=2.5, color=c, alpha=0.6, lw=0.6)
            else:
                ax.plot(w, y[sel], "o", ms=2.5, color=c, alpha=0.6)
            ax.plot(w, np.asarray(ym)[sel], "-", color=c, lw=1.2, label=f"{ang:g}°")
        axes[2].plot(w, ((np.asarray(psi_model) - data.psi_deg) / sp)[sel], ".", ms=2, color=c)
        axes[2].plot(w, (wrap_delta(np.asarray(delta_model) - data.delta_deg) / sd)[sel], "x", ms=2, color=c)
    axes[0].set_ylabel("Ψ (°)")
    axes[1].set_ylabel("Δ (°)")
    axes[2].set_ylabel("residual / σ (1)" if data.has_sigma else "residual (°)")
    axes[2].axhline(0, color="k", lw=0.5)
    axes[2].set_xlabel("wavelength (nm)")
    axes[0].legend(title="angle (points: data, lines: model)", fontsize=8)
    axes[0].set_title(title or f"{data.name}: data and model")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def plot_nk(curves, path, title: str = "optical constants") -> Path:
    """Save n and k plots. ``curves``: list of (label, wavelength_nm, nk[, sigma_n, sigma_k]).

    Curves without uncertainties are drawn as thick translucent lines (references, models);
    curves with them as points with a ±2σ band (NaN σ: points only).
    """
    plt = _plt()
    fig, (ax_n, ax_k) = plt.subplots(1, 2, figsize=(10, 4))
    for curve in curves:
        label, w, nk = curve[0], np.asarray(curve[1]), np.asarray(curve[2])
        # references (no uncertainties): thick translucent lines; results: points on thin lines
        kw = dict(lw=4, alpha=0.45) if len(curve) < 4 else dict(marker="o", ms=2.5, lw=0.8)
        line, = ax_n.plot(w, nk.real, label=label, **kw)
        ax_k.plot(w, nk.imag, color=line.get_color(), label=label, **kw)
        if len(curve) >= 5:
            sn, sk = np.asarray(curve[3]), np.asarray(curve[4])
            ok = np.isfinite(sn) & np.isfinite(sk)
            ax_n.fill_between(w[ok], (nk.real - 2 * sn)[ok], (nk.real + 2 * sn)[ok], color=line.get_color(), alpha=0.25)
            ax_k.fill_between(w[ok], (nk.imag - 2 * sk)[ok], (nk.imag + 2 * sk)[ok], color=line.get_color(), alpha=0.25)
    ax_n.set_ylabel("refractive index n (1)")
    ax_k.set_ylabel("extinction coefficient k (1)")
    for ax in (ax_n, ax_k):
        ax.set_xlabel("wavelength (nm)")
    ax_n.legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
