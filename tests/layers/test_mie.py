"""Mie scattering against independent references.

- miepython (Prahl, numba/NumPy Mie code) run inside the test on the same inputs;
- Bohren & Huffman's BHMIE listing (appendix A, p. 482): m = 1.55, λ = 0.6328 µm,
  radius 0.525 µm in vacuum -> Q_ext = Q_sca = 3.10543, Q_back = 2.92534;
- the optical theorem Q_ext = 4 Re S(0) / x² (BH eq. 4.76);
- the electrostatic (Rayleigh) limit of a coated sphere (BH eq. 5.36) and the limits
  core = shell and shell = host of the layered solution.
"""

import os

import numpy as np
import pytest

os.environ.setdefault("MIEPYTHON_USE_JIT", "0")
miepython = pytest.importorskip("miepython")

from nmmm.errors import InvalidInputError  # noqa: E402
from nmmm.layers.mie_scattering import mie, mie_coated, mie_multilayer  # noqa: E402

M_VALUES = [1.5 + 0.01j, 1.33 + 1e-8j, 2.9 + 0.3j, 1.05 + 0j, 0.2 + 3.0j, 10 + 10j]
X_VALUES = [0.3, 1.0, 3.0, 10.0, 30.0, 120.0]


def test_bhmie_listing():
    r = mie(1.55, 1.0, 1050.0, 632.8)
    assert float(r.qext) == pytest.approx(3.10543, abs=1e-5)
    assert float(r.qsca) == pytest.approx(3.10543, abs=1e-5)
    assert float(r.qback) == pytest.approx(2.92534, abs=1e-5)


