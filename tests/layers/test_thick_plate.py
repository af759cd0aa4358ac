"""Transmittance of a thick plate in air (Beer–Lambert + Fresnel faces) against closed forms."""

import numpy as np

from nmmm.layers.thick_plate import plate_transmittance


def test_plate_transmittance_analytic():
    w = np.array([500.0, 600.0])
    # lossless n = 1.5: T = (1-R)^2/(1-R^2) = 2n/(n^2+1) (Born & Wolf, incoherent slab)
    T = plate_transmittance(np.array([1.5, 1.5]), w, 1e6)
    np.testing.assert_allclose(T, 2 * 1.5 / (1.5**2 + 1), rtol=1e-12)
    T = plate_transmittance(np.array([1.5 + 1e-5j] * 2), w, np.array([[1e6], [2e6]]), multiple_reflections=False)
    R = (0.5 / 2.5) ** 2
    np.testing.assert_allclose(T, (1 - R) ** 2 * np.exp(-4 * np.pi * 1e-5 / w * np.array([[1e6], [2e6]])), rtol=1e-6)
