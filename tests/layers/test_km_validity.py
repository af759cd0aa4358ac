"""KM/AD disagreement map (issue 24 item 5).

Independent references run here: iadpython (Prahl's adding-doubling) for the AD side (opaque, and
finite over black),
Kubelka's closed form R_inf = 1 + K/S - sqrt((K/S)^2 + 2 K/S) with Saunderson's correction written
out for the KM side, and the empty-slab limit.
"""

import warnings

import numpy as np
import pytest

from nmmm.layers.km_validity import KMAccuracyWarning, check_km_film, km_ad_disagreement, plot_km_ad_map
from nmmm.layers.kubelka_munk import km_coefficients, saunderson_k1, saunderson_k2


@pytest.mark.parametrize("a,g,n", [(0.95, 0.6, 1.55), (0.999, 0.3, 1.5), (0.7, 0.0, 1.4)])
def test_opaque_sides_against_iadpython_and_kubelka(a, g, n):
    iad = pytest.importorskip("iadpython")
    m = km_ad_disagreement(a, np.inf, g, n)
    s = iad.Sample(a=a, b=1e4, g=g, n=n, n_above=n, n_below=n, quad_pts=32)
    k1 = float(saunderson_k1(n))
    # iadpython's ur1 includes the first-surface (specular) reflection k1
    assert float(m.r_ad) == pytest.approx(s.rt()[0] - k1, abs=1e-3)
    K, S = km_coefficients(1 - a, a, g)
    q = K / S
    r_inf = 1 + q - np.sqrt(q * q + 2 * q)
    k2 = float(saunderson_k2(n))
    assert float(m.r_km) == pytest.approx((1 - k1) * (1 - k2) * r_inf / (1 - k2 * r_inf), rel=1e-9)


def test_empty_slab_and_white_limits():
    m = km_ad_disagreement(0.9, 1e-6, 0.5, 1.5)
    assert abs(float(m.r_km)) < 1e-5 and abs(float(m.r_ad)) < 1e-5
    white = km_ad_disagreement(0.999, np.inf, 0.6, 1.5)
    assert float(white.delta_e00) < 1.0  # opaque nearly lossless white: KM is safe
    # a thin, absorbing, forward-scattering film over black: KM is far off (measured dE00 8-9)
    dark = km_ad_disagreement(0.9, 2.0, 0.6, 1.5)
    assert float(dark.delta_e00) > 5.0 and float(dark.delta_r) > 0


def test_finite_dark_case_against_iadpython_and_kubelka():
    # the thin, absorbing, forward-scattering film over black (tau 2): the AD side from iadpython (a slide of
    # the slab's index that absorbs everything, b_below = 10, stands for the black substrate: no bottom
    # interface, nothing returns), the KM side from Kubelka's hyperbolic solution over black,
    # R = 1 / (a + b coth(b S X)), a = 1 + K/S, b = sqrt(a^2 - 1), with Saunderson's correction; the
    # lightness difference of the two greys in CIEDE2000 written out (a* = b* = 0)
    iad = pytest.importorskip("iadpython")
    a, tau, g, n = 0.9, 2.0, 0.6, 1.5
    m = km_ad_disagreement(a, tau, g, n)
    s = iad.Sample(a=a, b=tau, g=g, n=n, n_above=n, n_below=n, quad_pts=32)
    s.b_below = 10.0
    k1, k2 = float(saunderson_k1(n)), float(saunderson_k2(n))
    r_ad = s.rt()[0] - k1  # iadpython's ur1 includes the first-surface reflection k1
    assert float(m.r_ad) == pytest.approx(r_ad, abs=1e-4)
    K, S = km_coefficients(1 - a, a, g)
    aa = 1 + K / S
    bb = np.sqrt(aa * aa - 1)
    rb = 1 / (aa + bb / np.tanh(bb * S * tau))
    r_km = (1 - k1) * (1 - k2) * rb / (1 - k2 * rb)
    assert float(m.r_km) == pytest.approx(r_km, rel=1e-9)

    def lightness(y):
        return 116 * np.cbrt(y) - 16 if y > (6 / 29) ** 3 else 116 * (y / (3 * (6 / 29) ** 2) + 4 / 29) - 16

    L1, L2 = lightness(r_km), lightness(r_ad)
    Lm = (L1 + L2) / 2
    de00 = abs(L1 - L2) / (1 + 0.015 * (Lm - 50) ** 2 / np.sqrt(20 + (Lm - 50) ** 2))
    assert de00 > 5.0 and r_km > r_ad  # KM is far off here, by the independent numbers too
    assert float(m.delta_e00) == pytest.approx(de00, abs=0.02)


def test_map_broadcasts_and_figure(tmp_path):
    m = km_ad_disagreement(np.linspace(0, 0.99, 5)[None, :, None], np.geomspace(0.1, 100, 4)[:, None, None],
                           np.array([0.0, 0.8])[None, None, :], 1.5)
    assert m.delta_e00.shape == (4, 5, 2) and np.all(np.isfinite(m.delta_e00))
    p = plot_km_ad_map(tmp_path / "km_ad.png", g_values=(0.0, 0.8))
    assert p.stat().st_size > 1000


def test_check_km_film_warns_for_a_thin_absorbing_film_only():
    from nmmm.layers.distributions import lognormal
    from nmmm.layers.paint import PaintFilm

    w = np.arange(400.0, 701.0, 20.0)
    thin = PaintFilm(pigment=2.9 + 0.05j, binder=1.5, distribution=lognormal(250.0, 1.2, n_nodes=6),
                     volume_fraction=0.05, thickness_nm=3e3, substrate_reflectance=0.0)
    with pytest.warns(KMAccuracyWarning, match="solver='ad'"):
        de = check_km_film(thin, w)
    assert de > 1.0
    white = PaintFilm(pigment=2.7 + 0j, binder=1.5, distribution=lognormal(250.0, 1.3, n_nodes=6),
                      volume_fraction=0.15, thickness_nm=np.inf)
    with warnings.catch_warnings():
        warnings.simplefilter("error", KMAccuracyWarning)
        assert check_km_film(white, w) < 1e-3  # lossless and opaque: both give the same white (5e-5)