@pytest.mark.parametrize("m", M_VALUES)
def test_homogeneous_against_miepython(m):
    x = np.array(X_VALUES)
    wavelength = 500.0
    d = x * wavelength / np.pi
    r = mie(m, 1.0, d, wavelength)
    qext, qsca, qback, g = miepython.efficiencies_mx(np.full(x.size, m), x)
    np.testing.assert_allclose(r.qext, qext, rtol=1e-9)
    np.testing.assert_allclose(r.qsca, qsca, rtol=1e-9)
    np.testing.assert_allclose(r.qback, qback, rtol=1e-7)
    np.testing.assert_allclose(r.g, g, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(r.qabs, qext - qsca, atol=1e-9)


def test_host_medium_scaling_against_miepython():
    # a sphere of index 2.0+0.1i in water: miepython's n_env path on a wavelength x diameter grid
    w = np.linspace(400, 700, 7)
    d = np.array([50.0, 200.0, 800.0])
    r = mie(2.0 + 0.1j, 1.33, d[None, :], w[:, None])
    assert r.qext.shape == (7, 3)
    W, D = np.meshgrid(w, d, indexing="ij")
    qext, qsca, qback, g = miepython.efficiencies(2.0 + 0.1j, D.ravel(), W.ravel(), n_env=1.33)
    np.testing.assert_allclose(r.qext.ravel(), qext, rtol=1e-9)
    np.testing.assert_allclose(r.qsca.ravel(), qsca, rtol=1e-9)
    np.testing.assert_allclose(r.g.ravel(), g, rtol=1e-9)


def test_amplitudes_against_miepython_and_optical_theorem():
    ang = np.linspace(0, 180, 19)
    m, x = 1.5 + 0.1j, 4.0
    r = mie(m, 1.0, x * 600 / np.pi, 600.0, angles_deg=ang)
    s1, s2 = miepython.S1_S2(m, x, np.cos(np.radians(ang)), norm="wiscombe")
    # miepython uses exp(+i omega t): its amplitudes are the complex conjugates of BH's
    np.testing.assert_allclose(r.s1, np.conj(s1), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(r.s2, np.conj(s2), rtol=1e-9, atol=1e-12)
    # optical theorem (BH eq. 4.76)
    assert float(r.qext) == pytest.approx(4 * r.s1[0].real / x**2, rel=1e-12)
    # integrating the differential cross section gives C_sca
    mu, wq = np.polynomial.legendre.leggauss(200)
    r2 = mie(m, 1.0, x * 600 / np.pi, 600.0, angles_deg=np.degrees(np.arccos(mu)))
    csca = 2 * np.pi * np.sum(wq * r2.differential_cross_section_nm2())
    assert csca == pytest.approx(float(r2.csca_nm2), rel=1e-9)


def test_non_absorbing_sphere_does_not_absorb():
    r = mie(1.6 + 0j, 1.5, np.geomspace(10, 5000, 40), 550.0)
    np.testing.assert_allclose(r.qabs, 0.0, atol=1e-10)


def test_coated_core_equal_shell_is_homogeneous():
    w = np.linspace(400, 700, 4)[:, None]
    d = np.array([80.0, 300.0, 1200.0])[None, :]
    hom = mie(2.2 + 0.2j, 1.5, d, w)
    coat = mie_coated(2.2 + 0.2j, 2.2 + 0.2j, 1.5, 0.6 * d, d, w)
    for q in ("qext", "qsca", "qback", "g"):
        np.testing.assert_allclose(getattr(coat, q), getattr(hom, q), rtol=1e-9)


def test_coated_shell_matching_host_is_the_bare_core():
    # a shell with the host's index is invisible: cross sections are the core's
    d_core, d = 300.0, 500.0
    core = mie(2.0 + 0.5j, 1.5, d_core, 600.0)
    coat = mie_coated(2.0 + 0.5j, 1.5, 1.5, d_core, d, 600.0)
    assert float(coat.cext_nm2) == pytest.approx(float(core.cext_nm2), rel=1e-9)
    assert float(coat.csca_nm2) == pytest.approx(float(core.csca_nm2), rel=1e-9)
    assert float(coat.g) == pytest.approx(float(core.g), rel=1e-9)


def test_coated_rayleigh_limit():
    # BH eq. 5.36: polarizability of a small coated sphere (relative permittivities)
    e1, e2 = (3.0 + 0.4j) ** 2, (1.8 + 0.05j) ** 2
    a, b = 2.0, 3.0  # nm radii
    lam = 1000.0
    f = (a / b) ** 3
    alpha = 4 * np.pi * b**3 * ((e2 - 1) * (e1 + 2 * e2) + f * (e1 - e2) * (1 + 2 * e2)) / (
        (e2 + 2) * (e1 + 2 * e2) + f * (2 * e2 - 2) * (e1 - e2)
    )
    k = 2 * np.pi / lam
    cabs = k * alpha.imag
    csca = k**4 * abs(alpha) ** 2 / (6 * np.pi)
    r = mie_coated(np.sqrt(e1), np.sqrt(e2), 1.0, 2 * a, 2 * b, lam)
    assert float(r.cabs_nm2) == pytest.approx(cabs, rel=1e-3)
    assert float(r.csca_nm2) == pytest.approx(csca, rel=1e-3)


def test_three_layer_with_repeated_layers_matches_coated():
    d = np.array([100.0, 250.0, 400.0])
    three = mie_multilayer([1.9 + 0.3j, 1.9 + 0.3j, 1.4 + 0j], 1.33, [d[0], d[1], d[2]], 550.0)
    two = mie_coated(1.9 + 0.3j, 1.4 + 0j, 1.33, d[1], d[2], 550.0)
    for q in ("qext", "qsca", "qback", "g"):
        assert float(getattr(three, q)) == pytest.approx(float(getattr(two, q)), rel=1e-9)


def test_material_inputs():
    from nmmm.materials.material import TabulatedMaterial

    mat = TabulatedMaterial("x", np.array([300.0, 900.0]), np.array([2.0, 2.0]), np.array([0.1, 0.1]))
    w = np.array([400.0, 600.0])
    np.testing.assert_allclose(mie(mat, 1.5, 200.0, w).qext, mie(2.0 + 0.1j, 1.5, 200.0, w).qext)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(n_particle=1.5 - 0.1j), "n_particle has k < 0"),
        (dict(n_particle=np.nan), "n_particle contains NaN"),
        (dict(diameter_nm=0.0), "diameter_nm must be > 0"),
        (dict(diameter_nm=-5.0), "diameter_nm must be > 0"),
        (dict(n_medium=1.5 + 0.01j), "absorbing"),
        (dict(wavelength_nm=np.nan), "NaN"),
    ],
)
def test_bad_input(kwargs, match):
    args = dict(n_particle=1.5 + 0.1j, n_medium=1.33, diameter_nm=100.0, wavelength_nm=500.0)
    args.update(kwargs)
    with pytest.raises(InvalidInputError, match=match):
        mie(**args)


def test_bad_layer_order():
    with pytest.raises(InvalidInputError, match="increase"):
        mie_coated(1.5, 2.0, 1.0, 300.0, 200.0, 500.0)


def test_lossless_layered_sphere_conserves_energy_and_optical_theorem():
    # real indices: each multipole is unitary (Re a_n = |a_n|^2), so Q_abs = 0 exactly
    d = np.array([300.0, 900.0, 2500.0])
    r = mie_multilayer([2.4 + 0j, 1.3 + 0j, 1.7 + 0j], 1.33, [0.4 * d, 0.7 * d, d], 500.0, angles_deg=[0.0])
    np.testing.assert_allclose(r.qabs, 0.0, atol=1e-9)
    x = r.size_parameter
    np.testing.assert_allclose(r.qext, 4 * r.s1[..., 0].real / x**2, rtol=1e-10)
