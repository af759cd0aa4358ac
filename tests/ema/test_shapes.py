"""Depolarization factors against the closed forms of Osborn (1945) / Bohren & Huffman (1983)."""

import numpy as np
import pytest

from nmmm.ema import Shape, ellipsoid_depolarization, spheroid_depolarization
from nmmm.errors import InvalidInputError


def _prolate_closed_form(r):
    """L along the long axis of a prolate spheroid, r = c/a > 1 (BH eq. 5.34)."""
    e = np.sqrt(1 - 1 / r**2)
    return (1 - e**2) / e**2 * (np.arctanh(e) / e - 1)


def _oblate_closed_form(r):
    """L along the short (symmetry) axis of an oblate spheroid, r = c/a < 1 (Osborn 1945)."""
    e = np.sqrt(1 - r**2)
    return (1 - np.sqrt(1 - e**2) * np.arcsin(e) / e) / e**2


def test_spheroids_match_closed_forms():
    r = np.array([1.2, 1.5, 2.0, 3.0, 5.0, 10.0, 50.0])
    L = spheroid_depolarization(r)
    np.testing.assert_allclose(L[:, 2], _prolate_closed_form(r), rtol=1e-10)
    np.testing.assert_allclose(L[:, 0], (1 - _prolate_closed_form(r)) / 2, rtol=1e-10)
    r = np.array([0.02, 0.1, 0.3, 0.5, 0.8])
    L = spheroid_depolarization(r)
    np.testing.assert_allclose(L[:, 2], _oblate_closed_form(r), rtol=1e-10)


def test_published_value_and_limits():
    # prolate spheroid of axis ratio 2: L = 0.1736 (Osborn 1945, Table I)
    assert abs(spheroid_depolarization(2.0)[2] - 0.1736) < 1e-4
    np.testing.assert_allclose(spheroid_depolarization(1.0), [1 / 3] * 3, rtol=1e-12)
    assert spheroid_depolarization(1e4)[2] < 1e-6          # needle
    assert spheroid_depolarization(1e-4)[2] > 1 - 1e-3     # platelet
    L = ellipsoid_depolarization(np.array([1.0, 2.0]), 3.0, np.array([[0.5], [4.0]]))
    assert L.shape == (2, 2, 3)
    np.testing.assert_allclose(L.sum(-1), 1.0, rtol=1e-12)
    # the longest axis has the smallest factor
    La = ellipsoid_depolarization(1.0, 2.0, 3.0)
    assert La[0] > La[1] > La[2]


def test_shape_objects_and_errors():
    s = Shape.spheroid(3.0, orientation="aligned")
    assert s.orientation == "aligned" and abs(sum(s.depolarization) - 1) < 1e-12
    assert Shape.cube().kind == "cube"
    with pytest.raises(InvalidInputError, match="sum to 1"):
        Shape((0.2, 0.2, 0.2))
    with pytest.raises(InvalidInputError):
        Shape.spheroid(-1.0)
    with pytest.raises(InvalidInputError, match="orientation"):
        Shape.sphere().__class__((1 / 3, 1 / 3, 1 / 3), "diagonal")
    with pytest.raises(InvalidInputError):
        ellipsoid_depolarization(1.0, np.nan, 1.0)
