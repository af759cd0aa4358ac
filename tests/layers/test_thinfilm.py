"""Transfer-matrix thin films against tmm (coh_tmm, inc_tmm) run on the same inputs,
analytic quarter-wave results and energy conservation."""

import numpy as np
import pytest
import tmm

from nmmm.errors import InvalidInputError, OutOfRangeError
from nmmm.layers import Layer, Stack, fresnel
from nmmm.materials.material import TabulatedMaterial

WL = np.array([380.0, 455.0, 550.0, 633.0, 780.0])
ANG = np.array([0.0, 25.0, 50.0, 70.0, 85.0])

# ambient, 4 layers (absorbing dielectric, glass, metal, weakly absorbing), absorbing substrate
N_LIST = [1.0, 2.2 + 0.3j, 1.46, 0.2 + 3.0j, 1.8 + 0.01j, 1.5 + 0.1j]
D_LIST = [np.inf, 80.0, 120.0, 15.0, 300.0, np.inf]


def _stack(n_list, d_list, c_list=None):
    c_list = c_list or ["c"] * len(n_list)
    layers = [(n_list[i], d_list[i], c_list[i]) for i in range(1, len(n_list) - 1)]
    return Stack(layers, ambient=n_list[0], substrate=n_list[-1])


@pytest.mark.parametrize("pol", ["s", "p"])
@pytest.mark.parametrize("method", ["numba", "numpy"])
def test_coherent_against_tmm_oblique_absorbing(pol, method):
    st = _stack(N_LIST, D_LIST)
    res = st.rt(WL, ANG, method=method)
    res_abs = st.rt(WL, ANG, layer_absorption=True)  # always the NumPy kernel
    for i, w in enumerate(WL):
        for j, a in enumerate(ANG):
            ref = tmm.coh_tmm(pol, N_LIST, D_LIST, np.radians(a), w)
            assert getattr(res, "r" + pol)[i, j] == pytest.approx(ref["r"], abs=1e-12)
            assert getattr(res, "t" + pol)[i, j] == pytest.approx(ref["t"], abs=1e-12)
            assert getattr(res, "R" + pol)[i, j] == pytest.approx(ref["R"], abs=1e-12)
            assert getattr(res, "T" + pol)[i, j] == pytest.approx(ref["T"], abs=1e-12)
            assert getattr(res_abs, "R" + pol)[i, j] == pytest.approx(ref["R"], abs=1e-12)
            absorp = tmm.absorp_in_each_layer(ref)[1:-1]
            np.testing.assert_allclose(getattr(res_abs, "absorbed_" + pol)[:, i, j], absorp, atol=1e-12)


@pytest.mark.parametrize("pol", ["s", "p"])
def test_incoherent_mixed_against_tmm(pol):
    # coherent film / thick absorbing clear coat / coherent pair / two thick incoherent layers
    n_list = [1.0, 2.2 + 0.3j, 1.46 + 1e-4j, 0.2 + 3.0j, 1.8 + 0.01j, 1.5 + 0.1j, 1.3 + 1e-3j, 1.4]
    d_list = [np.inf, 80.0, 5000.0, 15.0, 300.0, 3000.0, 4000.0, np.inf]
    c_list = ["i", "c", "i", "c", "c", "i", "i", "i"]
    res = _stack(n_list, d_list, c_list).rt(WL, ANG, layer_absorption=True)
    assert res.rs is None  # no phase for partly incoherent stacks
    for i, w in enumerate(WL):
        for j, a in enumerate(ANG):
            ref = tmm.inc_tmm(pol, n_list, d_list, c_list, np.radians(a), w)
            assert getattr(res, "R" + pol)[i, j] == pytest.approx(ref["R"], abs=1e-12)
            assert getattr(res, "T" + pol)[i, j] == pytest.approx(ref["T"], abs=1e-12)
            absorp = tmm.inc_absorp_in_each_layer(ref)[1:-1]
            np.testing.assert_allclose(getattr(res, "absorbed_" + pol)[:, i, j], absorp, atol=1e-12)


def test_energy_conservation_mixed():
    n_list = [1.0, 1.5 + 1e-4j, 2.4 + 0.05j, 1.38, 0.05 + 4.0j]
    d_list = [np.inf, 30000.0, 60.0, 100.0, np.inf]
    st = _stack(n_list, d_list, ["i", "i", "c", "c", "i"])
    res = st.rt(np.linspace(380, 780, 41), np.linspace(0, 89, 30), layer_absorption=True)
    for R, T, A in ((res.Rs, res.Ts, res.absorbed_s), (res.Rp, res.Tp, res.absorbed_p)):
        np.testing.assert_allclose(R + T + A.sum(axis=0), 1.0, atol=1e-12)
        assert np.all(A >= -1e-14)
    np.testing.assert_allclose(res.A, res.absorbed.sum(axis=0), atol=1e-12)


