"""Joint fits with shared parameters: two Cauchy films of one resin on Si, data made by pyElli."""

import warnings

import numpy as np
import pytest

from nmmm.ellipsometry.data import EllipsometryData
from nmmm.ellipsometry.fitting import FitAtBoundWarning, Parameter
from nmmm.ellipsometry.joint import fit_joint, joint_parameter_names
from nmmm.ellipsometry.model import EllipsometryModel
from nmmm.errors import InvalidInputError

elli = pytest.importorskip("elli")

# an epoxy-like resin: n = A + B/λ² + C/λ⁴ (λ in µm), n(589 nm) ≈ 1.585
TRUTH = {"A": 1.565, "B": 0.0065, "C": 0.00015}
W = np.arange(400.0, 1001.0, 10.0)
ANGLES = (65.0, 75.0)
SIGMA_PSI, SIGMA_DELTA = 0.02, 0.1


def film_model(thickness, name="epoxy"):
    return EllipsometryModel.from_dict({
        "substrate": {"material": "main/Si/Green-2008"},
        "layers": [{"name": name, "model": "cauchy",
                    "thickness_nm": {"value": thickness, "min": 10, "max": 3000},
                    "A": {"value": 1.55, "min": 1.3, "max": 1.9}, "B": {"value": 0.005, "min": -0.1, "max": 0.2},
                    "C": {"value": 0.0, "min": -0.01, "max": 0.01}}]})


def pyelli_data(silicon, elli_table, thickness_nm, noise_seed=None):
    """Ψ, Δ of a Cauchy film on Si by pyElli (pyElli's Cauchy: n0 + 1e2·n1/λ² + 1e7·n2/λ⁴, λ in nm),
    with Gaussian noise of σΨ, σΔ when a seed is given."""
    film = elli.IsotropicMaterial(elli.Cauchy(n0=TRUTH["A"], n1=TRUTH["B"] * 1e4, n2=TRUTH["C"] * 1e5))
    s = elli.Structure(elli.AIR, [elli.Layer(film, thickness_nm)], elli_table(silicon, W))
    ww, aa, pp, dd = [], [], [], []
    for ang in ANGLES:
        r = s.evaluate(W, ang, solver=elli.Solver2x2)
        ww.append(W), aa.append(np.full(W.shape, ang)), pp.append(r.psi), dd.append(r.delta)
    psi, delta = np.concatenate(pp), np.concatenate(dd)
    if noise_seed is None:
        return EllipsometryData(np.concatenate(ww), np.concatenate(aa), psi, delta)
    rng = np.random.default_rng(noise_seed)
    return EllipsometryData(np.concatenate(ww), np.concatenate(aa), psi + rng.normal(0, SIGMA_PSI, psi.shape),
                            delta + rng.normal(0, SIGMA_DELTA, delta.shape),
                            np.full(psi.shape, SIGMA_PSI), np.full(psi.shape, SIGMA_DELTA))


@pytest.fixture(scope="module")
def noisy(silicon, elli_table):
    return pyelli_data(silicon, elli_table, 300.0, 1), pyelli_data(silicon, elli_table, 900.0, 2)


def test_joint_fit_recovers_pyelli_parameters_and_tightens_A(noisy):
    """Joint fit of a 300 nm and a 900 nm film (shared A, B, C; one thickness each): every
    estimate within 3 reported σ of pyElli's truth, MSE ≈ 1, and σ(A) smaller than that of
    either film fitted alone — the reason for fitting them jointly."""
    d300, d900 = noisy
    with warnings.catch_warnings():
        warnings.simplefilter("error", FitAtBoundWarning)
        res = fit_joint([(d300, film_model(310.0)), (d900, film_model(890.0))], shared=["A", "B", "C"])
    assert set(res.names) == {"epoxy.A", "epoxy.B", "epoxy.C", "epoxy.thickness_nm[0]", "epoxy.thickness_nm[1]"}
    truth = {"epoxy.A": TRUTH["A"], "epoxy.B": TRUTH["B"], "epoxy.C": TRUTH["C"],
             "epoxy.thickness_nm[0]": 300.0, "epoxy.thickness_nm[1]": 900.0}
    for name, t in truth.items():
        assert abs(res[name] - t) < 3 * res.stderr[name], (name, res[name], t, res.stderr[name])
    assert 0.8 < res.mse < 1.2
    assert res.dof == 2 * (d300.psi_deg.size + d900.psi_deg.size) - 5
    np.testing.assert_allclose(sum(res.extra["chi2_per_dataset"]), res.chi2, rtol=1e-9)
    np.testing.assert_allclose(np.diag(res.correlation), 1.0)
    # per-data-set views use each model's own names
    assert res.extra["values"][1]["epoxy.thickness_nm"] == res["epoxy.thickness_nm[1]"]
    assert res.extra["models"][0].values["epoxy.A"] == res["epoxy.A"]
    singles = [film_model(310.0).fit(d300), film_model(890.0).fit(d900)]
    for single in singles:
        assert res.stderr["epoxy.A"] < single.stderr["epoxy.A"]
    assert "epoxy.thickness_nm[1]" in res.summary()


