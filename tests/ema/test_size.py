"""Size-corrected Maxwell Garnett: a1 against miepython, limits, extinction, warnings."""

import warnings

import numpy as np
import pytest

from nmmm.ema import (
    SizeValidityWarning,
    check_quasi_static,
    dipole_polarizability_mie,
    maxwell_garnett,
    maxwell_garnett_mie,
    mie_a1,
    size_parameter,
)
from nmmm.errors import InvalidInputError

miepython = pytest.importorskip("miepython")


@pytest.mark.parametrize("m", [1.5 + 0j, 1.33 + 0.001j, 0.3 + 2.5j, 0.05 + 4.0j, 2.9 + 0.3j, 0.2 + 1.7j])
def test_a1_matches_miepython(m):
    x = np.geomspace(1e-4, 5.0, 40)
    ours = mie_a1(m, x)
    ref = np.array([miepython.an_bn(m, xi, 1)[0][0] for xi in x])
    np.testing.assert_allclose(ours, ref, rtol=1e-7)


def test_polarizability_tends_to_quasi_static():
    ei, em = -5.6 + 2.1j, 2.13
    alpha = dipole_polarizability_mie(ei, em, 0.01, 500.0)
    np.testing.assert_allclose(alpha, 3 * (ei - em) / (ei + 2 * em), rtol=1e-6)  # O(x²), x ~ 2e-4
    np.testing.assert_allclose(maxwell_garnett_mie(ei, em, 0.2, 0.01, 500.0), maxwell_garnett(ei, em, 0.2), rtol=1e-6)


def test_dilute_extinction_matches_full_mie(gold_silica):
    """Dilute limit: the coherent-beam attenuation 4πk/λ of the size-corrected medium equals
    N·C_ext of the spheres (full Mie series from miepython) while the dipole dominates."""
    w, _, _, ea, es = gold_silica
    sel = slice(100, 500, 20)  # 400–880 nm
    w, ea, es = w[sel], ea[sel], es[sel]
    p, r = 1e-6, 10.0
    eps = maxwell_garnett_mie(ea, es, p, r, w)
    nk = np.sqrt(eps)
    att = 4 * np.pi * nk.imag / w
    n_m = np.sqrt(es).real
    m = np.sqrt(ea)  # miepython takes the absolute index with n_env
    qext = np.array([miepython.efficiencies(mi, 2 * r, wi, n_env=ni)[0] for mi, wi, ni in zip(m, w, n_m)])
    ref = p / (4 / 3 * np.pi * r**3) * qext * np.pi * r**2
    np.testing.assert_allclose(att, ref, rtol=0.02)


def test_red_shift_with_size(gold_silica):
    w, _, _, ea, es = gold_silica
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SizeValidityWarning)
        peaks = [w[np.argmax(maxwell_garnett_mie(ea, es, 1e-4, r, w).imag)] for r in (2.0, 20.0, 40.0)]
    assert peaks[0] < peaks[1] < peaks[2]


def test_warnings_and_errors():
    with pytest.warns(SizeValidityWarning) as record:
        maxwell_garnett_mie(-5 + 2j, 2.25, 0.01, 150.0, 500.0)
    messages = " ".join(str(r.message) for r in record)
    assert "size parameter" in messages and "quadrupole" in messages
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        maxwell_garnett_mie(-5 + 2j, 2.25, 0.01, 20.0, 500.0)
    with pytest.warns(SizeValidityWarning, match="quasi-static"):
        check_quasi_static(125.0, 400.0, 1.55**2)
    np.testing.assert_allclose(size_parameter(50.0, 500.0, 2.25), 2 * np.pi * 1.5 * 50 / 500)
    with pytest.raises(InvalidInputError):
        size_parameter(-1.0, 500.0, 2.25)
    with pytest.raises(InvalidInputError):
        mie_a1(1.5 - 0.1j, 1.0)


@pytest.mark.parametrize("m,x", [(1.5 + 0.1j, 1.0), (0.2 + 3.5j, 0.5), (0.3 + 2j, 3.0), (2.9 + 0.3j, 0.8)])
def test_low_orders_match_miepython(m, x):
    from nmmm.ema import mie_low_orders

    a, b = miepython.an_bn(m, x, 2)
    np.testing.assert_allclose(mie_low_orders(m, x), [a[0], b[0], a[1], b[1]], rtol=1e-10)


def test_neglected_multipoles_warning(gold_silica):
    from nmmm.ema import check_dipole_validity, neglected_multipole_fraction

    w, _, _, ea, es = gold_silica
    small = neglected_multipole_fraction(ea, es, 5.0, w)
    big = neglected_multipole_fraction(ea, es, 45.0, w)
    assert small.max() < 0.01 and big.max() > 0.1  # the quadrupole appears for ~90 nm gold
    with pytest.warns(SizeValidityWarning) as record:
        check_dipole_validity(ea, es, 45.0, w)
    assert any("quadrupole" in str(r.message) for r in record)
