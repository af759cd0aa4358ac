"""Issue 21: physically impossible inputs are named errors, not silent numbers or numpy tracebacks
(colour of a negative spectrum, L* < 0, k < 0 / eps2 < 0, a host of eps = 0, mismatched shapes,
a metre-sized Mie sphere, a Mie grid beyond the work limit)."""

import numpy as np
import pytest

import nmmm.layers.mie_scattering as mie_module
from nmmm.colour import delta_e2000, spectra_to_lab
from nmmm.ema import bruggeman, maxwell_garnett
from nmmm.errors import InvalidInputError
from nmmm.layers import mie
from nmmm.materials import eps_to_nk, nk_to_eps

W = np.arange(380, 781, 5.0)


def test_colour_of_a_negative_spectrum_is_refused():
    with pytest.raises(InvalidInputError, match="reflectance, transmittance or reflectance factor is >= 0"):
        spectra_to_lab(W, -np.ones_like(W))  # was L* = -903
    lab = spectra_to_lab(W, np.clip(np.full_like(W, 0.5) - 1e-9, 0, None))  # round-off is fine
    assert 0 < lab[0] < 100


def test_delta_e2000_refuses_negative_lightness():
    with pytest.raises(InvalidInputError, match="L\\* = -50 < 0"):
        delta_e2000([-50.0, 0, 0], [50.0, 0, 0])
    assert float(delta_e2000([50.0, 0, 0], [50.0, 0, 0])) == 0.0


def test_gain_is_refused_unless_asked_for():
    with pytest.raises(InvalidInputError, match="eps2 < 0"):
        eps_to_nk(2.0 - 0.5j)
    with pytest.raises(InvalidInputError, match="k < 0"):
        nk_to_eps(1.5 - 0.1j)
    nk = eps_to_nk(2.0 - 0.5j, allow_gain=True)
    assert nk.imag < 0 and abs(nk * nk - (2.0 - 0.5j)) < 1e-12  # same root as before, on request
    # an independent check of the passive root: (1.5 + 0.1i)^2 back to n, k
    np.testing.assert_allclose(eps_to_nk(nk_to_eps(1.5 + 0.1j)), 1.5 + 0.1j, rtol=1e-14)
    assert eps_to_nk(2.25 - 1e-18j).imag == 0.0  # round-off below zero is not gain


def test_mixing_rules_refuse_a_host_of_eps_zero():
    for f in (lambda: maxwell_garnett(2.0, 0.0, 0.1), lambda: bruggeman(2.0, 0.0, 0.1)):
        with pytest.raises(InvalidInputError, match="eps_host = 0"):
            f()  # were 0 and -1.56


def test_mismatched_shapes_are_named():
    with pytest.raises(InvalidInputError, match=r"eps_inclusion \(3,\), eps_host \(4,\)"):
        maxwell_garnett(np.full(3, 4.0), np.full(4, 2.25), 0.1)
    with pytest.raises(InvalidInputError, match="shapes do not broadcast"):
        bruggeman(np.full(3, 4.0), np.full(4, 2.25), 0.1)
    with pytest.raises(InvalidInputError, match=r"wavelength_nm \(4,\).*diameter_nm \(3,\)"):
        mie(1.5, 1.0, np.full(3, 200.0), np.full(4, 500.0))


def test_mie_refuses_a_sphere_beyond_the_series_and_a_grid_beyond_the_work_limit(monkeypatch):
    with pytest.raises(InvalidInputError, match="geometric-optics"):
        mie(1.5, 1.0, 1e9, 500.0)  # a 1 m sphere (pigment.body_diagonal_nm = 1e9): was > 420 s
    with pytest.raises(InvalidInputError, match="MIE_MAX_TERMS") as e:
        mie(1.5, 1.0, np.linspace(100, 5000, 2000)[None, :], np.linspace(400, 700, 20000)[:, None])
    assert "40,000,000" in str(e.value) and "min" in str(e.value) and "GB" in str(e.value)
    monkeypatch.setattr(mie_module, "MIE_MAX_TERMS", 1e5)  # the setting the message names
    with pytest.raises(InvalidInputError, match="MIE_MAX_TERMS"):
        mie(1.5, 1.0, np.linspace(100, 500, 1000)[None, :], np.linspace(400, 700, 200)[:, None])
    monkeypatch.setattr(mie_module, "MIE_MAX_TERMS", 1e12)
    r = mie(1.5, 1.0, np.linspace(100, 500, 1000)[None, :], np.linspace(400, 700, 200)[:, None])
    assert r.qext.shape == (200, 1000) and np.all(np.isfinite(r.qext))
