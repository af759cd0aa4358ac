"""Named multi-angle geometry sets (issue 18 item 4)."""

import numpy as np
import pytest

from nmmm.appearance.brdf import opaque_paint
from nmmm.appearance.multiangle import GEOMETRY_SETS, GEOMETRY_SOURCES, multiangle_lab, multiangle_lab_set
from nmmm.errors import InvalidInputError

W = np.arange(380.0, 781.0, 20.0)


def test_every_geometry_set_has_a_source_and_valid_angles():
    assert set(GEOMETRY_SETS) == set(GEOMETRY_SOURCES)
    for name, sets in GEOMETRY_SETS.items():
        for ti, g in sets.items():
            assert 0 <= ti < 90 and all(abs(ti - a) < 90 and a != 0 for a in g), name


class _Lambertian:
    """A perfect diffuser: f = 1/π at every geometry (an independent reference: L* = 100)."""

    name = "perfect diffuser"

    def __call__(self, w, wi, wo):
        shape = np.broadcast_shapes(np.shape(wi), np.shape(wo))[:-1]
        return np.full(shape + (len(w),), 1 / np.pi)


@pytest.mark.parametrize("name", list(GEOMETRY_SETS))
def test_perfect_diffuser_is_white_at_every_geometry_of_every_set(name):
    for ti, c in multiangle_lab_set(_Lambertian(), W, name).items():
        np.testing.assert_allclose(c.lab, np.tile([100.0, 0.0, 0.0], (len(c.aspecular_deg), 1)), atol=1e-6)
        assert c.illumination_deg == ti


def test_set_equals_multiangle_lab_at_its_angles_and_unknown_set_is_refused():
    paint = opaque_paint(0.4)
    c = multiangle_lab_set(paint, W, "BYK-mac i")[45.0]
    np.testing.assert_array_equal(c.lab, multiangle_lab(paint, W, (-15, 15, 25, 45, 75, 110)).lab)
    with pytest.raises(InvalidInputError, match="unknown geometry set 'MA98'"):
        multiangle_lab_set(paint, W, "MA98")
