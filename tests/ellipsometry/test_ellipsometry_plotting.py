"""Ellipsometry figures: every axis labelled with its quantity and unit (issue 25), checked on the
figure objects while they are saved."""

import numpy as np

from nmmm.ellipsometry.data import EllipsometryData
from nmmm.ellipsometry.plotting import plot_fit, plot_nk
from nmmm.recipes.figures import audit_axis_labels


def _data(sigma):
    w = np.repeat(np.linspace(400.0, 700.0, 7), 2)
    ang = np.tile([65.0, 70.0], 7)
    s = np.full(w.size, 0.05) if sigma else None
    return EllipsometryData(w, ang, 30 + 0.01 * w, 100 + 0.02 * w, s, s, name="film")


def test_nk_and_fit_figures_label_every_axis_with_a_unit(tmp_path):
    w = np.linspace(400.0, 700.0, 7)
    nk = 1.5 + 0.01j + 0 * w
    with audit_axis_labels() as saved:
        plot_nk([("reference", w, nk), ("inverted", w, nk, 0.01 + 0 * w, 0.001 + 0 * w)], tmp_path / "nk.png")
        for sigma in (True, False):
            d = _data(sigma)
            plot_fit(d, d.psi_deg + 0.1, d.delta_deg - 0.1, tmp_path / f"fit{sigma}.png")
    assert len(saved) == 3
    assert [(name, miss) for name, miss in saved if miss] == []


def test_nk_axes_name_the_quantity(tmp_path):
    import matplotlib.pyplot as plt

    w = np.linspace(400.0, 700.0, 5)
    captured = []
    orig = plt.close
    try:
        plt.close = lambda fig=None: captured.append(fig)
        plot_nk([("x", w, 1.5 + 0.1j + 0 * w)], tmp_path / "nk.png")
    finally:
        plt.close = orig
    fig = captured[0]
    assert [ax.get_ylabel() for ax in fig.axes] == ["refractive index n (1)", "extinction coefficient k (1)"]
    assert all(ax.get_xlabel() == "wavelength (nm)" for ax in fig.axes)
    orig(fig)
