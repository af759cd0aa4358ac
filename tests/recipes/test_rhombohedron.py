"""Rhombohedral pigments in recipes (hematite's {01-12} pseudo-cubes, seed example 2)."""

import numpy as np
import pytest

from nmmm.errors import RecipeError
from nmmm.recipes.run import run_recipe
from nmmm.recipes.schema import parse_recipe, set_key

from .conftest import fast_raw


def _rhombohedral(edge_nm=170.0, angle_deg=85.7, **extra):
    raw = fast_raw("hematite_paint", step_nm=40.0)
    raw["pigment"].pop("body_diagonal_nm")
    raw["pigment"].update(shape="rhombohedron", edge_nm=edge_nm, angle_deg=angle_deg, **extra)
    return raw


def _err(raw) -> str:
    with pytest.raises(RecipeError) as ei:
        parse_recipe(raw)
    return str(ei.value)


@pytest.mark.parametrize("key, value, expected", [
    ("pigment.angle_deg", 120.0, "pigment.angle_deg: Input should be less than 120"),
    ("pigment.angle_deg", 0.0, "pigment.angle_deg: Input should be greater than 0"),
    ("pigment.angle_deg", float("nan"), "pigment.angle_deg"),
    ("pigment.angle_deg", "85.7", "pigment.angle_deg: Input should be a valid number"),
    ("pigment.edge_nm", -3.0, "pigment.edge_nm"),
])
def test_bad_rhombohedron_values_name_the_key(key, value, expected):
    assert expected in _err(set_key(_rhombohedral(), key, value))


def test_rhombohedron_needs_edge_and_angle():
    raw = _rhombohedral()
    raw["pigment"].pop("angle_deg")
    assert "pigment: a rhombohedron pigment is sized by angle_deg + edge_nm; got ['edge_nm']" in _err(raw)
    # an angle is meaningless for a cube
    raw = fast_raw("hematite_paint")
    raw["pigment"]["angle_deg"] = 85.7
    assert "pigment: a cube pigment is sized by" in _err(raw)


def test_rhombohedral_recipe_equals_its_equal_volume_sphere(tmp_path):
    a, alpha = 170.0, 85.7
    c = np.cos(np.radians(alpha))
    volume = a**3 * np.sqrt(1 - 3 * c * c + 2 * c**3)  # parallelepiped of three edges at angle alpha
    d_sphere = (6 * volume / np.pi) ** (1 / 3)
    rh = run_recipe(_rhombohedral(a, alpha), tmp_path / "rh", progress=False, report=False)
    sp_raw = _rhombohedral()
    for k in ("edge_nm", "angle_deg"):
        sp_raw["pigment"].pop(k)
    sp_raw["pigment"].update(shape="sphere", diameter_nm=d_sphere)
    sp = run_recipe(sp_raw, tmp_path / "sp", progress=False, report=False)
    assert rh.scalars["equivalent_diameter_nm"] == pytest.approx(d_sphere, rel=1e-12)
    assert rh.primary == sp.primary
    np.testing.assert_allclose(rh.spectra[rh.primary], sp.spectra[sp.primary], rtol=1e-12, atol=1e-14)
    # and it is a different paint from a cube of the same edge (not a no-op shape)
    cube_raw = set_key(sp_raw, "pigment.shape", "cube")
    cube_raw["pigment"].pop("diameter_nm")
    cube_raw["pigment"]["edge_nm"] = a
    cube = run_recipe(cube_raw, tmp_path / "cube", progress=False, report=False)
    assert np.max(np.abs(cube.spectra[cube.primary] - rh.spectra[rh.primary])) > 1e-4
