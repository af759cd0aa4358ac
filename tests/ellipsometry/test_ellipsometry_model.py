"""Layer models: TOML files, dispersion parameterisation, roughness layer (vs pyElli)."""

import numpy as np
import pytest

from nmmm.ellipsometry.forward import psi_delta
from nmmm.ellipsometry.model import EllipsometryModel, dispersion_material, read_model, roughness_material
from nmmm.errors import DataFileError, InvalidInputError, RecipeError

elli = pytest.importorskip("elli")

TOML = """
name = "rough epoxy on Si"
[substrate]
material = "main/Si/Green-2008"
[[layers]]
name = "rough"
roughness = true
thickness_nm = {value = 4.0, min = 0, max = 30}
[[layers]]
name = "epoxy"
thickness_nm = {value = 480, min = 10, max = 3000}
model = "cauchy"
A = {value = 1.55, min = 1.3, max = 1.8}
B = 0.007
"""


def test_toml_model_with_roughness_matches_pyelli(tmp_path, silicon, elli_table, ddelta):
    """Roughness = Bruggeman 50/50 of the film and void (pyElli BruggemanEMA), stack vs pyElli."""
    p = tmp_path / "m.toml"
    p.write_text(TOML)
    model = read_model(p)
    assert [q.name for q in model.parameters if q.vary] == ["rough.thickness_nm", "epoxy.thickness_nm", "epoxy.A"]
    w = np.linspace(300.0, 1000.0, 15)
    psi, delta = psi_delta(model.build(), w, 65.0)
    film = elli.IsotropicMaterial(elli.Cauchy(n0=1.55, n1=0.007 * 1e4))
    rough = elli.BruggemanEMA(film, elli.AIR, 0.5)
    s = elli.Structure(elli.AIR, [elli.Layer(rough, 4.0), elli.Layer(film, 480.0)], elli_table(silicon, w))
    ref = s.evaluate(w, 65.0, solver=elli.Solver2x2)
    np.testing.assert_allclose(psi, ref.psi, atol=1e-9)
    np.testing.assert_allclose(ddelta(delta, ref.delta), 0, atol=1e-8)


def test_roughness_medium_is_bruggeman(silicon):
    """ε of the roughness layer solves Bruggeman's equation with 50 % void."""
    w = np.linspace(300.0, 900.0, 7)
    e = roughness_material(silicon).eps(w)
    es = silicon.eps(w)
    np.testing.assert_allclose(0.5 * (1 - e) / (1 + 2 * e) + 0.5 * (es - e) / (es + 2 * e), 0, atol=1e-12)


def test_dispersion_models_against_pyelli():
    """Parameterised Tauc-Lorentz and Lorentz give pyElli's ε for the same parameters."""
    w = np.linspace(250.0, 1000.0, 16)
    tl = dispersion_material("tauc_lorentz", {"A": 120.0, "E0": 4.2, "C": 1.8, "Eg": 2.1, "eps_inf": 1.3})
    ref = elli.TaucLorentz(Eg=2.1).add(A=120.0, E=4.2, C=1.8) + elli.EpsilonInf(eps=1.3)
    np.testing.assert_allclose(tl.eps(w), ref.get_dielectric(w), rtol=1e-6)
    lo = dispersion_material("lorentz", {"eps_inf": 2.0, "oscillators[0].amplitude_ev2": 10.0,
                                         "oscillators[0].center_ev": 5.0, "oscillators[0].broadening_ev": 0.5})
    E = 1239.841984 / w
    np.testing.assert_allclose(lo.eps(w), 2.0 + 10.0 / (25.0 - E**2 - 0.5j * E))


def test_model_parameter_names_and_lists():
    m = EllipsometryModel.from_dict({
        "substrate": {"model": "lorentz", "eps_inf": {"value": 2.0},
                      "oscillators": [{"amplitude_ev2": 5.0, "center_ev": 3.0, "broadening_ev": {"value": 0.5}}]},
        "layers": [{"name": "glass", "model": "sellmeier", "thickness_nm": 100.0, "B": [0.69, {"value": 0.4}],
                    "C": [0.0047, 0.0135]},
                   {"name": "metal", "model": "drude", "thickness_nm": 10.0, "plasma_ev": {"value": 9.0},
                    "gamma_ev": 0.1}]})
    varied = [p.name for p in m.parameters if p.vary]
    assert varied == ["glass.B[1]", "metal.plasma_ev", "substrate.eps_inf", "substrate.oscillators[0].broadening_ev"]
    assert m.material("glass").n(600.0) > 1.3
    m.build()


def test_model_errors(tmp_path):
    with pytest.raises(RecipeError, match="substrate"):
        EllipsometryModel.from_dict({"layers": []})
    with pytest.raises(RecipeError, match="unknown model"):
        EllipsometryModel.from_dict({"substrate": {"model": "nonsense"}})
    with pytest.raises(RecipeError, match="unknown parameter"):
        EllipsometryModel.from_dict({"substrate": {"model": "cauchy", "A": 1.5, "Q": 2}})
    with pytest.raises(RecipeError, match="thickness_nm"):
        EllipsometryModel.from_dict({"substrate": 1.5, "layers": [{"name": "x", "n": 1.4}]})
    with pytest.raises(InvalidInputError, match="outside its bounds"):
        EllipsometryModel.from_dict({"substrate": {"model": "cauchy", "A": {"value": 5, "min": 1, "max": 2}}})
    for fv in (1.5, -0.1, "half"):
        with pytest.raises(RecipeError, match=r"fraction_void must be a volume fraction in \[0, 1\]"):
            EllipsometryModel.from_dict({"substrate": 1.5, "layers": [
                {"name": "r", "roughness": True, "thickness_nm": 3.0, "fraction_void": fv}]})
    with pytest.raises(RecipeError, match="only to a roughness layer"):
        EllipsometryModel.from_dict({"substrate": 1.5, "layers": [
            {"name": "x", "n": 1.4, "thickness_nm": 3.0, "fraction_void": 0.3}]})
    p = tmp_path / "bad.toml"
    p.write_text("substrate = [\n")
    with pytest.raises(DataFileError, match="TOML"):
        read_model(p)


def test_fit_options_validated():
    with pytest.raises(RecipeError, match=r"\[fit\]"):
        EllipsometryModel.from_dict({"substrate": 1.5, "fit": {"wavelength_min": 300}})
