"""Kramers–Kronig transforms against the exactly causal Lorentz oscillator."""

import numpy as np
import pytest

from nmmm.materials import Cauchy, Lorentz, TabulatedMaterial, eps1_from_eps2, eps2_from_eps1, get, kk_consistency
from nmmm.materials.material import HC_EV_NM

A, E0, G = 10.0, 2.0, 0.5


def lorentz(E):
    return 1 + A / (E0**2 - E**2 - 1j * G * E)


def test_eps1_from_eps2_exact_lorentz():
    E = np.geomspace(1e-4, 2000, 40000)
    x = np.linspace(1.0, 3.5, 60)
    e1 = eps1_from_eps2(lorentz(E).imag, energy_ev=E, at_energy_ev=x, eps_inf=1.0)
    np.testing.assert_allclose(e1, lorentz(x).real, atol=3e-5)


def test_eps2_from_eps1_exact_lorentz():
    E = np.geomspace(1e-7, 2000, 40000)
    x = np.linspace(1.0, 3.5, 60)
    e2 = eps2_from_eps1(lorentz(E).real, energy_ev=E, at_energy_ev=x, eps_inf=1.0)
    np.testing.assert_allclose(e2, lorentz(x).imag, atol=3e-4)


def test_on_a_wavelength_grid_at_its_own_nodes():
    w = np.geomspace(1.0, 1e7, 3000)  # wavelength grid, non-uniform in energy
    e = lorentz(HC_EV_NM / w)
    e1 = eps1_from_eps2(e.imag, w)
    sel = (w > 400) & (w < 900)
    np.testing.assert_allclose(e1[sel], e.real[sel], atol=3e-3)  # O(h²) sampling error of the grid


def test_consistency_report_flags_a_broken_material():
    w = np.linspace(250, 2000, 800)
    good = Lorentz(oscillators=[(A, E0, G)], range_nm=(250, 2000))
    nk = good.nk(w)
    report = kk_consistency(good)
    assert report.consistent(0.01), str(report)
    # change the absorption without changing the index: the package must say so
    broken = TabulatedMaterial("broken", w, nk.real, nk.imag * 1.5)
    assert not kk_consistency(broken).consistent(0.01)


def test_transparent_cauchy_has_small_deviation_only_from_background():
    r = kk_consistency(Cauchy(A=1.5, B=0.004, range_nm=(400, 1000)))
    assert r.max_abs < 1e-3


def test_gold_data_report_against_scipy_quadrature():
    """On measured data (Johnson & Christy gold) the report's KK index, less its fitted background
    c0 + c_uv E² + c_ir/E², equals (2/π) P∫ E'k(E')/(E'² − E²) dE' of the linearly interpolated k,
    integrated here by QUADPACK (Cauchy weight on the two segments around E, plain elsewhere)."""
    from scipy import integrate

    au = get("main/Au/Johnson")
    r = kk_consistency(au, n_points=300)
    assert r.n_kk.shape == r.n.shape and np.isfinite(r.rms)
    E = HC_EV_NM / r.wavelength_nm
    k = au.nk(r.wavelength_nm).imag
    c0, c_uv, c_ir = r.background
    n_int = r.n_kk - (c0 + c_uv * E**2 + c_ir / E**2)
    kin = lambda e: np.interp(e, E, k)  # noqa: E731
    for i in (40, 150, 260):
        x = E[i]
        pv, _ = integrate.quad(lambda e: e * kin(e) / (e + x), E[i - 1], E[i + 1], weight="cauchy", wvar=x)
        rest = sum(integrate.quad(lambda e: e * kin(e) / (e * e - x * x), E[j], E[j + 1])[0]
                   for j in range(E.size - 1) if j not in (i - 1, i))
        assert n_int[i] == pytest.approx(2 / np.pi * (pv + rest), abs=1e-8)
