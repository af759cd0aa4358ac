"""Fitting: round trips model -> data -> fit, data made by pyElli, uncertainties, failures."""

import warnings

import numpy as np
import pytest

from nmmm.ellipsometry.data import EllipsometryData
from nmmm.ellipsometry.fitting import FitAtBoundWarning, Parameter, fit_psi_delta
from nmmm.ellipsometry.model import EllipsometryModel
from nmmm.errors import ConvergenceError, InvalidInputError

elli = pytest.importorskip("elli")


def epoxy_model(thickness=500.0, A=1.5, B=0.005, fit_C=False):
    return EllipsometryModel.from_dict({
        "substrate": {"material": "main/Si/Green-2008"},
        "layers": [{"name": "epoxy", "model": "cauchy",
                    "thickness_nm": {"value": thickness, "min": 10, "max": 3000},
                    "A": {"value": A, "min": 1.2, "max": 2.0}, "B": {"value": B, "min": -0.1, "max": 0.2},
                    "C": {"value": 0.0, "fit": fit_C, "min": -0.01, "max": 0.01}}]})


def test_fit_data_made_by_pyelli(silicon, elli_table):
    """Ψ, Δ of a Cauchy film on Si computed by pyElli at 3 angles are fitted back to pyElli's
    parameters (an independent forward model: exact data, so the fit must be exact)."""
    w = np.arange(350.0, 1000.0, 10.0)
    t_true, n0, b_um2 = 437.0, 1.562, 0.0081
    film = elli.IsotropicMaterial(elli.Cauchy(n0=n0, n1=b_um2 * 1e4))
    s = elli.Structure(elli.AIR, [elli.Layer(film, t_true)], elli_table(silicon, w))
    W, A, P, D = [], [], [], []
    for ang in (55.0, 65.0, 75.0):
        r = s.evaluate(w, ang, solver=elli.Solver2x2)
        W.append(w), A.append(np.full(w.shape, ang)), P.append(r.psi), D.append(r.delta)
    data = EllipsometryData(np.concatenate(W), np.concatenate(A), np.concatenate(P), np.concatenate(D))
    res = epoxy_model(thickness=420.0, A=1.54, B=0.006).fit(data)
    assert res["epoxy.thickness_nm"] == pytest.approx(t_true, abs=1e-5)
    assert res["epoxy.A"] == pytest.approx(n0, abs=1e-8)
    assert res["epoxy.B"] == pytest.approx(b_um2, abs=1e-8)
    assert res.chi2 < 1e-12
    assert np.all(np.isfinite(res.correlation)) and np.allclose(np.diag(res.correlation), 1.0)  # exact data


def test_round_trip_with_noise_within_uncertainties():
    """model -> noisy data -> fit: estimates within 4σ, MSE ≈ 1, correlation matrix symmetric."""
    model = epoxy_model(fit_C=True)
    truth = dict(model.values, **{"epoxy.thickness_nm": 523.0, "epoxy.A": 1.552, "epoxy.B": 0.0071,
                                  "epoxy.C": 0.0002})
    data = EllipsometryData.from_model(model.build(truth), np.linspace(400, 1000, 61), [60.0, 70.0],
                                       0.02, 0.08, noise_seed=11)
    with warnings.catch_warnings():
        warnings.simplefilter("error", FitAtBoundWarning)  # an interior optimum: no warning
        res = model.fit(data)
    assert res.at_bound == ()
    for name in res.names:
        assert abs(res[name] - truth[name]) < 4 * res.stderr[name], name
    assert 0.8 < res.mse < 1.2
    np.testing.assert_allclose(res.correlation, res.correlation.T)
    np.testing.assert_allclose(np.diag(res.correlation), 1.0)
    assert "epoxy.thickness_nm" in res.summary()


def test_uncertainties_match_monte_carlo_scatter():
    """The reported σ of thickness and A equal the scatter of estimates over repeated noisy
    measurements (Monte Carlo), within the sampling error of 25 repetitions."""
    model = epoxy_model()
    truth = dict(model.values, **{"epoxy.thickness_nm": 300.0, "epoxy.A": 1.55, "epoxy.B": 0.006})
    stack = model.build(truth)
    w = np.linspace(450, 900, 19)
    est, errs = [], []
    start = model.with_values(truth)
    for seed in range(25):
        data = EllipsometryData.from_model(stack, w, [65.0], 0.05, 0.2, noise_seed=seed)
        res = start.fit(data)
        est.append([res[n] for n in res.names])
        errs.append([res.stderr[n] for n in res.names])
    ratio = np.std(est, axis=0, ddof=1) / np.mean(errs, axis=0)
    assert np.all((ratio > 0.6) & (ratio < 1.45)), ratio


def test_fewer_data_than_parameters():
    model = epoxy_model(fit_C=True)
    data = EllipsometryData([500.0], [70.0], [30.0], [100.0])  # 2 residuals, 4 parameters
    with pytest.raises(InvalidInputError, match="more data than parameters"):
        model.fit(data)


