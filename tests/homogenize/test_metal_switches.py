"""Issue 22 (metals): early detection of a solve that will not converge within maxiter, and the
automatic choice of one Lanczos run per loading for a two-phase spectrum."""

import json
import warnings

import numpy as np
import pytest

from nmmm.errors import ConvergenceError, InvalidInputError
from nmmm.homogenize import fft_permittivity, two_phase_spectrum
from nmmm.homogenize import geometries as G
from nmmm.homogenize.fft import _compact_labels, predicted_projections, slow_solve_monitor
from nmmm.homogenize.green import green_operator
from nmmm.homogenize.solvers import Problem, solve_cocg
from nmmm.homogenize.work_estimate import choose_spectrum_method, estimate_fft_work


def test_prediction_extrapolates_the_recent_decay():
    h = [10.0 ** (-k / 100) for k in range(201)]  # one decade per 100 projections
    assert predicted_projections(h, 1e-5) == pytest.approx(500)
    # a fast start then a slow tail: the prediction follows the tail, not the average
    h2 = [10.0 ** (-k / 10) for k in range(21)] + [1e-2 * 10.0 ** (-k / 1000) for k in range(1, 200)]
    assert predicted_projections(h2, 1e-5) > 2000
    assert predicted_projections([1.0, 0.5, 0.6, 0.5, 0.55], 1e-5) == np.inf  # plateau
    assert predicted_projections([1.0, 1e-6], 1e-5) == 1  # reached


def _boolean(n=16, seed=4):
    lab = G.boolean_spheres(n, 0.2, 2.5, ndim=3, seed=seed)
    compact, values, counts = _compact_labels(lab)
    return lab, compact


def test_monitor_stops_cocg_before_maxiter():
    """A complex64 COCG asked for tol 1e-9 floors near 1e-6: stopped after a few hundred projections instead
    of running its 3000 projections."""
    lab, compact = _boolean()
    prob = Problem(compact, 2, green_operator(lab.shape, "willot2015"), np.complex64, 1)
    out = solve_cocg(prob, np.array([2.25, -50 + 20j]), np.array([1.0, 0, 0]), tol=1e-9, maxiter=3000,
                     keep_x=False, stall_window=None, monitor=slow_solve_monitor(1e-9, 3000, first=50))
    assert not out.converged and out.iterations <= 400  # (326 measured)
    assert "predicted slow" in out.message and "maxiter=3000" in out.message


def test_monitor_keeps_a_solve_that_converges():
    lab, compact = _boolean()
    prob = Problem(compact, 2, green_operator(lab.shape, "willot2015"), np.complex128, 1)
    args = (prob, np.array([2.25, -50 + 2j]), np.array([1.0, 0, 0]))
    ref = solve_cocg(*args, tol=1e-8, maxiter=3000, keep_x=False, stall_window=None)
    assert ref.converged
    m = int(ref.iterations * 1.05)
    out = solve_cocg(*args, tol=1e-8, maxiter=m, keep_x=False, stall_window=None, monitor=slow_solve_monitor(1e-8, m))
    assert out.converged and out.iterations == ref.iterations
    # with a small margin, the slow start of this superlinear solve looks hopeless (why PREDICT[1] = 5)
    early = solve_cocg(*args, tol=1e-8, maxiter=m, keep_x=False, stall_window=None,
                       monitor=slow_solve_monitor(1e-8, m, margin=1.5))
    assert not early.converged and "predicted slow" in early.message


def test_default_path_reports_a_predicted_stop():
    """fallback=True (the default path): the stopped COCG is reported with the projections it
    ran, the residual reached and the prediction; the error carries every attempt."""
    lab, _ = _boolean()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ConvergenceError, match="predicted slow") as exc:
            fft_permittivity(lab, {0: 2.25, 1: -50 + 20j}, green="willot2015", dtype="complex64", tol=1e-12,
                             maxiter=600, directions=[0], workers=1)
    assert len(exc.value.history["cocg"]) < 400  # stopped at the first check (from 0.6 × maxiter), not after 600
    # BiCGStab and GMRES measured worse on predicted-slow (near-singular) cells: not tried
    assert set(exc.value.history) == {"cocg"}


