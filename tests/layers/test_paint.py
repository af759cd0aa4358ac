"""The paint-film chain (Mie -> transport coefficients -> KM / adding-doubling) against
miepython + iadpython + the closed-form KM/Saunderson result, run on the same inputs."""

import numpy as np
import pytest

from nmmm.errors import InvalidInputError
from nmmm.layers.distributions import monodisperse
from nmmm.layers.kubelka_munk import km_r_infinity
from nmmm.layers.paint import PaintFilm, compare_km_ad, film_coefficients, paint_reflectance

miepython = pytest.importorskip("miepython")
iad = pytest.importorskip("iadpython")

W = np.array([450.0, 550.0, 650.0])
PIG = 2.6 + 0.05j
N_B = 1.5
D = 300.0


def _mie_coefficients(f, k_binder=0.0):
    qext, qsca, qback, g = miepython.efficiencies(np.full(W.size, PIG), np.full(W.size, D), W, n_env=N_B)
    mu_s = f * 1.5 * qsca / D
    mu_a = f * 1.5 * (qext - qsca) / D + (1 - f) * 4 * np.pi * k_binder / W
    return mu_a, mu_s, g


def test_film_coefficients_against_miepython():
    film = PaintFilm(PIG, N_B + 1e-6j, monodisperse(D), 0.08, 20e3)
    co = film_coefficients(film, W)
    mu_a, mu_s, g = _mie_coefficients(0.08, 1e-6)
    np.testing.assert_allclose(co.mu_a_per_nm, mu_a, rtol=1e-9)
    np.testing.assert_allclose(co.mu_s_per_nm, mu_s, rtol=1e-9)
    np.testing.assert_allclose(co.g, g, rtol=1e-9)


def test_opaque_film_adding_doubling_against_iadpython():
    film = PaintFilm(PIG, N_B, monodisperse(D), 0.08, np.inf)
    R = paint_reflectance(film, W, solver="ad", quad_pts=16, phase_function="hg", quadrature="prahl").reflectance
    mu_a, mu_s, g = _mie_coefficients(0.08)
    ref = []
    for i in range(W.size):
        s = iad.Sample(a=mu_s[i] / (mu_a[i] + mu_s[i]), b=1e5, g=g[i], n=N_B, n_above=N_B, n_below=N_B, quad_pts=16)
        ref.append(s.rt()[0])
    np.testing.assert_allclose(R, ref, atol=3e-5)


def test_opaque_film_kubelka_munk_is_saunderson_of_r_infinity():
    film = PaintFilm(PIG, N_B, monodisperse(D), 0.08, np.inf)
    R = paint_reflectance(film, W, solver="km").reflectance
    mu_a, mu_s, g = _mie_coefficients(0.08)
    Rinf = km_r_infinity(2 * mu_a / (0.75 * mu_s * (1 - g)))
    k1, k2 = 0.04, 0.5963  # Fresnel at normal incidence; Judd (1942) internal diffuse reflectance, n = 1.5
    np.testing.assert_allclose(R, k1 + (1 - k1) * (1 - k2) * Rinf / (1 - k2 * Rinf), atol=2e-4)


def test_lossless_film_on_white_substrate_reflects_everything():
    film = PaintFilm(1.9 + 0j, N_B, monodisperse(250.0), 0.1, 5e3, substrate_reflectance=1.0, clear_coat_thickness_nm=1e4)
    for solver in ("km", "ad"):
        np.testing.assert_allclose(paint_reflectance(film, W, solver=solver).reflectance, 1.0, atol=1e-9)


def _kubelka_1948(K, S, X, Rg):
    """Kubelka (1948), eq. (7): reflectance of a layer of thickness X over a background Rg."""
    a = 1 + K / S
    b = np.sqrt(a * a - 1)
    coth = 1 / np.tanh(b * S * X)
    return (1 - Rg * (a - b * coth)) / (a - Rg + b * coth)


