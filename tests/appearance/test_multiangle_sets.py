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


# -- flop formulas of the registry ------------------------------------------------------


def test_flop_registry_declares_the_angles_each_formula_takes():
    import inspect

    from nmmm.appearance.multiangle import FLOP_INDEX_ASPECULAR_DEG, FLOP_INDEX_METHODS

    assert set(FLOP_INDEX_METHODS) == set(FLOP_INDEX_ASPECULAR_DEG)
    assert {"Alman 1987", "highlight-shade dL* (US 11472963)"} <= set(FLOP_INDEX_METHODS)
    for name, fn in FLOP_INDEX_METHODS.items():
        assert len(inspect.signature(fn).parameters) == len(FLOP_INDEX_ASPECULAR_DEG[name]), name


def test_highlight_shade_difference_is_the_patent_definition_on_hand_values():
    from nmmm.appearance.multiangle import flop_index, lightness_flop_highlight_shade

    # highlight (L*15 + L*25)/2 = (90 + 70)/2 = 80; shade (L*75 + L*110)/2 = (30 + 20)/2 = 25
    assert lightness_flop_highlight_shade(90.0, 70.0, 30.0, 20.0) == 55.0
    assert flop_index(90.0, 70.0, 30.0, 20.0, method="highlight-shade dL* (US 11472963)") == 55.0
    # a solid (same L* at every angle) has no flop; vectorised over samples
    np.testing.assert_array_equal(lightness_flop_highlight_shade([50.0, 10.0], [50.0, 10.0], [50.0, 10.0],
                                                                 [50.0, 10.0]), [0.0, 0.0])
    with pytest.raises(InvalidInputError, match="L\\*75 must be >= 0"):
        lightness_flop_highlight_shade(90.0, 70.0, -1.0, 20.0)


def test_flop_of_a_measured_set_reads_each_formulas_own_angles():
    from nmmm.appearance.multiangle import flop_index, flop_index_alman1987, lightness_flop_highlight_shade

    c = multiangle_lab_set(opaque_paint(0.4), W, "BYK-mac i")[45.0]
    L = {g: float(l) for g, l in zip(c.aspecular_deg, c.L)}
    assert np.isclose(flop_index(c), flop_index_alman1987(L[15.0], L[45.0], L[110.0]))
    assert np.isclose(flop_index(c, method="highlight-shade dL* (US 11472963)"),
                      lightness_flop_highlight_shade(L[15.0], L[25.0], L[75.0], L[110.0]))
    assert np.isclose(c.flop_index("highlight-shade dL* (US 11472963)"),
                      (L[15.0] + L[25.0]) / 2 - (L[75.0] + L[110.0]) / 2)
    # the perfect diffuser has no flop by either formula
    white = multiangle_lab_set(_Lambertian(), W, "BYK-mac i")[45.0]
    for method in ("Alman 1987", "highlight-shade dL* (US 11472963)"):
        assert abs(flop_index(white, method=method)) < 1e-6


def test_flop_refusals_name_the_choices_and_the_missing_angles():
    from nmmm.appearance.multiangle import flop_index

    with pytest.raises(InvalidInputError, match="choose among \\['Alman 1987', 'highlight-shade dL\\* \\(US 11472963\\)'\\]"):
        flop_index(1.0, 2.0, 3.0, method="DIN 6175-2")
    with pytest.raises(InvalidInputError, match="takes 4 lightnesses \\(L\\*15, L\\*25, L\\*75, L\\*110\\), got 3"):
        flop_index(1.0, 2.0, 3.0, method="highlight-shade dL* (US 11472963)")
    three = multiangle_lab_set(opaque_paint(0.4), W, "ASTM E2194")[45.0]  # 15, 45, 110 only
    with pytest.raises(InvalidInputError, match="aspecular angle 25.0° .* was not measured"):
        flop_index(three, method="highlight-shade dL* (US 11472963)")
    at15 = multiangle_lab(opaque_paint(0.4), W, (15.0, 45.0, 60.0), illumination_deg=15.0)
    with pytest.raises(InvalidInputError, match="45° illumination"):
        flop_index(at15)


# -- X-Rite's 19 geometries: the two illuminators share their detectors ------------------


def _viewing_directions(ti, inplane, out_of_plane):
    from nmmm.appearance.multiangle import aspecular_directions

    g = list(inplane) + [a for a, _ in out_of_plane]
    phi = [0.0] * len(inplane) + [p for _, p in out_of_plane]
    return aspecular_directions(g, ti, phi)[1]


def test_xrite_geometries_of_both_illuminators_view_along_shared_detector_directions():
    """An instrument with two illuminators (45°, 15°) and fixed detectors: every geometry of the 15° set must
    view along a direction of the 45° set. True for the in-plane angles by construction of the list
    (θv = 60, 30, 0, −30, −65° in both); for the out-of-plane ones it holds only with X-Rite's azimuth read as
    180° − φ (XRITE_OUT_OF_PLANE_DEG), within 0.04° (X-Rite's values have one decimal). Read literally, its
    45as60az125.3 would view from below the horizon."""
    from nmmm.appearance.multiangle import XRITE_OUT_OF_PLANE_DEG, aspecular_directions

    sets = GEOMETRY_SETS["X-Rite 19 geometries (in-plane)"]
    d45 = _viewing_directions(45.0, sets[45.0], XRITE_OUT_OF_PLANE_DEG[45.0])
    d15 = _viewing_directions(15.0, sets[15.0], XRITE_OUT_OF_PLANE_DEG[15.0])
    assert len(d45) + len(d15) == 19
    sep = np.degrees(np.arccos(np.clip(d15 @ d45.T, -1.0, 1.0))).min(axis=1)
    assert np.all(sep < 0.05), sep
    with pytest.raises(InvalidInputError, match="below the surface"):
        aspecular_directions([60.0], 45.0, [125.3])


def test_xrite_set_on_a_paint_gives_one_colour_per_illuminator():
    paint = opaque_paint(0.4)
    out = multiangle_lab_set(paint, W, "X-Rite 19 geometries (in-plane)")
    assert sorted(out) == [15.0, 45.0]
    assert out[15.0].aspecular_deg.tolist() == [-45.0, -15.0, 15.0, 45.0, 80.0]
    assert np.all(np.isfinite(out[15.0].lab)) and np.all(np.isfinite(out[45.0].lab))
