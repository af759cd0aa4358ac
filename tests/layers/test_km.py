"""Kubelka–Munk and Saunderson against analytic limits, a numerical solution of the
two-flux equations, and published constants (Judd 1942: k2 = 0.596 for n = 1.5)."""

import numpy as np
import pytest
from scipy.integrate import solve_bvp

from nmmm.errors import InvalidInputError
from nmmm.layers.kubelka_munk import (
    hiding_thickness,
    km_coefficients,
    km_r_infinity,
    km_reflectance,
    km_transmittance,
    saunderson,
    saunderson_k1,
    saunderson_k2,
)


@pytest.mark.parametrize("K,S,X,Rg", [(0.3, 2.0, 0.7, 0.0), (0.05, 1.0, 2.0, 0.8), (1.0, 0.5, 1.5, 0.4)])
def test_against_two_flux_ode(K, S, X, Rg):
    # dI/dx = -(K+S) I + S J ; dJ/dx = (K+S) J - S I ; I(0) = 1, J(X) = Rg I(X)
    def f(x, y):
        return np.vstack([-(K + S) * y[0] + S * y[1], (K + S) * y[1] - S * y[0]])

    def bc(ya, yb):
        return np.array([ya[0] - 1, yb[1] - Rg * yb[0]])

    x = np.linspace(0, X, 50)
    sol = solve_bvp(f, bc, x, np.vstack([np.ones_like(x), 0.3 * np.ones_like(x)]), tol=1e-10)
    assert sol.success
    R_ode = sol.sol(0)[1]
    assert float(km_reflectance(K, S, X, Rg)) == pytest.approx(R_ode, rel=1e-6)
    if Rg == 0:
        assert float(km_transmittance(K, S, X)) == pytest.approx(sol.sol(X)[0], rel=1e-6)


def test_limits():
    X = np.linspace(0, 5, 11)
    # no scattering: Beer-Lambert on the two diffuse passes
    np.testing.assert_allclose(km_reflectance(0.4, 0.0, X, 0.6), 0.6 * np.exp(-0.8 * X))
    np.testing.assert_allclose(km_transmittance(0.4, 0.0, X), np.exp(-0.4 * X))
    # no absorption (Kubelka 1948): R = (SX(1-Rg)+Rg)/(1+SX(1-Rg)); R + T = 1 on a black background
    for Rg in (0.0, 0.3):
        np.testing.assert_allclose(km_reflectance(0.0, 2.0, X, Rg), (2 * X * (1 - Rg) + Rg) / (1 + 2 * X * (1 - Rg)))
    np.testing.assert_allclose(km_reflectance(0.0, 2.0, X, 0.0) + km_transmittance(0.0, 2.0, X), 1.0)
    # infinite thickness
    q = np.array([1e-4, 0.01, 0.3, 5.0])
    np.testing.assert_allclose(km_reflectance(q, 1.0, 1e4, 0.5), 1 + q - np.sqrt(q * q + 2 * q), rtol=1e-10)
    np.testing.assert_allclose(km_r_infinity(q), 1 + q - np.sqrt(q**2 + 2 * q))
    assert float(km_r_infinity(np.inf)) == 0.0  # no scattering: nothing comes back
    # K/S of R_inf is the KM function (1-R)^2/(2R)
    R = km_r_infinity(q)
    np.testing.assert_allclose((1 - R) ** 2 / (2 * R), q, rtol=1e-9)
    # energy: R + T + A = 1 with A >= 0
    K, S = 0.3, 1.2
    assert 0 < 1 - km_reflectance(K, S, 1.0) - km_transmittance(K, S, 1.0) < 1


def test_saunderson_constants():
    assert float(saunderson_k1(1.5)) == pytest.approx(0.04)
    assert float(saunderson_k2(1.5)) == pytest.approx(0.596, abs=5e-4)  # Judd (1942)
    assert float(saunderson_k2(1.0)) == pytest.approx(0.0, abs=1e-12)
    # black body: only the surface; white lossless body: everything comes back
    assert float(saunderson(0.0, 0.04, 0.6)) == pytest.approx(0.04)
    assert float(saunderson(1.0, 0.04, 0.6)) == pytest.approx(1.0)
    assert float(saunderson(1.0, 0.04, 0.6, specular="excluded")) == pytest.approx(0.96)


def test_km_coefficients_and_hiding():
    K, S = km_coefficients(np.array([0.01, 0.1]), np.array([2.0, 2.0]), np.array([0.6, 0.6]))
    np.testing.assert_allclose(K, [0.02, 0.2])
    np.testing.assert_allclose(S, [0.6, 0.6])
    Ks, Ss = km_coefficients(0.1, 2.0, 0.6, method="star")
    assert Ss == pytest.approx(0.6 - 0.025)
    X = float(hiding_thickness(0.05, 1.0, 0.98, 0.8))
    # contrast ratio from Kubelka's (1948) closed form, R = (1 - Rg(a - b coth bSX))/(a - Rg + b coth bSX)
    a = 1 + 0.05 / 1.0
    b = np.sqrt(a * a - 1)
    coth = 1 / np.tanh(b * X)
    cr = (1 / (a + b * coth)) / ((1 - 0.8 * (a - b * coth)) / (a - 0.8 + b * coth))
    assert cr == pytest.approx(0.98, rel=1e-6)
    assert np.isinf(hiding_thickness(0.05, 0.0))


def test_bad_input():
    with pytest.raises(InvalidInputError):
        km_reflectance(-0.1, 1.0, 1.0)
    with pytest.raises(InvalidInputError):
        km_reflectance(0.1, 1.0, -1.0)
    with pytest.raises(InvalidInputError):
        km_reflectance(0.1, 1.0, 1.0, 1.2)
    with pytest.raises(InvalidInputError):
        km_coefficients(0.1, 1.0, 1.0)
    with pytest.raises(InvalidInputError):
        km_coefficients(0.1, 1.0, 0.5, method="nope")
