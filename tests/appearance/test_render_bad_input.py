"""Bad input to the plate renderer gives clean errors naming what is wrong (issue 19, bad input)."""

import numpy as np
import pytest

from nmmm.appearance.render import DirectionalLight, LatLongEnvironment, PaintedPlate, PinholeCamera, render_plate
from nmmm.appearance.render.plate import LambertianBRDF
from nmmm.errors import InvalidInputError, NmmmError

W = np.array([450.0, 550.0, 650.0])


def _plate():
    return PaintedPlate(LambertianBRDF(0.5), None, (150.0, 100.0))


def test_camera_that_misses_the_plate_is_refused():
    cam = PinholeCamera((0.0, -180.0, 420.0), (2000.0, 0.0, 0.0), fov_deg=5.0, resolution=(8, 6))
    with pytest.raises(InvalidInputError, match="(no pixel centre of the camera falls on the plate|looks away)"):
        render_plate(_plate(), cam, lights=[DirectionalLight.from_angles(30, 0, "D65")], wavelength_nm=W)


def test_camera_behind_the_plate_is_refused():
    cam = PinholeCamera((0.0, 0.0, -300.0), (0.0, 0.0, 0.0), resolution=(8, 6))
    with pytest.raises(InvalidInputError, match="behind the plate"):
        render_plate(_plate(), cam, lights=[DirectionalLight.from_angles(30, 0, "D65")], wavelength_nm=W)


def test_environment_map_with_negative_radiance_names_the_texel():
    r = np.ones((4, 8, 3))
    r[2, 5, 1] = -0.5
    with pytest.raises(InvalidInputError, match=r"environment radiance must be >= 0.*row 2, column 5.*550 nm.*-0\.5"):
        LatLongEnvironment(W, r)


def test_environment_map_with_non_finite_radiance_is_refused():
    r = np.ones((4, 8, 3))
    r[0, 0, 0] = np.nan
    with pytest.raises(NmmmError, match="environment radiance"):
        LatLongEnvironment(W, r)


def test_pixels_beyond_the_memory_bound_are_refused_with_the_estimate():
    cam = PinholeCamera((0.0, -180.0, 420.0), (0.0, 0.0, 0.0), resolution=(200000, 133333))
    with pytest.raises(InvalidInputError, match="max_memory_gb"):
        render_plate(_plate(), cam, lights=[DirectionalLight.from_angles(30, 0, "D65")], wavelength_nm=W)
