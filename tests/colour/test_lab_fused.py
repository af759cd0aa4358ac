"""spectra_to_lab on large stacks (issue 22): checks, weighted sums and CIELAB in one parallel
pass give the values of the two-step path (spectra_to_xyz, then colour-science's XYZ_to_Lab)
and refuse exactly what it refuses."""

import warnings

import numpy as np
import pytest

from nmmm.colour import spectra_to_lab, spectra_to_xyz, weighting_factors, white_point, xyz_to_lab
from nmmm.colour.tristimulus import _FUSED_MIN_SIZE
from nmmm.errors import InvalidInputError

W_NM = np.arange(380.0, 781.0, 5.0)
ROWS = _FUSED_MIN_SIZE // W_NM.size + 10


def _stack(rows=ROWS):
    return np.random.default_rng(5).random((rows, W_NM.size))


def _two_step(R, illuminant="D65", observer="2"):
    return xyz_to_lab(spectra_to_xyz(W_NM, R, illuminant, observer), white_point(W_NM, illuminant, observer))


@pytest.mark.parametrize("illuminant, observer", [("D65", "2"), ("A", "10"), ("F11", "2")])
def test_large_stack_lab_equals_the_two_step_path(illuminant, observer):
    R = _stack(2 * ROWS).reshape(2, ROWS, W_NM.size)
    got = spectra_to_lab(W_NM, R, illuminant, observer)
    assert got.shape == (2, ROWS, 3)
    np.testing.assert_allclose(got, _two_step(R, illuminant, observer), rtol=0, atol=1e-11)


def test_white_and_dark_rows():
    R = _stack()
    R[0] = 1.0
    R[1] = 0.0
    R[2] = 1e-4  # below CIE's (24/116)^3: the linear branch
    lab = spectra_to_lab(W_NM, R)
    np.testing.assert_allclose(lab[0], [100.0, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(lab[1], [0.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(lab[:3], _two_step(R[:3]), atol=1e-11)


@pytest.mark.parametrize("bad, words", [(np.nan, "NaN or infinite"), (np.inf, "NaN or infinite"),
                                        (-np.inf, "NaN or infinite"), (-0.2, "-0.2")])
def test_large_stack_lab_refuses_like_the_checks(bad, words):
    R = _stack()
    R[ROWS - 1, 4] = bad
    with pytest.raises(InvalidInputError, match=words):
        spectra_to_lab(W_NM, R)


def test_rounding_below_zero_is_accepted():
    R = _stack()
    R[7, 3] = -1e-9
    assert np.isfinite(spectra_to_lab(W_NM, R)).all()


def test_other_layouts_take_the_checked_numpy_path():
    R = _stack()
    ref = spectra_to_lab(W_NM, R)
    np.testing.assert_allclose(spectra_to_lab(W_NM, np.asfortranarray(R)), ref, atol=1e-11)
    np.testing.assert_allclose(spectra_to_lab(W_NM, R.astype(np.float32)), _two_step(R.astype(np.float32)),
                               atol=1e-11)


def test_truncated_grid_still_warns_on_a_large_stack():
    w = np.arange(500.0, 601.0, 1.0)
    R = np.random.default_rng(1).random((_FUSED_MIN_SIZE // w.size + 10, w.size))
    with pytest.warns(UserWarning, match="truncated"):
        spectra_to_lab(w, R)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        spectra_to_lab(W_NM, _stack())


@pytest.mark.parametrize("rows", [ROWS, ROWS + 1])  # the kernels take rows two at a time: even and odd counts
def test_odd_and_even_row_counts(rows):
    R = _stack(rows)
    np.testing.assert_allclose(spectra_to_xyz(W_NM, R), R @ weighting_factors(W_NM), rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(spectra_to_lab(W_NM, R), _two_step(R), rtol=0, atol=1e-11)
    R[rows - 1, 0] = np.nan  # the last row, alone in its pass when the count is odd
    for f in (spectra_to_xyz, spectra_to_lab):
        with pytest.raises(InvalidInputError, match="NaN or infinite"):
            f(W_NM, R)
