"""Wavelength-by-wavelength inversion, Kramers-Kronig check, uniaxial two-orientation inversion."""

import numpy as np
import pytest

from nmmm.ellipsometry.anisotropy import synthetic_uniaxial_data, uniaxial_from_two_orientations
from nmmm.ellipsometry.data import EllipsometryData
from nmmm.ellipsometry.model import EllipsometryModel
from nmmm.ellipsometry.point_by_point_inversion import kk_check, point_by_point
from nmmm.errors import ConvergenceError, InvalidInputError

elli = pytest.importorskip("elli")

W = np.arange(300.0, 1000.0 + 1e-9, 10.0)


def absorbing_film_model():
    return EllipsometryModel.from_dict({
        "substrate": {"material": "main/Si/Green-2008"},
        "layers": [{"name": "film", "thickness_nm": 100.0, "model": "tauc_lorentz",
                    "A": 100.0, "E0": 4.0, "C": 1.5, "Eg": 2.0, "eps_inf": 1.5}]})


def pyelli_data(structure, angles):
    W_, A_, P_, D_ = [], [], [], []
    for a in angles:
        r = structure.evaluate(W, a, solver=elli.Solver2x2)
        W_.append(W), A_.append(np.full(W.shape, a)), P_.append(r.psi), D_.append(r.delta)
    return EllipsometryData(*(np.concatenate(x) for x in (W_, A_, P_, D_)))


def test_point_by_point_film_on_pyelli_data(silicon, elli_table):
    """n, k of a Tauc-Lorentz film at each wavelength, from pyElli's Ψ, Δ (exact data) at 2
    angles, starting 5 % away from the truth."""
    model = absorbing_film_model()
    film = model.material("film")
    s = elli.Structure(elli.AIR, [elli.Layer(elli_table(film, W), 100.0)], elli_table(silicon, W))
    data = pyelli_data(s, [60.0, 70.0])
    res = point_by_point(data, model, "film", start=film.nk(W) * 1.05 + 0.01j)
    np.testing.assert_allclose(res.nk, film.nk(W), atol=1e-7)
    assert res.converged.all()


def test_point_by_point_bulk_substrate_equals_pseudo_dielectric(silicon, elli_table):
    """A bare substrate inverted point by point from a crude start returns the database n + ik."""
    model = EllipsometryModel.from_dict({"substrate": {"material": "main/Si/Green-2008"}})
    data = pyelli_data(elli.Structure(elli.AIR, [], elli_table(silicon, W)), [70.0])
    res = point_by_point(data, model, "substrate", start=3.0 + 0.5j)
    np.testing.assert_allclose(res.nk, silicon.nk(W), rtol=1e-9)


def test_point_by_point_uncertainties_and_material_file(tmp_path):
    from nmmm.materials import read_csv

    model = absorbing_film_model()
    film = model.material("film")
    data = EllipsometryData.from_model(model.build(), W, [60.0, 70.0], 0.01, 0.05, noise_seed=5)
    res = point_by_point(data, model, "film")
    z = (res.nk.real - film.n(W)) / res.sigma_n
    assert 0.6 < np.std(z) < 1.5
    m = read_csv(res.write_csv(tmp_path / "film.csv"))
    np.testing.assert_allclose(m.nk(W), res.nk.real + 1j * np.maximum(res.nk.imag, 0))


def test_kk_check_flags_inconsistent_constants():
    """Inverted Tauc-Lorentz constants (causal) are as KK-consistent as the model itself; the same n
    with k scaled by 1.5 is not."""
    from nmmm.materials import TabulatedMaterial, kk_consistency

    model = absorbing_film_model()
    film = model.material("film")
    data = EllipsometryData.from_model(model.build(), W, [60.0, 70.0])
    res = point_by_point(data, model, "film")
    rep = kk_check(res)
    base = kk_consistency(film, wavelength_nm=W)
    assert rep.rms == pytest.approx(base.rms, rel=0.05)
    nk = res.nk
    bad = TabulatedMaterial("bad", W, nk.real, 1.5 * nk.imag)
    assert kk_check(bad, wavelength_nm=W).rms > 1.4 * rep.rms