def test_a_late_superlinear_solve_is_not_stopped():
    """Near a resonance COCG can sit on a plateau, then converge fast: 16³ spheres at −50 + 1i
    with the rotated operator converge in ~510 projections where the extrapolation at 150 says
    ~15000 (and at −50 + 0.5i the best residual does not decrease over 75-150). With maxiter 1000
    that solve must converge, not be stopped as predicted slow (the check waits for 0.6 ×
    maxiter); the Lanczos run's check alike."""
    from nmmm.homogenize.fft import first_prediction

    assert first_prediction(200) == 150 and first_prediction(1000) == 600 and first_prediction(1001) == 601
    lab, _ = _boolean()
    for eps in (-50 + 1j, -50 + 0.5j):
        ref = fft_permittivity(lab, {0: 2.25, 1: eps}, green="willot2015", tol=1e-6, maxiter=1000,
                               directions=[0], workers=1, fallback=False)
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # no stop, no switch
            r = fft_permittivity(lab, {0: 2.25, 1: eps}, green="willot2015", tol=1e-6, maxiter=1000,
                                 directions=[0], workers=1)
        assert 300 < ref.iterations[0] <= 1000 and r.iterations[0] == ref.iterations[0]
        assert [sw for sw in r.switches if sw["what"] != "stop"] == []  # (the flux rule's report aside)
        assert r.tensor[0, 0] == ref.tensor[0, 0]


def test_a_predicted_stop_is_reported_with_its_numbers(monkeypatch):
    """The switch after a stop records the projections run, the residual reached and the
    prediction, and goes to COCG with the other Willot operator (a monitor that stops the first
    COCG after 30 steps stands in for a slow case; 31 projections with the right-hand side's)."""
    import nmmm.homogenize.fft as F

    calls = []

    def stop_first_at_30(tol, maxiter):
        calls.append(1)
        first = len(calls) == 1
        return lambda h, flux=None: "predicted slow (test)" if first and len(h) > 30 else None

    monkeypatch.setattr(F, "slow_solve_monitor", stop_first_at_30)
    lab, _ = _boolean()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = fft_permittivity(lab, {0: 2.25, 1: -50 + 20j}, tol=1e-6, directions=[0], workers=1)
    assert r.green == "willot2015"
    sw = [s for s in r.switches if "residual_reached" in s][0]
    assert sw["from"] == "cocg/willot2015" and sw["to"] == "cocg/willot2014" and sw["reason"] == "predicted slow (test)"
    assert sw["projections"] == 31 and 1e-6 < sw["residual_reached"] < 1 and sw["predicted_projections"] > 30
    assert r.solver[0] == "cocg" and r.metadata["green_used"][0] == "willot2014"


def _anisotropic_cell():
    """A tilted two-phase cell with off-diagonal terms: a voxel laminate along (1, 1, 0) with
    a hole pattern."""
    i, j, k = np.indices((12, 12, 8))
    lab = (((i + j) % 6) < 2).astype(np.uint8)
    lab[(i % 4 == 0) & (k % 4 == 1)] = 1
    return lab


