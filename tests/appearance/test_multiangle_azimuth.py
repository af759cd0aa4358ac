"""Out-of-plane multi-angle geometries (issue 18 item 4): ``azimuth_deg`` turns the viewing
direction about the specular direction.

Definition checked (module docstring of nmmm.appearance.multiangle): plane of incidence xz,
light from +x at θi, specular r = (−sin θi, 0, cos θi), t = (cos θi, 0, sin θi) the in-plane
direction of positive aspecular angle, and ωo = cos γ r + sin γ (cos φ t + sin φ ŷ).
"""

import numpy as np
import pytest

from nmmm.appearance.brdf import metallic_paint, opaque_paint
from nmmm.appearance.multiangle import aspecular_directions, flop_index, multiangle_lab, multiangle_reflectance
from nmmm.errors import InvalidInputError

W = np.arange(380.0, 781.0, 20.0)
G = np.array([-15.0, 15.0, 25.0, 45.0, 75.0, 110.0])


def test_zero_azimuth_is_the_in_plane_geometry_and_180_flips_the_sign_of_the_aspecular_angle():
    wi0, wo0 = aspecular_directions(G, 45.0)
    wi1, wo1 = aspecular_directions(G, 45.0, 0.0)
    np.testing.assert_array_equal(wi0, wi1)
    np.testing.assert_array_equal(wo0, wo1)
    _, wo_flip = aspecular_directions([15.0, 30.0], 45.0, 180.0)
    _, wo_neg = aspecular_directions([-15.0, -30.0], 45.0)
    np.testing.assert_allclose(wo_flip, wo_neg, atol=1e-15)
    assert np.all(wo_flip[:, 1] == 0.0)  # exactly in the plane


def test_out_of_plane_directions_written_out_by_hand():
    s, c = np.sin, np.cos
    d = np.radians
    # θi = 45°, γ = 25°, φ = +90°: cos25·r + sin25·ŷ
    _, wo = aspecular_directions(25.0, 45.0, 90.0)
    np.testing.assert_allclose(wo[0], [-s(d(45)) * c(d(25)), s(d(25)), c(d(45)) * c(d(25))], atol=1e-15)
    np.testing.assert_allclose(wo[0], [-0.6408564, 0.4226183, 0.6408564], atol=1e-7)
    # θi = 15°, γ = 40°, φ = −60°
    _, wo = aspecular_directions(40.0, 15.0, -60.0)
    r = np.array([-s(d(15)), 0.0, c(d(15))])
    t = np.array([c(d(15)), 0.0, s(d(15))])
    expected = c(d(40)) * r + s(d(40)) * (c(d(-60)) * t + s(d(-60)) * np.array([0.0, 1.0, 0.0]))
    np.testing.assert_allclose(wo[0], expected, atol=1e-15)


def test_aspecular_angle_and_azimuth_are_recovered_from_the_vectors():
    g = np.array([15.0, 25.0, 45.0, 60.0, 38.3, 46.9])
    phi = np.array([30.0, 90.0, -90.0, 50.0, -43.0, 104.5])
    for ti in (15.0, 45.0):
        wi, wo = aspecular_directions(g, ti, phi)
        r = np.array([-wi[0], -wi[1], wi[2]])
        t = np.array([np.cos(np.radians(ti)), 0.0, np.sin(np.radians(ti))])
        np.testing.assert_allclose(np.linalg.norm(wo, axis=1), 1.0, atol=1e-14)
        np.testing.assert_allclose(np.degrees(np.arccos(np.clip(wo @ r, -1, 1))), g, atol=1e-9)
        perp = wo - (wo @ r)[:, None] * r
        np.testing.assert_allclose(np.degrees(np.arctan2(perp[:, 1], perp @ t)), phi, atol=1e-9)


def test_azimuth_broadcasts_and_mismatched_shapes_are_refused():
    _, wo = aspecular_directions([25.0, 60.0], 45.0, [90.0, -90.0])
    assert wo.shape == (2, 3) and wo[0, 1] > 0 > wo[1, 1]
    with pytest.raises(InvalidInputError, match="azimuth_deg"):
        aspecular_directions([15.0, 25.0, 45.0], 45.0, [0.0, 90.0])


def test_below_the_horizon_out_of_the_plane_is_refused_naming_the_geometry():
    with pytest.raises(InvalidInputError, match=r"\(aspecular, azimuth\).*\(100\.0, 180\.0\)"):
        aspecular_directions(100.0, 45.0, 180.0)  # = −100° in the plane: 145° from the normal
    with pytest.raises(InvalidInputError, match="below the surface"):
        aspecular_directions(95.0, 45.0, 90.0)  # z = cos95° cos45° < 0
    with pytest.raises(InvalidInputError, match="azimuth_deg"):
        aspecular_directions(25.0, 45.0, np.nan)


class _Lambertian:
    name = "perfect diffuser"

    def __call__(self, w, wi, wo):
        shape = np.broadcast_shapes(np.shape(wi), np.shape(wo))[:-1]
        return np.full(shape + (len(w),), 1 / np.pi)


def test_isotropic_paints_are_mirror_symmetric_in_azimuth_and_the_diffuser_stays_white():
    for paint in (opaque_paint(0.4, roughness=0.2), metallic_paint(1.5, 12.0, body_reflectance=0.2)):
        rp = multiangle_reflectance(paint, W, [25.0, 60.0], 45.0, [90.0, 50.0])
        rm = multiangle_reflectance(paint, W, [25.0, 60.0], 45.0, [-90.0, -50.0])
        np.testing.assert_allclose(rp, rm, rtol=1e-12, atol=1e-15)
        r0 = multiangle_reflectance(paint, W, [25.0, 60.0], 45.0)  # same γ in the plane: another geometry
        assert np.all(np.abs(rp - r0).max(axis=1) > 1e-3)
    c = multiangle_lab(_Lambertian(), W, [25.0, 60.0, 38.3], 15.0, azimuth_deg=[90.0, 50.0, -43.0])
    np.testing.assert_allclose(c.lab, np.tile([100.0, 0.0, 0.0], (3, 1)), atol=1e-6)


def test_multiangle_lab_out_of_plane_rows_table_and_lookup():
    paint = metallic_paint(1.5, 12.0, body_reflectance=0.2)
    inplane = multiangle_lab(paint, W, (15.0, 45.0, 110.0))
    assert inplane.azimuth_deg is None and "azimuth_deg" not in inplane.table()[0]
    c = multiangle_lab(paint, W, [15.0, 45.0, 110.0, 25.0, 25.0], azimuth_deg=[0.0, 0.0, 0.0, 90.0, -90.0])
    np.testing.assert_allclose(c.lab[:3], inplane.lab, atol=1e-12)
    assert c.table()[3]["azimuth_deg"] == 90.0 and list(c.table()[3])[:2] == ["aspecular_deg", "azimuth_deg"]
    assert c.lightness_at(25.0, 90.0) == pytest.approx(c.lightness_at(25.0, -90.0), abs=1e-9)
    assert flop_index(c) == pytest.approx(flop_index(inplane), abs=1e-12)  # the in-plane rows
    with pytest.raises(InvalidInputError, match=r"at azimuth 0.0° was not measured; available: \[\(15.0, 0.0\)"):
        c.lightness_at(25.0)
    with pytest.raises(InvalidInputError, match="azimuth_deg"):
        multiangle_lab(paint, W, [15.0, 45.0, 110.0], azimuth_deg=[0.0, 90.0])