def test_point_by_point_failures():
    model = absorbing_film_model()
    data = EllipsometryData.from_model(model.build(), W, [60.0, 70.0])
    with pytest.raises(ConvergenceError, match="did not converge"):
        point_by_point(data, model, "film", start=2.5 + 0.5j, max_iter=1)
    with pytest.raises(InvalidInputError, match="no layer"):
        point_by_point(data, model, "nothing")


def test_uniaxial_hematite_from_pyelli_4x4_data():
    """Hematite (Querry o/e) with the c axis in the surface: pyElli's 4x4 Ψ, Δ in both orientations
    are inverted back to the ordinary and extraordinary constants; the mean is uniaxial_mean's."""
    from nmmm.materials import get, uniaxial_mean

    o, e = get("main/Fe2O3/Querry-o"), get("main/Fe2O3/Querry-e")
    w = np.arange(300.0, 800.0 + 1e-9, 10.0)
    sets = []
    for rot in ([[0, 0, 1.0], [0, 1, 0], [-1, 0, 0]], [[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]):
        mat = elli.UniaxialMaterial(elli.Table(lbda=w, n=o.nk(w)), elli.Table(lbda=w, n=e.nk(w)))
        mat.set_rotation(np.array(rot))
        s = elli.Structure(elli.AIR, [], mat)
        rows = [(w, np.full(w.shape, a), *(lambda r: (r.psi, r.delta))(s.evaluate(w, a, solver=elli.Solver4x4)))
                for a in (60.0, 70.0)]
        sets.append(EllipsometryData(*(np.concatenate(x) for x in zip(*rows))))
    res = uniaxial_from_two_orientations(*sets, name="hematite")
    np.testing.assert_allclose(res.nk_ordinary, o.nk(w), atol=1e-8)
    np.testing.assert_allclose(res.nk_extraordinary, e.nk(w), atol=1e-8)
    np.testing.assert_allclose(res.mean().eps(w), uniaxial_mean(o, e).eps(w), rtol=1e-7)


def test_uniaxial_noisy_uncertainties(tmp_path):
    from nmmm.materials import get, read_csv

    o, e = get("main/Fe2O3/Querry-o"), get("main/Fe2O3/Querry-e")
    w = np.arange(300.0, 800.0 + 1e-9, 5.0)
    d1 = synthetic_uniaxial_data(o, e, w, [60.0, 70.0], "parallel", 0.02, 0.05, noise_seed=1)
    d2 = synthetic_uniaxial_data(o, e, w, [60.0, 70.0], "perpendicular", 0.02, 0.05, noise_seed=2)
    res = uniaxial_from_two_orientations(d1, d2)
    zo = (res.nk_ordinary.real - o.n(w)) / res.sigma_ordinary[:, 0]
    ze = (res.nk_extraordinary.imag - e.k(w)) / res.sigma_extraordinary[:, 1]
    assert 0.6 < np.std(zo) < 1.5 and 0.6 < np.std(ze) < 1.5
    files = res.write_csv(tmp_path)
    assert read_csv(files["mean"]).range_nm == (300.0, 800.0)
    with pytest.raises(InvalidInputError, match="share no wavelength"):
        uniaxial_from_two_orientations(d1, synthetic_uniaxial_data(o, e, [812.0], [65.0], "perpendicular"))


def test_point_by_point_under_roughness(silicon, elli_table):
    """A rough bulk sample (Si under 3 nm of Bruggeman 50 % void, pyElli's BruggemanEMA): the
    point-by-point inversion with the roughness layer in the model returns Si's n + ik, whereas
    the pseudo-dielectric function (no roughness) does not."""
    from nmmm.ellipsometry.pseudo_dielectric_function import pseudo_dielectric

    si = elli_table(silicon, W)
    s = elli.Structure(elli.AIR, [elli.Layer(elli.BruggemanEMA(si, elli.AIR, 0.5), 3.0)], si)
    data = pyelli_data(s, [70.0])
    model = EllipsometryModel.from_dict({
        "substrate": {"material": "main/Si/Green-2008"},
        "layers": [{"name": "rough", "roughness": True, "thickness_nm": 3.0}]})
    res = point_by_point(data, model, "substrate", start=silicon.nk(W) * 0.97)
    np.testing.assert_allclose(res.nk, silicon.nk(W), rtol=1e-7)
    pseudo = pseudo_dielectric(data.psi_deg, data.delta_deg, 70.0)
    assert np.max(np.abs(pseudo - silicon.eps(W))) > 0.5