def test_quarter_wave_analytic():
    # Macleod (2010) §3.2: a quarter-wave layer of index n1 on ns, R = ((n0 ns - n1^2)/(n0 ns + n1^2))^2
    n1, ns, w0 = 1.38, 1.52, 550.0
    st = Stack([(n1, w0 / (4 * n1))], substrate=ns)
    assert float(st.rt(w0).R) == pytest.approx(((ns - n1**2) / (ns + n1**2)) ** 2, rel=1e-12)
    # half-wave layer is absent: R equals the bare substrate
    st2 = Stack([(n1, w0 / (2 * n1))], substrate=ns)
    assert float(st2.rt(w0).R) == pytest.approx(((1 - ns) / (1 + ns)) ** 2, rel=1e-12)


def test_quarter_wave_bragg_mirror_analytic():
    # (HL)^N H on substrate: R = ((1 - (nH/nL)^(2N) nH^2/ns)/(1 + ...))^2 (Macleod 2010 §5.2)
    nH, nL, ns, w0, N = 2.35, 1.38, 1.52, 600.0, 5
    layers = []
    for _ in range(N):
        layers += [(nH, w0 / (4 * nH)), (nL, w0 / (4 * nL))]
    layers.append((nH, w0 / (4 * nH)))
    y = (nH / nL) ** (2 * N) * nH**2 / ns
    assert float(Stack(layers, substrate=ns).rt(w0).R) == pytest.approx(((1 - y) / (1 + y)) ** 2, rel=1e-10)


def test_single_interface_equals_fresnel():
    res = Stack([], ambient=1.0, substrate=0.2 + 3.4j).rt(WL, ANG)
    c = fresnel(1.0, 0.2 + 3.4j, ANG)
    np.testing.assert_allclose(res.rs, np.broadcast_to(c.rs, res.rs.shape), atol=1e-14)
    np.testing.assert_allclose(res.rp, np.broadcast_to(c.rp, res.rp.shape), atol=1e-14)
    np.testing.assert_allclose(res.rs[:, 0], -res.rp[:, 0], atol=1e-14)  # rp = -rs at normal incidence


def test_bare_interface_with_layer_absorption_has_no_layers():
    # no layers: nothing absorbed between the media, R + T = 1 (lossless, Born & Wolf §1.5)
    res = Stack([], substrate=1.5).rt(WL, ANG, layer_absorption=True)
    assert res.absorbed.shape == (0,) + res.R.shape
    np.testing.assert_allclose(res.R + res.T, 1.0, atol=1e-14)


def test_brewster_angle_uncoated():
    # tan(theta_B) = n2/n1: Rp vanishes for the bare interface
    theta_b = np.degrees(np.arctan(1.5 / 1.0))
    assert float(Stack([], substrate=1.5).rt(550.0, theta_b).Rp) < 1e-25


@pytest.mark.parametrize("method", ["numba", "numpy"])
def test_thick_opaque_layer_is_stable(method):
    # a 10 µm metal layer: no overflow, T -> 0, R equals the bare metal
    res = Stack([(0.2 + 3.0j, 1e4)], substrate=1.5).rt(WL, ANG, method=method)
    assert np.all(np.isfinite(res.Rs)) and np.all(np.isfinite(res.rs))
    np.testing.assert_allclose(res.Ts, 0.0, atol=1e-200)
    np.testing.assert_allclose(res.Rs, fresnel(1.0, 0.2 + 3.0j, ANG).Rs[None, :] * np.ones((5, 1)), rtol=1e-12)


def test_thickness_grid_broadcasting():
    d = np.linspace(50, 300, 7)
    st = Stack([(2.4, d), (1.46, 100.0)], substrate=1.52)
    res = st.rt(WL, ANG)
    assert res.R.shape == (7, 5, 5)
    for k in (0, 3, 6):
        single = Stack([(2.4, d[k]), (1.46, 100.0)], substrate=1.52).rt(WL, ANG)
        np.testing.assert_allclose(res.Rs[k], single.Rs, atol=1e-15)
    # two grids broadcast together, NumPy rules
    st2 = Stack([(2.4, d[:, None]), (1.46, np.array([80.0, 120.0]))], substrate=1.52)
    assert st2.rt(WL, 0.0).R.shape == (7, 2, 5)


def test_paired_points_grid_false():
    st = _stack(N_LIST, D_LIST)
    full = st.rt(WL, ANG)
    paired = st.rt(WL, ANG, grid=False)
    np.testing.assert_allclose(paired.rs, np.diagonal(full.rs), atol=1e-15)


