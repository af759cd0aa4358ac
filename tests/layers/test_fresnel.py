"""Fresnel coefficients against analytic results (Born & Wolf §1.5) and the tmm package."""

import numpy as np
import pytest
import tmm

from nmmm.errors import InvalidInputError
from nmmm.layers import brewster_angle, critical_angle, fresnel, n_cos_theta


def test_normal_incidence_analytic():
    # Born & Wolf eq. 1.5(25): r = (n1 - n2)/(n1 + n2) at normal incidence
    c = fresnel(1.0, 1.5, 0.0)
    assert c.rs == pytest.approx(-0.2)
    assert c.rp == pytest.approx(0.2)  # convention rp = -rs at normal incidence
    assert c.R == pytest.approx(0.04)
    assert c.T == pytest.approx(0.96)


def test_metal_normal_incidence_analytic():
    # R = ((n-1)^2 + k^2)/((n+1)^2 + k^2) for air -> n + ik
    n = 0.2 + 3.0j
    c = fresnel(1.0, n, 0.0)
    expected = ((n.real - 1) ** 2 + n.imag**2) / ((n.real + 1) ** 2 + n.imag**2)
    assert c.Rs == pytest.approx(expected)
    assert c.Rp == pytest.approx(expected)


@pytest.mark.parametrize("n1,n2", [(1.0, 1.5), (1.33, 2.4), (1.5, 1.0)])
def test_brewster_angle_rp_vanishes(n1, n2):
    theta_b = brewster_angle(n1, n2)
    assert np.tan(np.radians(theta_b)) == pytest.approx(n2 / n1)
    assert abs(fresnel(n1, n2, theta_b).rp) < 1e-12
    assert abs(fresnel(n1, n2, theta_b).rs) > 0.01


def test_total_internal_reflection():
    theta_c = critical_angle(1.5, 1.0)
    assert np.sin(np.radians(theta_c)) == pytest.approx(1 / 1.5)
    c = fresnel(1.5, 1.0, np.array([50.0, 60.0, 80.0]))
    np.testing.assert_allclose(c.Rs, 1.0, atol=1e-14)
    np.testing.assert_allclose(c.Rp, 1.0, atol=1e-14)
    np.testing.assert_allclose(c.Ts, 0.0, atol=1e-14)


@pytest.mark.parametrize("pol", ["s", "p"])
def test_against_tmm_interface_absorbing(pol):
    """Oblique incidence onto absorbing media, amplitudes and powers against tmm."""
    angles = np.array([0.0, 20.0, 45.0, 70.0, 89.0])
    for n1, n2 in [(1.0, 1.5 + 0.2j), (1.5, 0.2 + 3.4j), (1.0, 2.9 + 0.01j), (1.6, 1.0)]:
        c = fresnel(n1, n2, angles)
        for i, a in enumerate(angles):
            th2 = tmm.snell(n1, n2, np.radians(a))
            r_ref = tmm.interface_r(pol, n1, n2, np.radians(a), th2)
            t_ref = tmm.interface_t(pol, n1, n2, np.radians(a), th2)
            T_ref = tmm.T_from_t(pol, t_ref, n1, n2, np.radians(a), th2)
            assert getattr(c, "r" + pol)[i] == pytest.approx(r_ref, abs=1e-12)
            assert getattr(c, "t" + pol)[i] == pytest.approx(t_ref, abs=1e-12)
            assert getattr(c, "T" + pol)[i] == pytest.approx(T_ref, abs=1e-12)


def test_energy_conservation_lossless():
    a = np.linspace(0, 89, 90)
    c = fresnel(1.0, 1.7, a)
    np.testing.assert_allclose(c.Rs + c.Ts, 1.0, atol=1e-13)
    np.testing.assert_allclose(c.Rp + c.Tp, 1.0, atol=1e-13)


def test_broadcasting():
    n2 = np.array([1.3, 1.5, 2.0 + 0.1j])
    c = fresnel(1.0, n2[:, None], np.array([0.0, 30.0, 60.0, 80.0])[None, :])
    assert c.rs.shape == (3, 4)


def test_forward_branch_in_absorber():
    q = n_cos_theta(np.array([1.5 + 0.5j, 0.1 + 4j]), 0.9)
    assert np.all(q.imag > 0)


@pytest.mark.parametrize(
    "args",
    [
        (1.0, 1.5 - 0.1j, 10.0),  # k < 0
        (1.0, np.nan, 10.0),
        (1.0, 1.5, 90.0),
        (1.0, 1.5, -1.0),
        (1.0, 1.5, np.nan),
    ],
)
def test_bad_input(args):
    with pytest.raises(InvalidInputError):
        fresnel(*args)
