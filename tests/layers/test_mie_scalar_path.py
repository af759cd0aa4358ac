"""The one-sphere fast path of mie() (issue 22): checks done in the kernel, the result filled
directly. Same numbers as the general path at small and large x, the same refusals (the size-parameter
limit as the module sets it now), and a result that behaves like any MieResult."""

import dataclasses
import pickle

import numpy as np
import pytest

from nmmm.errors import InvalidInputError
from nmmm.layers import mie_scattering as M


def _general(n, nm, d, w):
    return M._mie_layers([n], nm, [d], w, None, [("n_particle", "diameter_nm")])


@pytest.mark.parametrize("args", [(1.55 + 0.02j, 1.33, 10.0, 632.8),  # x < 1: the small-x branch
                                  (1.5 + 0.01j, 1.0, 500.0, 550.0), (2.0, 1, 3000, 400),
                                  (np.float64(1.7), np.float32(1.5), np.int64(800), 700.0),
                                  (0.2 + 3.0j, 1.0, 40.0, 500.0)])  # a metal
def test_fast_path_equals_general_path(args):
    fast, ref = M.mie(*args), _general(*args)
    assert type(fast) is M.MieResult
    for f in dataclasses.fields(fast):
        a, b = getattr(fast, f.name), getattr(ref, f.name)
        if b is None:
            assert a is None
            continue
        assert isinstance(a, np.float64) and a == b, f.name


def test_fast_path_equals_general_path_bit_for_bit_in_any_medium():
    """n_medium != 1 and every kind of plain number: m = n / n_medium was a Numba complex division
    in the fast path and a NumPy one in the general path, 1 ulp apart in 44 % of cases (e.g. the
    first case: Q_ext 4.4e-16 apart)."""
    rng = np.random.default_rng(3)
    cases = [(2.2838449706104615 + 2.1961446592915324j, 1.33, 1851.0, 468.0)]
    for _ in range(150):
        n = complex(rng.uniform(0.2, 3.0), rng.choice([0.0, rng.uniform(0, 4)]))
        cases.append((n, float(rng.uniform(1.0, 1.8)), float(10 ** rng.uniform(0.5, 3.8)), float(rng.uniform(350, 850))))
    cases += [(np.complex64(1.7 + 0.3j), np.float32(1.41), np.int64(700), 512), (1.6 + 0j, np.float64(1.52), 250, 600.0)]
    for args in cases:
        fast, ref = M.mie(*args), _general(*args)
        for name in ("qext", "qsca", "qabs", "qback", "g", "size_parameter"):
            assert getattr(fast, name) == getattr(ref, name), (args, name)


def test_size_parameter_limit_is_read_at_call_time(monkeypatch):
    assert float(M.mie(1.5, 1.0, 500.0, 550.0).size_parameter) > 2
    monkeypatch.setattr(M, "MIE_MAX_SIZE_PARAMETER", 2.0)
    with pytest.raises(InvalidInputError, match="size parameter"):
        M.mie(1.5, 1.0, 500.0, 550.0)


@pytest.mark.parametrize("bad", [(1.5 + 1j * float("nan"), 1.0, 100.0, 550.0), (float("inf"), 1.0, 100.0, 550.0),
                                 (1.5, 0.0, 100.0, 550.0), (1.5, -1.33, 100.0, 550.0), (0.0, 1.0, 100.0, 550.0),
                                 (1.5, 1.0, float("nan"), 550.0), (1.5, 1.0, 100.0, -550.0),
                                 (1.5, 1.0, 1e12, 550.0)])
def test_invalid_numbers_are_refused(bad):
    with pytest.raises(InvalidInputError):
        M.mie(*bad)


def test_non_numbers_take_the_general_path():
    assert np.shape(M.mie(1.5, 1.0, [100.0], 550.0).qext) == (1,)  # a list keeps its axis
    r = M.mie(1.5, 1.0, np.array(100.0), 550.0)  # a 0-d array: the general path, the same values
    assert r.qext == M.mie(1.5, 1.0, 100.0, 550.0).qext


def test_fast_result_behaves_like_a_dataclass():
    r = M.mie(1.5 + 0.01j, 1.0, 500.0, 550.0)
    assert r.angle_deg is None and r.s1 is None and r.s2 is None
    assert r.qabs == r.qext - r.qsca
    assert repr(r).startswith("MieResult(qext=")
    assert pickle.loads(pickle.dumps(r)) == r
    r2 = dataclasses.replace(r, qext=np.float64(0.0))
    assert r2.qext == 0 and r2.qsca == r.qsca
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.qext = 1.0
    assert float(r.cext_nm2) == pytest.approx(float(r.qext) * np.pi * 500.0**2 / 4)