def test_thin_film_over_a_substrate_against_iadpython_and_kubelka():
    """A film that does not hide its substrate, index-matched to the ambient (n = 1, no
    Fresnel surfaces: iadpython's slab is then exactly the film, at 16 quadrature points).

    Adding–doubling reference: iadpython's slab (collimated R, T; diffuse R, T) plus a
    Lambertian substrate rho summed over all round trips,
    R = R_c + T_c rho T_d / (1 − rho R_d). Kubelka–Munk reference: Kubelka's (1948)
    closed form with K = 2 μa, S = ¾ μs (1 − g) (Gate 1974) from miepython.
    """
    colour = pytest.importorskip("colour")
    w = np.linspace(400.0, 700.0, 31)
    f, X, rho = 0.02, 2e3, 0.8
    film = PaintFilm(PIG, 1.0, monodisperse(D), f, X, substrate_reflectance=rho)
    c = compare_km_ad(film, w, phase_function="hg")  # iadpython is Henyey–Greenstein

    qext, qsca, qback, g = miepython.efficiencies(np.full(w.size, PIG), np.full(w.size, D), w, n_env=1.0)
    mu_s = f * 1.5 * qsca / D
    mu_a = f * 1.5 * (qext - qsca) / D
    ad = []
    for i in range(w.size):
        s = iad.Sample(a=mu_s[i] / (mu_a[i] + mu_s[i]), b=(mu_a[i] + mu_s[i]) * X, g=g[i], n=1.0,
                       n_above=1.0, n_below=1.0, quad_pts=16)
        ur1, ut1, uru, utu = s.rt()
        ad.append(ur1 + ut1 * rho * utu / (1 - rho * uru))
    km = _kubelka_1948(2 * mu_a, 0.75 * mu_s * (1 - g), X, rho)
    np.testing.assert_allclose(c["ad"], ad, atol=3e-5)
    np.testing.assert_allclose(c["km"], km, rtol=1e-9)
    # the film does not hide its substrate: over black it reflects much less
    black = _kubelka_1948(2 * mu_a, 0.75 * mu_s * (1 - g), X, 0.0)
    assert np.all(km - black > 0.1)
    assert c["max_abs_difference"] == pytest.approx(np.max(np.abs(km - np.asarray(ad))), abs=3e-5)
    assert c["delta_e2000"] == pytest.approx(
        float(colour.delta_E(c["lab_km"], c["lab_ad"], method="CIE 2000")), rel=1e-6
    )


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(volume_fraction=1.5),
        dict(volume_fraction=-0.1),
        dict(thickness_nm=0.0),
        dict(thickness_nm=-5.0),
        dict(thickness_nm=float("nan")),
        dict(thickness_nm=-np.inf),
        dict(thickness_nm="thick"),
        dict(substrate_reflectance=1.2),
        dict(clear_coat_thickness_nm=-1.0),
    ],
)
def test_bad_film(kwargs):
    args = dict(pigment=PIG, binder=N_B, distribution=monodisperse(D), volume_fraction=0.05, thickness_nm=1e4)
    args.update(kwargs)
    with pytest.raises(InvalidInputError):
        PaintFilm(**args)


def test_bad_indices_and_solver():
    with pytest.raises(InvalidInputError, match="pigment has k < 0"):
        paint_reflectance(PaintFilm(2.0 - 0.1j, N_B, monodisperse(D), 0.05, 1e4), W)
    with pytest.raises(InvalidInputError, match="binder has k < 0"):
        paint_reflectance(PaintFilm(PIG, 1.5 - 1e-6j, monodisperse(D), 0.05, 1e4), W)
    with pytest.raises(InvalidInputError):
        paint_reflectance(PaintFilm(PIG, N_B, monodisperse(D), 0.05, 1e4), W, solver="monte-carlo")


def test_body_reflectance_refuses_impossible_readings_and_clips_only_rounding():
    # Saunderson (1942) inverted: a reading below k1 (specular included) or above 1 has no Lambertian body;
    # it used to be clipped to 0 or 1 silently
    from nmmm.layers.kubelka_munk import saunderson, saunderson_k1, saunderson_k2
    from nmmm.layers.paint import body_reflectance_from_reading

    k1, k2 = saunderson_k1(1.5), saunderson_k2(1.5)
    w = np.array([400.0, 450.0, 500.0])
    with pytest.raises(InvalidInputError, match=r"at 450 nm: R = 0\.02 .*between k1"):
        body_reflectance_from_reading(np.array([0.3, 0.02, 0.3]), 1.5, "included", wavelength_nm=w)
    with pytest.raises(InvalidInputError, match=r"at index 1: R = 1\.2 "):
        body_reflectance_from_reading(np.array([0.3, 1.2]), 1.5, "excluded")
    with pytest.raises(InvalidInputError, match=r"R = -0\.01"):
        body_reflectance_from_reading(-0.01, 1.5)
    edge = saunderson(np.array([0.0, 1.0]), k1, k2, specular="included") + np.array([-1e-13, 1e-13])
    np.testing.assert_allclose(body_reflectance_from_reading(edge, 1.5, "included"), [0.0, 1.0], atol=1e-11)
    rho = body_reflectance_from_reading(edge, 1.5, "included")
    assert rho.min() >= 0.0 and rho.max() <= 1.0
