"""Plots of optical constants (matplotlib, Agg backend)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def plot_nk(materials, path, range_nm=None, title=None, n_points: int = 400):
    """Plot n and k of ``materials`` against wavelength (nm) side by side into ``path``.

    Each material is plotted over ``range_nm`` (default: the visible 380–780 nm clipped to
    its own data range).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_n, ax_k) = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for m in materials:
        lo, hi = range_nm if range_nm else (380.0, 780.0)
        lo, hi = max(lo, m.range_nm[0]), min(hi, m.range_nm[1])
        w = np.linspace(lo, hi, n_points)
        nk = m.nk(w)
        ax_n.plot(w, nk.real, label=m.name)
        ax_k.plot(w, nk.imag, label=m.name)
    for ax, lab in ((ax_n, "n (1)"), (ax_k, "k (1)")):
        ax.set_xlabel("wavelength (nm)")
        ax.set_ylabel(lab)
        ax.grid(alpha=0.3)
    ax_k.legend(fontsize=8)
    if title:
        fig.suptitle(title)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