def test_not_converged_raises_with_history():
    model = epoxy_model(thickness=800.0)
    data = EllipsometryData.from_model(model.build(dict(model.values, **{"epoxy.thickness_nm": 500.0})),
                                       np.linspace(400, 1000, 31), [70.0])
    with pytest.raises(ConvergenceError, match="did not converge") as info:
        model.fit(data, max_nfev=3)
    assert info.value.history and len(info.value.history) >= 3


def test_undetermined_parameter_raises():
    """A parameter with no effect on Ψ, Δ (Urbach amplitude with a zero exponent of a vanishing
    tail... simplest: a parameter the model ignores) -> singular Jacobian -> ConvergenceError."""
    model = epoxy_model()
    data = EllipsometryData.from_model(model.build(), np.linspace(400, 1000, 31), [70.0])

    def build(values):
        return model.build({k: v for k, v in values.items() if k != "unused"})

    params = list(model.parameters) + [Parameter("unused", 1.0)]
    with pytest.raises(ConvergenceError, match="do not determine.*unused"):
        fit_psi_delta(data, build, params)


def test_parameter_validation():
    with pytest.raises(InvalidInputError, match="outside its bounds"):
        Parameter("t", 5.0, min=10.0, max=20.0)
    with pytest.raises(InvalidInputError, match="finite"):
        Parameter("t", np.nan)


def test_roughness_thickness_recovered(silicon):
    """Si under a 3 nm Bruggeman roughness layer (50 % void, nmmm.ema): the
    roughness thickness is fitted back within its uncertainty from noisy data at 2 angles."""
    model = EllipsometryModel.from_dict({
        "substrate": {"material": "main/Si/Green-2008"},
        "layers": [{"name": "rough", "roughness": True, "thickness_nm": {"value": 1.0, "min": 0, "max": 20}}]})
    truth = {"rough.thickness_nm": 3.0}
    data = EllipsometryData.from_model(model.build(truth), np.linspace(300, 800, 51), [65.0, 75.0], 0.01, 0.02,
                                       noise_seed=4)
    res = model.fit(data)
    assert abs(res["rough.thickness_nm"] - 3.0) < 4 * res.stderr["rough.thickness_nm"]
    assert res.stderr["rough.thickness_nm"] < 0.05


def test_thickness_scan_finds_interference_order():
    """A start 150 nm off lands in a wrong local minimum; the vectorised thickness scan finds the
    right order, and the fit then converges to the truth."""
    model = epoxy_model(thickness=1000.0, A=1.553, B=0.0068)
    truth = dict(model.values, **{"epoxy.thickness_nm": 850.0})
    data = EllipsometryData.from_model(model.build(truth), np.linspace(400, 1000, 61), [70.0], 0.02, 0.05,
                                       noise_seed=2)
    scanned, grid, chi2 = model.scan(data, "epoxy.thickness_nm", np.arange(500.0, 1200.0, 2.0))
    assert grid.size == chi2.size and abs(scanned.values["epoxy.thickness_nm"] - 850.0) <= 2.0
    res = scanned.fit(data)
    assert abs(res["epoxy.thickness_nm"] - 850.0) < 4 * res.stderr["epoxy.thickness_nm"]


def test_fit_ending_on_a_bound_warns():
    """Data made with a 523 nm film, thickness bounded to [400, 500] nm: the fit ends on the
    upper bound; it must warn (naming the parameter, value, bound), list it in ``at_bound`` and
    flag it in the summary, while the interior parameters carry no flag."""
    model = EllipsometryModel.from_dict({
        "substrate": {"material": "main/Si/Green-2008"},
        "layers": [{"name": "epoxy", "model": "cauchy",
                    "thickness_nm": {"value": 480.0, "min": 400, "max": 500},
                    "A": {"value": 1.55, "min": 1.2, "max": 2.0}, "B": {"value": 0.007, "min": -0.1, "max": 0.2},
                    "C": {"value": 0.0, "fit": False}}]})
    truth = dict(model.values, **{"epoxy.thickness_nm": 523.0, "epoxy.A": 1.552, "epoxy.B": 0.0071})
    data = EllipsometryData.from_model(model.build(truth), np.linspace(400, 1000, 61), [60.0, 70.0],
                                       0.02, 0.08, noise_seed=3)
    with pytest.warns(FitAtBoundWarning) as record:
        res = model.fit(data)
    assert res.at_bound == ("epoxy.thickness_nm",)
    assert res["epoxy.thickness_nm"] == pytest.approx(500.0, abs=1e-3)
    msgs = [str(w.message) for w in record if issubclass(w.category, FitAtBoundWarning)]
    assert len(msgs) == 1
    assert "epoxy.thickness_nm" in msgs[0] and "upper bound" in msgs[0] and "500" in msgs[0]
    assert "not meaningful" in msgs[0] and "widen" in msgs[0].lower() and "vary=False" in msgs[0]
    assert issubclass(FitAtBoundWarning, UserWarning)
    lines = {ln.split("=")[0].strip(): ln for ln in res.summary().splitlines() if "=" in ln and "epoxy." in ln}
    assert "(at bound" in lines["epoxy.thickness_nm"]
    assert "at bound" not in lines["epoxy.A"]