def test_joint_round_trip_on_exact_pyelli_data(silicon, elli_table):
    """Exact pyElli data of both films: the joint fit returns the parameters to ~1e-6."""
    data = [pyelli_data(silicon, elli_table, t) for t in (300.0, 900.0)]
    res = fit_joint([(data[0], film_model(305.0)), (data[1], film_model(895.0))], shared="A,B,C")
    assert res["epoxy.thickness_nm[0]"] == pytest.approx(300.0, rel=1e-6)
    assert res["epoxy.thickness_nm[1]"] == pytest.approx(900.0, rel=1e-6)
    assert res["epoxy.A"] == pytest.approx(TRUTH["A"], rel=1e-6)
    assert res["epoxy.B"] == pytest.approx(TRUTH["B"], rel=1e-5)
    assert res["epoxy.C"] == pytest.approx(TRUTH["C"], abs=1e-8)
    assert res.chi2 < 1e-10


def test_shared_name_resolution_and_generic_builders():
    """Full names and layer names differing between models; (data, build, parameters) triples."""
    maps = joint_parameter_names([["a.thickness_nm", "a.A"], ["b.thickness_nm", "b.A"]], ["A"])
    assert maps == [{"a.thickness_nm": "a.thickness_nm[0]", "a.A": "a.A"},
                    {"b.thickness_nm": "b.thickness_nm[1]", "b.A": "a.A"}]
    m1, m2 = film_model(300.0, "resin1"), film_model(900.0, "resin2")
    truth = {"A": 1.56, "B": 0.006, "C": 0.0}
    d1 = EllipsometryData.from_model(m1.build({**m1.values, "resin1.A": truth["A"], "resin1.B": truth["B"]}),
                                     W[::3], [70.0])
    d2 = EllipsometryData.from_model(m2.build({**m2.values, "resin2.A": truth["A"], "resin2.B": truth["B"]}),
                                     W[::3], [70.0])
    fixed_c = [p if not p.name.endswith(".C") else Parameter(p.name, 0.0, False) for p in m2.parameters]
    res = fit_joint([(d1, m1), (d2, m2.build, fixed_c)], shared=["resin1.A", "B"])
    assert res["resin1.A"] == pytest.approx(1.56, abs=1e-7)
    assert "resin2.A" not in res.values and "resin2.C[1]" in res.values
    assert res.extra["models"][1] is None


def test_bad_input_is_rejected(noisy):
    d300, d900 = noisy
    with pytest.raises(InvalidInputError, match="empty"):
        fit_joint([], shared=["A"])
    with pytest.raises(InvalidInputError, match="not a parameter of data set 1"):
        fit_joint([(d300, film_model(300.0)), (d900, EllipsometryModel.from_dict({
            "substrate": {"material": "main/Si/Green-2008"},
            "layers": [{"name": "epoxy", "model": "sellmeier", "thickness_nm": {"value": 900.0},
                        "A": 1.0, "B": [1.3], "C": [0.01]}]}))], shared=["A", "B"])
    with pytest.raises(InvalidInputError, match="not a parameter"):
        fit_joint([(d300, film_model(300.0)), (d900, film_model(900.0))], shared=["n_inf"])
    no_sigma = EllipsometryData(d900.wavelength_nm, d900.angle_deg, d900.psi_deg, d900.delta_deg)
    with pytest.raises(InvalidInputError, match="sigma"):
        fit_joint([(d300, film_model(300.0)), (no_sigma, film_model(900.0))], shared=["A"])
    with pytest.raises(InvalidInputError, match=r"expected \(data, EllipsometryModel\)"):
        fit_joint([d300], shared=["A"])