def test_lanczos_off_diagonal_terms_equal_cocg():
    lab = _anisotropic_cell()
    em = np.array([-50 + 20j, -10 + 1j, 8 + 3j])
    a = two_phase_spectrum(lab, {0: 2.25, 1: em}, tol=1e-10, workers=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        b = fft_permittivity(lab, {0: 2.25, 1: em}, tol=1e-10, green="willot2015", workers=1,
                             method="per_wavelength")
    assert np.abs(b.tensor[:, 0, 1]).min() > 0.05  # the cell has off-diagonal terms
    assert np.abs(a.tensor - b.tensor).max() <= 1e-7 * np.abs(b.tensor).max()


@pytest.mark.parametrize("green", ["willot2015", "willot2014", "continuous"])
def test_method_lanczos_laminate_is_exact(green):
    """Both methods give the closed forms of a laminate (arithmetic along, harmonic across;
    off-diagonal zero) at every wavelength."""
    lab = np.zeros((8, 8, 8), dtype=int)
    lab[:, :, 2:5] = 1
    em = np.array([-50 + 20j, -50 + 2j, -10 + 1j, 12 + 0.5j])
    p = 3 / 8
    exact = np.zeros((em.size, 3, 3), complex)
    exact[:, 0, 0] = exact[:, 1, 1] = (1 - p) * 2.25 + p * em
    exact[:, 2, 2] = 1 / ((1 - p) / 2.25 + p / em)
    for method in ("lanczos", "per_wavelength"):
        r = fft_permittivity(lab, {0: 2.25, 1: em}, green=green, tol=1e-10, workers=1, method=method)
        assert r.metadata["method"] == method
        assert np.allclose(r.tensor, exact, rtol=1e-8, atol=1e-8)


def test_auto_chooses_lanczos_for_a_two_phase_spectrum_and_reports_it():
    lab = G.boolean_spheres(16, 0.2, 2.5, ndim=3, seed=4)
    em = np.linspace(-50, -10, 8) + 13j
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        auto = fft_permittivity(lab, {0: 2.25, 1: em}, tol=1e-8, workers=1)
        per = fft_permittivity(lab, {0: 2.25, 1: em}, tol=1e-8, workers=1, method="per_wavelength")
    assert auto.metadata["method"] == "lanczos" and per.metadata["method"] == "per_wavelength"
    sw = [s for s in auto.switches if s["what"] == "method"]
    assert len(sw) == 1 and sw[0]["to"] == "lanczos" and "estimated" in sw[0]["reason"]
    assert auto.green == per.green  # the same operator: the same discrete problem
    assert np.abs(auto.tensor - per.tensor).max() <= 1e-5 * np.abs(per.tensor).max()
    assert sum(auto.metadata["projections"]) < per.iterations.sum()
    # one wavelength, or a low-loss metal at some wavelength (Lanczos drifts there): per wavelength
    one = fft_permittivity(lab, {0: 2.25, 1: -50 + 5j}, tol=1e-6, workers=1, directions=[0])
    assert one.metadata["method"] == "per_wavelength" and not [s for s in one.switches if s["what"] == "method"]
    low = fft_permittivity(lab, {0: 2.25, 1: np.array([-44 + 13j, -50 + 2j])}, tol=1e-6, workers=1, directions=[0])
    assert low.metadata["method"] == "per_wavelength" and "low-loss" in low.metadata["method_reason"]
    assert auto.metadata["method_reason"].startswith("auto: two-phase cell over 8 wavelengths")


def test_method_choice_follows_the_estimate():
    assert choose_spectrum_method(81, "complex64")[0] == "lanczos"
    assert choose_spectrum_method(1, "complex128")[0] == "per_wavelength"
    per = estimate_fft_work((128,) * 3, n_wavelengths=81, metal=True, dtype="complex64")
    lz = estimate_fft_work((128,) * 3, n_wavelengths=81, metal=True, method="lanczos")
    assert lz["seconds"] < per["seconds"] / 10


@pytest.mark.parametrize("kw,match", [({"method": "bergman"}, "unknown method 'bergman'"),
                                      ({"method": "lanczos", "return_fields": True}, "local fields"),
                                      ({"method": "lanczos", "solver": "gmres"}, "per_wavelength")])
def test_bad_method_settings_are_refused_by_name(kw, match):
    lab = np.zeros((4, 4, 4), dtype=int)
    lab[:, :, :2] = 1
    with pytest.raises(InvalidInputError, match=match):
        fft_permittivity(lab, {0: 2.25, 1: np.array([-50 + 20j, -10 + 1j])}, workers=1, **kw)


def test_lanczos_needs_two_phases():
    lab = np.zeros((4, 4, 4), dtype=int)
    lab[0] = 1
    lab[1] = 2
    with pytest.raises(InvalidInputError, match="two-phase"):
        fft_permittivity(lab, {0: 1.0, 1: 2.0, 2: 3.0}, method="lanczos", workers=1)


def _cell_file(tmp_path):
    from nmmm.microstructure import Microstructure, save_microstructure

    lab = np.zeros((8, 8, 8), dtype=np.uint8)
    lab[:, :, 2:5] = 1
    path = tmp_path / "laminate.npz"
    save_microstructure(Microstructure(labels=lab, voxel_nm=10.0), path)
    return path


def test_cli_method_and_spectrum(tmp_path, capsys):
    from nmmm.cli import main

    path = _cell_file(tmp_path)
    rc = main(["homogenize", "run", str(path), "--eps", "0=2.25", "--eps", "1=main/Al/Rakic",
               "--wavelengths", "400:600:100", "--method", "lanczos", "--tol", "1e-9", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert rc in (0, None) and out["method"] == "lanczos" and out["wavelength_nm"] == [400.0, 500.0, 600.0]
    import nmmm.materials as M

    em = M.get("main/Al/Rakic").eps(np.array([400.0, 500.0, 600.0]))
    harm = 1 / ((5 / 8) / 2.25 + (3 / 8) / em)
    zz = np.array([t[2][2][0] + 1j * t[2][2][1] for t in out["tensor"]])
    assert np.allclose(zz, harm, rtol=1e-7)


@pytest.mark.parametrize("args,word", [(["--eps", "1=-50+2j", "--method", "bergman"], "--method"),
                                       (["--eps", "1=-50+2j", "--wavelengths", "600:400:10"], "--wavelengths"),
                                       (["--eps", "1=-50+2j", "--wavelengths", "380:inf:5"], "--wavelengths"),
                                       (["--eps", "1=-50+2j", "--wavelengths", "0:1e308:1e-308"], "--wavelengths"),
                                       (["--eps", "1=-50+2j", "--wavelengths", "380:780:1e-9"], "larger step"),
                                       (["--eps", "1=main/Al/Rakic"], "--wavelengths"),
                                       (["--eps", "1=nope/none", "--wavelengths", "500"], "nope/none")])
def test_cli_refuses_bad_values_in_one_line(tmp_path, capsys, args, word):
    from nmmm.cli import main

    path = _cell_file(tmp_path)
    rc = main(["homogenize", "run", str(path), "--eps", "0=2.25"] + args)
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("error:") and word in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1


def test_reaching_maxiter_while_converging_does_not_try_bicgstab():
    """A COCG still converging when maxiter ends (more than PREDICT[0] projections) is not handed to
    BiCGStab/GMRES (measured worse on such cells); with a handful of projections it still is
    (test_api's maxiter=3 case)."""
    lab, _ = _boolean()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ConvergenceError) as exc:
            fft_permittivity(lab, {0: 2.25, 1: -50 + 2j}, green="willot2015", tol=1e-10, maxiter=200,
                             directions=[0], workers=1)
    assert set(exc.value.history) == {"cocg"}
    assert "maxiter ≈" in str(exc.value)  # the error says how many projections the prediction asks for



def test_lanczos_memory_is_estimated_at_complex128():
    """One Lanczos run uses complex128 buffers whatever dtype was asked: the refusal before a run
    must not estimate it at complex64's half size."""
    e64 = estimate_fft_work((64, 64, 64), n_wavelengths=81, dtype="complex64", method="lanczos")
    e128 = estimate_fft_work((64, 64, 64), n_wavelengths=81, dtype="complex128", method="lanczos")
    assert e64["memory_gb"] == e128["memory_gb"] == estimate_fft_work((64, 64, 64), dtype="complex128")["memory_gb"]


def test_auto_lanczos_that_misses_maxiter_hands_over_to_per_wavelength():
    """Lanczos takes a few % more steps than COCG (finite precision): with a maxiter that
    per-wavelength COCG meets, the Lanczos run "auto" chose stops short; the per-wavelength solves
    then give the result, reported as a second method switch. method="lanczos" asked still raises."""
    lab = G.boolean_spheres(16, 0.2, 2.5, ndim=3, seed=4)
    nw = 6
    eps = {0: 2.25, 1: (-50 + 8j) * np.linspace(1, 1.05, nw)}
    kw = dict(wavelength_nm=np.linspace(400, 700, nw), directions=[0], workers=1, tol=1e-6, progress=False)
    ref = fft_permittivity(lab, eps, method="per_wavelength", **kw)
    m = int(ref.iterations.max())
    with pytest.raises(ConvergenceError, match="Lanczos"):
        fft_permittivity(lab, eps, method="lanczos", maxiter=m, **kw)
    with pytest.warns(RuntimeWarning, match="solving per wavelength"):
        r = fft_permittivity(lab, eps, method="auto", maxiter=m, **kw)
    assert r.metadata["method"] == "per_wavelength" and "did not converge" in r.metadata["method_reason"]
    methods = [(sw["from"], sw["to"]) for sw in r.switches if sw["what"] == "method"]
    assert methods == [("per_wavelength", "lanczos"), ("lanczos", "per_wavelength")]
    np.testing.assert_allclose(r.tensor, ref.tensor, rtol=0, atol=1e-12)


def test_cli_json_switches_are_strict_json():
    """A stopped solve's predicted_projections may be inf: --json writes it as a string, not the
    non-standard Infinity that strict JSON readers refuse."""
    from nmmm.homogenize.cli import _switch_json

    sw = {"what": "green", "from": "cocg/willot2015", "to": "cocg/willot2014", "reason": "predicted slow",
          "projections": 375, "residual_reached": 0.1, "predicted_projections": float("inf"), "loading": 0}
    text = json.dumps(_switch_json(sw))

    def refuse(name):
        raise ValueError(name)

    back = json.loads(text, parse_constant=refuse)
    assert back["predicted_projections"] == "inf" and back["projections"] == 375 and back["residual_reached"] == 0.1
