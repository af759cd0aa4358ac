"""Forward model: Ψ, Δ of stacks against pyElli, and the Δ sign convention."""

import numpy as np
import pytest

from nmmm.ellipsometry.forward import (bulk_rho, psi_delta, psi_delta_from_rho, rho_from_psi_delta,
                                       uniaxial_bulk_rho, wrap_delta)
from nmmm.errors import InvalidInputError
from nmmm.layers.thinfilm import Stack

elli = pytest.importorskip("elli")

W = np.linspace(300.0, 1000.0, 29)


@pytest.mark.parametrize("angle", [0.0, 45.0, 65.0, 75.0])
def test_film_on_silicon_matches_pyelli(silicon, angle, elli_table, ddelta):
    """A weakly absorbing 300 nm film on Si: Ψ, Δ equal pyElli's 2x2 solver."""
    film = 1.55 + 0.002j
    p, d = psi_delta(Stack([(film, 300.0)], ambient=1.0, substrate=silicon), W, angle)
    s = elli.Structure(elli.AIR, [elli.Layer(elli.IsotropicMaterial(elli.ConstantRefractiveIndex(film)), 300.0)],
                       elli_table(silicon, W))
    ref = s.evaluate(W, angle, solver=elli.Solver2x2)
    np.testing.assert_allclose(p, ref.psi, atol=1e-9)
    np.testing.assert_allclose(ddelta(d, ref.delta), 0.0, atol=1e-8)


def test_two_layers_and_metal_match_pyelli_4x4(silicon, elli_table, ddelta):
    """Cauchy film over a thin gold-like absorber on Si, several angles at once, vs pyElli 4x4."""
    from nmmm.materials import Cauchy

    cauchy = Cauchy(A=1.5, B=0.004)
    metal = 0.3 + 3.0j
    stack = Stack([(cauchy, 120.0), (metal, 15.0)], ambient=1.0, substrate=silicon)
    Wg, Ag = np.meshgrid(W, [50.0, 70.0], indexing="ij")
    p, d = psi_delta(stack, Wg, Ag)
    # pyElli's Cauchy: n0 + 100 n1/λ² (λ in nm) -> n1 = B[µm²]·1e4
    layers = [elli.Layer(elli.IsotropicMaterial(elli.Cauchy(n0=1.5, n1=0.004 * 1e4)), 120.0),
              elli.Layer(elli.IsotropicMaterial(elli.ConstantRefractiveIndex(metal)), 15.0)]
    s = elli.Structure(elli.AIR, layers, elli_table(silicon, W))
    for j, ang in enumerate([50.0, 70.0]):
        ref = s.evaluate(W, ang, solver=elli.Solver4x4)
        np.testing.assert_allclose(p[:, j], ref.psi, atol=1e-8)
        np.testing.assert_allclose(ddelta(d[:, j], ref.delta), 0.0, atol=1e-7)


def test_delta_convention_dielectric():
    """Δ = 180° at normal incidence and below Brewster's angle, 0° above (Fujiwara 2007 §4.4)."""
    glass = Stack([], ambient=1.0, substrate=1.5)
    brewster = np.degrees(np.arctan(1.5))
    p, d = psi_delta(glass, 500.0, np.array([0.0, 30.0, brewster - 5, brewster + 5, 80.0]))
    np.testing.assert_allclose(d, [180.0, 180.0, 180.0, 0.0, 0.0], atol=1e-9)
    assert p[0] == pytest.approx(45.0)  # |rp| = |rs| at normal incidence


def test_delta_convention_bulk_absorber():
    """0° < Δ < 180° for bulk absorbers (gold-like, silicon in the UV), as pyElli reports."""
    for n in (0.2 + 3.5j, 1.5 + 2.0j, 4.0 + 0.5j):
        _, d = psi_delta_from_rho(bulk_rho(n**2, np.array([20.0, 45.0, 70.0, 85.0])))
        assert np.all((d > 0) & (d < 180)), (n, d)
        s = elli.Structure(elli.AIR, [], elli.IsotropicMaterial(elli.ConstantRefractiveIndex(n)))
        ref = s.evaluate(np.array([500.0]), 70.0)
        np.testing.assert_allclose(psi_delta_from_rho(bulk_rho(n**2, 70.0))[1], ref.delta[0], atol=1e-9)


def test_rho_convention_matches_pyelli_calc_rho():
    """r_p/r_s = tanΨ e^{−iΔ}, pyElli's elli.utils.calc_rho."""
    import pandas as pd
    from elli.utils import calc_rho

    psi = np.array([10.0, 33.0, 60.0])
    delta = np.array([5.0, 120.0, 300.0])
    ref = calc_rho(pd.DataFrame({"Ψ": psi, "Δ": delta})).to_numpy()
    np.testing.assert_allclose(rho_from_psi_delta(psi, delta), ref, rtol=1e-14)
    p, d = psi_delta_from_rho(ref)
    np.testing.assert_allclose(p, psi)
    np.testing.assert_allclose(d, delta)


@pytest.mark.parametrize("orientation,rotation", [
    ("parallel", [[0, 0, 1.0], [0, 1, 0], [-1, 0, 0]]),       # c axis along x (plane of incidence)
    ("perpendicular", [[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]),  # c axis along y (s direction)
])
def test_uniaxial_bulk_matches_pyelli_4x4(orientation, rotation, ddelta):
    """Closed-form r_p/r_s of hematite (Querry o/e) with the c axis in the surface vs pyElli's 4x4."""
    from nmmm.materials import get

    o, e = get("main/Fe2O3/Querry-o"), get("main/Fe2O3/Querry-e")
    w = np.linspace(300.0, 800.0, 11)
    mat = elli.UniaxialMaterial(elli.Table(lbda=w, n=o.nk(w)), elli.Table(lbda=w, n=e.nk(w)))
    mat.set_rotation(np.array(rotation))
    s = elli.Structure(elli.AIR, [], mat)
    for ang in (55.0, 70.0):
        ref = s.evaluate(w, ang, solver=elli.Solver4x4)
        p, d = psi_delta_from_rho(uniaxial_bulk_rho(o.eps(w), e.eps(w), ang, orientation))
        np.testing.assert_allclose(p, ref.psi, atol=1e-9)
        np.testing.assert_allclose(ddelta(d, ref.delta), 0.0, atol=1e-8)


def test_wrap_delta():
    np.testing.assert_allclose(wrap_delta([359.0, -359.0, 180.0, -180.0, 10.0]), [-1.0, 1.0, 180.0, 180.0, 10.0])


def test_bad_angles_and_psi():
    with pytest.raises(InvalidInputError, match="90"):
        bulk_rho(2.25, 95.0)
    with pytest.raises(InvalidInputError, match=r"\[0, 90\]"):
        rho_from_psi_delta(95.0, 10.0)
    with pytest.raises(InvalidInputError):
        rho_from_psi_delta(np.nan, 10.0)
