"""Dispersion models against their analytic properties and independent integrations."""

import numpy as np
import pytest
from scipy import integrate

import nmmm
from nmmm.materials import (Cauchy, Constant, Drude, DrudeLorentz, Lorentz, Sellmeier, TaucLorentz,
                            eps_to_nk, nk_to_eps)
from nmmm.materials.material import HC_EV_NM


def test_eq1_conversions():
    # eq. (1) of the seed paper on a hand-checked value: (0.5 + 2i)² = −3.75 + 2i
    assert nk_to_eps(0.5 + 2j) == pytest.approx(-3.75 + 2j)
    assert eps_to_nk(-3.75 + 2j) == pytest.approx(0.5 + 2j)
    rng = np.random.default_rng(0)
    nk = rng.uniform(0.05, 5, 100) + 1j * rng.uniform(0, 5, 100)
    np.testing.assert_allclose(eps_to_nk(nk_to_eps(nk)), nk, rtol=1e-12)


def test_sellmeier_reproduces_malitson_silica():
    silica = Sellmeier(B=(0.6961663, 0.4079426, 0.8974794), C=(0.0684043**2, 0.1162414**2, 9.896161**2))
    assert silica.nk(587.5618).real == pytest.approx(1.458464, abs=2e-6)  # Malitson (1965) Table I


def test_cauchy_terms_in_micrometres():
    c = Cauchy(A=1.5, B=0.01, C=0.0)
    assert c.nk(500.0).real == pytest.approx(1.5 + 0.01 / 0.25)


def test_drude_zero_crossing_at_screened_plasma_energy():
    # Re ε = 0 at E = sqrt(ωp²/ε∞ − Γ²) (Dressel & Grüner 2002, eq. 5.1.16 rearranged)
    d = Drude(plasma_ev=9.0, gamma_ev=0.05, eps_inf=4.0)
    E0 = np.sqrt(81 / 4 - 0.05**2)
    assert d.eps(HC_EV_NM / E0).real == pytest.approx(0.0, abs=1e-9)
    assert np.all(d.eps(np.linspace(200, 2000, 50)).imag > 0)


def test_lorentz_single_oscillator_analytic():
    l = Lorentz(oscillators=[(10.0, 3.0, 0.2)], eps_inf=2.0)
    E = 2.0
    assert l.eps(HC_EV_NM / E) == pytest.approx(2.0 + 10.0 / (9.0 - 4.0 - 1j * 0.2 * 2.0))
    # at resonance ε2 = A/(Γ E0)
    assert l.eps(HC_EV_NM / 3.0).imag == pytest.approx(10.0 / (0.2 * 3.0))


def test_drude_lorentz_is_sum_of_parts():
    dl = DrudeLorentz(plasma_ev=8.0, gamma_ev=0.1, oscillators=[(5.0, 2.5, 0.5)], eps_inf=1.5)
    E = HC_EV_NM / 600.0
    expected = 1.5 - 64 / (E * E + 1j * 0.1 * E) + 5.0 / (6.25 - E * E - 0.5j * E)
    assert dl.eps(600.0) == pytest.approx(expected)


def test_tauc_lorentz_eps1_is_kramers_kronig_of_its_eps2():
    """ε1 closed form (Jellison & Modine 1996) against a direct principal-value quadrature."""
    tl = TaucLorentz(A=120.0, E0=3.6, C=1.8, Eg=1.9, eps_inf=1.2)
    for E in (1.0, 2.5, 3.6, 5.0):
        f = lambda x: x * tl.eps2(x) / (x + E)  # PV ∫ x ε2 /((x−E)(x+E)) with scipy's Cauchy weight
        pv, _ = integrate.quad(f, tl.Eg, 200.0, weight="cauchy", wvar=E, limit=400)
        tail, _ = integrate.quad(lambda x: x * tl.eps2(x) / (x * x - E * E), 200.0, np.inf)
        eps1 = 1.2 + 2 / np.pi * (pv + tail)
        assert tl.eps1(E) == pytest.approx(eps1, abs=2e-4)
    assert tl.eps(HC_EV_NM / 1.5).imag == 0.0  # transparent below the gap


def test_constant():
    assert Constant(1.5 + 0.1j).eps(500.0) == pytest.approx((1.5 + 0.1j) ** 2)
    assert Constant(eps=-10 + 1j).eps([400.0, 500.0]) == pytest.approx(-10 + 1j)


@pytest.mark.parametrize("make", [
    lambda: Constant(1.5 - 0.1j),
    lambda: Constant(eps=2 - 1j),
    lambda: Constant(np.nan),
    lambda: Cauchy(A=-1.0),
    lambda: Cauchy(A=1.5, k_amplitude=-0.01),
    lambda: Drude(plasma_ev=9.0, gamma_ev=0.0),
    lambda: Lorentz(oscillators=[(-1.0, 3.0, 0.2)]),
    lambda: Lorentz(oscillators=[(1.0, 3.0)]),
    lambda: TaucLorentz(A=100, E0=2.0, C=5.0, Eg=1.0),
    lambda: TaucLorentz(A=100, E0=2.0, C=1.0, Eg=3.0),
    lambda: Sellmeier(B=(1.0,), C=(-0.1,)),
    lambda: Cauchy(A=1.5, range_nm=(800, 400)),
])
def test_non_physical_parameters_are_clear_errors(make):
    with pytest.raises(nmmm.InvalidInputError):
        make()


def test_model_range_is_enforced_when_given():
    c = Cauchy(A=1.5, B=0.004, range_nm=(400, 1000))
    with pytest.raises(nmmm.OutOfRangeError):
        c.nk(300.0)
