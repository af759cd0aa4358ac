"""Rhombohedral pigments (hematite's {01-12} pseudo-cubes) as equivalent spheres.

Independent references: the cube (α = 90°: V = a³, S = 6a²) and scipy's convex hull of the
rhombohedron's 8 vertices (Qhull volume and area), built from three edge vectors at the
angle α — no use of the closed forms under test.
"""

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from nmmm.errors import InvalidInputError
from nmmm.layers.distributions import (
    HEMATITE_RHOMBOHEDRON_ANGLE_DEG,
    equivalent_sphere_diameter,
    rhombohedron_volume_surface,
)


def _edge_vectors(a, alpha_deg):
    """Three edges of length a, pairwise at angle α, symmetric about the z axis."""
    c = np.cos(np.radians(alpha_deg))
    # unit vectors at polar angle t from z, 120° apart in azimuth:
    # u_i·u_j = cos²t + sin²t·cos(120°) = 1 − 1.5 sin²t = cos α
    sin2t = 2 * (1 - c) / 3
    st, ct = np.sqrt(sin2t), np.sqrt(1 - sin2t)
    phi = np.radians([0.0, 120.0, 240.0])
    u = np.stack([st * np.cos(phi), st * np.sin(phi), np.full(3, ct)], axis=1)
    assert np.allclose(u @ u.T, np.where(np.eye(3, dtype=bool), 1.0, c))
    return a * u


def _hull(a, alpha_deg):
    e = _edge_vectors(a, alpha_deg)
    corners = np.array([i * e[0] + j * e[1] + k * e[2] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    return ConvexHull(corners)


@pytest.mark.parametrize("alpha", [60.0, HEMATITE_RHOMBOHEDRON_ANGLE_DEG, 110.0])
def test_rhombohedron_volume_surface_match_convex_hull(alpha):
    h = _hull(170.0, alpha)
    V, S = rhombohedron_volume_surface(170.0, alpha)
    assert V == pytest.approx(h.volume, rel=1e-10)
    assert S == pytest.approx(h.area, rel=1e-10)


@pytest.mark.parametrize("alpha", [60.0, HEMATITE_RHOMBOHEDRON_ANGLE_DEG, 110.0])
def test_rhombohedron_equivalent_spheres_match_convex_hull(alpha):
    h = _hull(200.0, alpha)
    V, S = h.volume, h.area
    kw = dict(edge_nm=200.0, angle_deg=alpha)
    assert equivalent_sphere_diameter("rhombohedron", **kw) == pytest.approx((6 * V / np.pi) ** (1 / 3), rel=1e-10)
    assert equivalent_sphere_diameter("rhombohedron", "surface", **kw) == pytest.approx(np.sqrt(S / np.pi), rel=1e-10)
    assert equivalent_sphere_diameter("rhombohedron", "volume_to_surface", **kw) == pytest.approx(6 * V / S, rel=1e-10)


def test_rhombohedron_at_90_degrees_is_the_cube():
    a = 123.0
    V, S = rhombohedron_volume_surface(a, 90.0)
    assert V == pytest.approx(a**3, rel=1e-12)
    assert S == pytest.approx(6 * a**2, rel=1e-12)
    for method in ("volume", "surface", "volume_to_surface"):
        assert equivalent_sphere_diameter("rhombohedron", method, edge_nm=a, angle_deg=90.0) == pytest.approx(
            equivalent_sphere_diameter("cube", method, edge_nm=a), rel=1e-12)
    # the closed form for the cube, independently: D_V = a (6/π)^{1/3}, D_V/S = a
    assert equivalent_sphere_diameter("rhombohedron", edge_nm=a, angle_deg=90.0) == pytest.approx(a * (6 / np.pi) ** (1 / 3))


def test_hematite_angle_from_the_hexagonal_cell():
    """α of the {01-12} rhombohedron from the cell of Blake et al. (1966), a = 5.0356 Å, c = 13.7489 Å."""
    a, c = 5.0356, 13.7489
    lat = np.array([[a, 0, 0], [-a / 2, a * np.sqrt(3) / 2, 0], [0, 0, c]])
    rec = np.linalg.inv(lat).T
    n = np.array([np.array(hkl) @ rec for hkl in ([0, 1, 2], [1, -1, 2], [-1, 0, 2])])
    e0, e1 = np.cross(n[0], n[1]), np.cross(n[1], n[2])
    e0, e1 = (x if x[2] < 0 else -x for x in (e0, e1))
    alpha = np.degrees(np.arccos(e0 @ e1 / np.linalg.norm(e0) / np.linalg.norm(e1)))
    assert HEMATITE_RHOMBOHEDRON_ANGLE_DEG == pytest.approx(alpha, abs=0.05)


@pytest.mark.parametrize("dims, word", [
    (dict(edge_nm=100.0), "angle_deg"),
    (dict(angle_deg=85.7), "edge_nm"),
    (dict(edge_nm=100.0, angle_deg=120.0), "angle_deg"),
    (dict(edge_nm=100.0, angle_deg=0.0), "angle_deg"),
    (dict(edge_nm=100.0, angle_deg=np.nan), "angle_deg"),
    (dict(edge_nm=-1.0, angle_deg=85.7), "edge_nm"),
])
def test_rhombohedron_bad_input(dims, word):
    with pytest.raises(InvalidInputError, match=word):
        equivalent_sphere_diameter("rhombohedron", **dims)
