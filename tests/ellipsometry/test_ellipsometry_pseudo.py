"""Pseudo-dielectric inversion of bulk samples: exact data return the material's ε."""

import numpy as np
import pandas as pd
import pytest

from nmmm.ellipsometry.data import EllipsometryData
from nmmm.ellipsometry.pseudo_dielectric_function import pseudo_dielectric, pseudo_dielectric_material
from nmmm.errors import InvalidInputError

elli = pytest.importorskip("elli")


@pytest.mark.parametrize("angle", [55.0, 70.0, 80.0])
def test_bulk_silicon_from_pyelli_data(silicon, angle, elli_table):
    """Ψ, Δ of bare Si computed by pyElli, inverted: ⟨ε⟩ equals the database ε."""
    w = np.linspace(260.0, 1200.0, 48)
    ref = elli.Structure(elli.AIR, [], elli_table(silicon, w)).evaluate(w, angle, solver=elli.Solver2x2)
    eps = pseudo_dielectric(ref.psi, ref.delta, angle)
    np.testing.assert_allclose(eps, silicon.eps(w), rtol=1e-9)
    assert np.all(eps.imag >= 0)


def test_matches_pyelli_calc_pseudo_diel():
    """Same ⟨ε⟩ as pyElli's elli.utils.calc_pseudo_diel on arbitrary Ψ, Δ."""
    from elli.utils import calc_pseudo_diel, calc_rho

    psi = np.array([12.0, 25.0, 40.0, 43.0])
    delta = np.array([170.0, 120.0, 100.0, 20.0])
    rho = calc_rho(pd.DataFrame({"Ψ": psi, "Δ": delta}))
    ref = calc_pseudo_diel(rho, 65.0, output="epsi").to_numpy()
    np.testing.assert_allclose(pseudo_dielectric(psi, delta, 65.0), ref, rtol=1e-13)


def test_gold_like_metal_analytic():
    """A Drude-like metal ε = −10 + 1.5i, Ψ/Δ from Fresnel written out here, back to ε."""
    eps = -10.0 + 1.5j
    th = np.radians(70.0)
    kz = np.sqrt(eps - np.sin(th) ** 2)
    rs = (np.cos(th) - kz) / (np.cos(th) + kz)
    rp = (eps * np.cos(th) - kz) / (eps * np.cos(th) + kz)
    rho = rp / rs
    psi, delta = np.degrees(np.arctan(abs(rho))), -np.degrees(np.angle(rho))
    assert 0 < delta < 180
    assert pseudo_dielectric(psi, delta, 70.0) == pytest.approx(eps, rel=1e-12)


def test_material_from_data(silicon, elli_table):
    w = np.linspace(300.0, 900.0, 13)
    ref = elli.Structure(elli.AIR, [], elli_table(silicon, w)).evaluate(w, 70.0)
    data = EllipsometryData(w[::-1], 70.0, ref.psi[::-1], ref.delta[::-1])  # unsorted on purpose
    mat = pseudo_dielectric_material(data)
    np.testing.assert_allclose(mat.nk(w), silicon.nk(w), rtol=1e-9)


def test_bad_input():
    with pytest.raises(InvalidInputError, match="oblique"):
        pseudo_dielectric(45.0, 180.0, 0.0)
    with pytest.raises(InvalidInputError, match=r"\[0, 90\]"):
        pseudo_dielectric(-3.0, 100.0, 70.0)
    # Δ in (180°, 360°) is not a bulk absorber in this convention: clear error for a Material
    data = EllipsometryData([500.0, 600.0], 70.0, [20.0, 20.0], [250.0, 250.0])
    with pytest.raises(InvalidInputError, match="Delta"):
        pseudo_dielectric_material(data)
