"""The fused check-and-sum path of spectra_to_xyz for large stacks (issue 22): the same XYZ as
the BLAS product R @ W, and the same refusals (NaN, infinity, negative) as the NumPy checks."""

import numpy as np
import pytest

from nmmm.colour import spectra_to_xyz, weighting_factors
from nmmm.colour.tristimulus import _FUSED_MIN_SIZE
from nmmm.errors import InvalidInputError

W_NM = np.arange(380.0, 781.0, 5.0)


def _stack(rows):
    return np.random.default_rng(3).random((rows, W_NM.size))


def test_large_stack_equals_blas_product():
    rows = _FUSED_MIN_SIZE // W_NM.size + 10
    R = _stack(2 * rows).reshape(2, rows, W_NM.size)  # a (2, M, N) stack: leading axes kept
    expected = R @ weighting_factors(W_NM)
    got = spectra_to_xyz(W_NM, R)
    assert got.shape == R.shape[:-1] + (3,)
    np.testing.assert_allclose(got, expected, rtol=1e-13, atol=1e-12)


@pytest.mark.parametrize("bad, words", [(np.nan, "NaN or infinite"), (np.inf, "NaN or infinite"),
                                        (-np.inf, "NaN or infinite"), (-0.2, "-0.2")])
def test_large_stack_refuses_like_the_checks(bad, words):
    R = _stack(_FUSED_MIN_SIZE // W_NM.size + 10)
    R[123, 4] = bad
    with pytest.raises(InvalidInputError, match=words):
        spectra_to_xyz(W_NM, R)


def test_rounding_below_zero_is_accepted():
    R = _stack(_FUSED_MIN_SIZE // W_NM.size + 10)
    R[7, 3] = -1e-9  # within NEGATIVE_TOLERANCE, as on the NumPy path
    assert np.isfinite(spectra_to_xyz(W_NM, R)).all()
