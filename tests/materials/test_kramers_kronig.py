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


def test_gold_data_report_runs():
    r = kk_consistency(get("main/Au/Johnson"))
    assert np.isfinite(r.rms) and r.n_kk.shape == r.n.shape
