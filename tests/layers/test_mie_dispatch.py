"""Small-call dispatch of nmmm.layers.mie_scattering (issue 22): the scalar fast path and the
serial kernel for small batches give the same numbers as the general parallel path."""

import dataclasses

import numba
import numpy as np
import pytest

from nmmm.errors import InvalidInputError
from nmmm.layers import mie_scattering as M


def _general(n, nm, d, w):
    return M._mie_layers([n], nm, [d], w, None, [("n_particle", "diameter_nm")])


@pytest.mark.parametrize("args", [(1.55 + 0.02j, 1.33, 1050.0, 632.8), (1.55, 1.0, 1050, 632.8),
                                  (np.complex128(2.6 + 0.4j), np.float64(1.5), 250.0, np.float32(450.0))])
def test_scalar_fast_path_equals_general_path(args):
    fast, ref = M.mie(*args), _general(*args)
    for f in dataclasses.fields(fast):
        a, b = getattr(fast, f.name), getattr(ref, f.name)
        if b is None:
            assert a is None
            continue
        assert np.shape(a) == np.shape(b) == () and np.asarray(a).dtype == b.dtype
        assert a == b, f.name


def test_scalar_fast_path_bohren_huffman():
    r = M.mie(1.55, 1.0, 1050.0, 632.8)  # BH appendix A: Q_ext 3.10543, Q_back 2.92534
    assert round(float(r.qext), 5) == 3.10543 and round(float(r.qback), 5) == 2.92534


@pytest.mark.parametrize("bad", [(1.5, 1.0, -1.0, 550.0), (1.5 - 0.1j, 1.0, 100.0, 550.0),
                                 (1.5, float("nan"), 100.0, 550.0), (1.5, 1.0, 100.0, float("inf")),
                                 (1.5, 1.0, 100.0, 0.0), (-1.5, 1.0, 100.0, 550.0)])
def test_invalid_scalars_still_raise_the_general_message(bad):
    with pytest.raises(InvalidInputError):
        M.mie(*bad)


def test_small_batches_run_serially_and_agree_with_the_parallel_kernel():
    d = np.linspace(50.0, 900.0, 20)
    x = (np.pi * d * 1.5 / 550.0)[:, None]
    assert M._work_terms(x, 0) < M.PARALLEL_ABOVE_TERMS  # 20 spheres: the serial kernel
    r = M.mie(2.0 + 0.1j, 1.5, d, 550.0)
    m = np.full((d.size, 1), (2.0 + 0.1j) / 1.5)
    out = np.empty((d.size, 4))
    s = np.empty((d.size, 0), complex)
    M._mie_batch(m, x, np.empty(0), out, s, s.copy(), max(1, numba.get_num_threads()))
    np.testing.assert_array_equal(r.qext, out[:, 0])
    np.testing.assert_array_equal(r.g, out[:, 3])