def test_material_layers_and_range_error():
    mat = TabulatedMaterial("film", np.array([300.0, 900.0]), np.array([2.0, 2.2]), np.array([0.01, 0.0]))
    res = Stack([(mat, 100.0)], substrate=1.5).rt(WL, 30.0)
    const = np.array([float(Stack([(complex(mat.nk(w)), 100.0)], substrate=1.5).rt(w, 30.0).R) for w in WL])
    np.testing.assert_allclose(res.R, const, atol=1e-14)
    with pytest.raises(OutOfRangeError):
        Stack([(mat, 100.0)]).rt(1000.0)


@pytest.mark.parametrize(
    "make",
    [
        lambda: Stack([(1.5 - 0.1j, 100.0)]),  # k < 0
        lambda: Stack([(1.5, 0.0)]),  # non-positive thickness
        lambda: Stack([(1.5, -5.0)]),
        lambda: Stack([(np.nan, 100.0)]),
        lambda: Stack([(1.5, np.nan)]),
        lambda: Stack([(1.5, 100.0, "x")]),
        lambda: Stack([(1.5, 100.0)], substrate=1.0 - 1j),
        lambda: Stack([("TiO2", 100.0)]),
        lambda: Stack([(1.5, 100.0)]).rt(550.0, 90.0),
        lambda: Stack([(1.5, 100.0)]).rt(550.0, -3.0),
        lambda: Stack([(1.5, 100.0)]).rt(np.nan, 0.0),
        lambda: Stack([(1.5, 100.0)]).rt(-550.0, 0.0),
        lambda: Stack([(1.5, 100.0)]).rt(550.0, 0.0, method="fast"),
    ],
)
def test_bad_input(make):
    with pytest.raises(InvalidInputError):
        make()


def test_layer_object_and_repr():
    st = Stack([Layer(1.5, 100.0), Layer(1.5, 1e5, coherent=False)], substrate=1.0)
    assert not st.coherent and st.n_layers == 2
    assert "incoherent" in repr(st)
    st2 = st.with_thicknesses([120.0, 2e5])
    assert float(st2.layers[0].thickness_nm) == 120.0


@pytest.mark.parametrize("method", ["numba", "numpy"])
def test_frustrated_total_internal_reflection_against_tmm(method):
    # glass | thin air gap | glass beyond the critical angle: evanescent field in the gap
    n_list, ang = [1.5, 1.0, 1.5 + 0.001j], np.array([45.0, 60.0, 75.0])
    for gap in (50.0, 300.0, 2000.0):
        res = Stack([(1.0, gap)], ambient=1.5, substrate=n_list[2]).rt(WL, ang, method=method)
        for i, w in enumerate(WL):
            for j, a in enumerate(ang):
                for pol in "sp":
                    ref = tmm.coh_tmm(pol, n_list, [np.inf, gap, np.inf], np.radians(a), w)
                    assert getattr(res, "r" + pol)[i, j] == pytest.approx(ref["r"], abs=1e-12)
                    assert getattr(res, "T" + pol)[i, j] == pytest.approx(ref["T"], abs=1e-12)


def test_absorbing_ambient_normal_incidence_against_tmm():
    # tmm accepts an absorbing incidence medium only where n0 sin(theta0) is real
    n_list = [1.4 + 0.05j, 2.0 + 0.2j, 1.5]
    res = Stack([(n_list[1], 70.0)], ambient=n_list[0], substrate=n_list[2]).rt(WL, 0.0)
    for i, w in enumerate(WL):
        for pol in "sp":
            ref = tmm.coh_tmm(pol, n_list, [np.inf, 70.0, np.inf], 0.0, w)
            assert getattr(res, "r" + pol)[i] == pytest.approx(ref["r"], abs=1e-12)
            assert getattr(res, "R" + pol)[i] == pytest.approx(ref["R"], abs=1e-12)
            assert getattr(res, "T" + pol)[i] == pytest.approx(ref["T"], abs=1e-12)


def test_numba_and_numpy_kernels_agree_on_thickness_grid():
    d = np.linspace(10.0, 400.0, 9)
    st = Stack([(2.2 + 0.3j, d[:, None]), (1.46, 120.0), (0.2 + 3.0j, np.array([5.0, 20.0]))], substrate=1.52)
    a = st.rt(WL, ANG, method="numba")
    b = st.rt(WL, ANG, method="numpy")
    assert a.rs.shape == (9, 2, 5, 5)
    for x in ("rs", "rp", "ts", "tp", "Rs", "Rp", "Ts", "Tp"):
        np.testing.assert_allclose(getattr(a, x), getattr(b, x), atol=1e-13)
