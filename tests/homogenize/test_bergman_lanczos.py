"""One Lanczos run for every wavelength of a two-phase cell, against COCG and exact laminates."""

import warnings

import numpy as np
import pytest

from nmmm.errors import InvalidInputError
from nmmm.homogenize import fft_permittivity, two_phase_spectrum
from nmmm.homogenize import geometries as G


def test_matches_cocg_at_every_wavelength():
    lab = G.boolean_spheres(16, 0.2, 2.5, ndim=3, seed=4)
    em = np.array([-50 + 20j, -44 + 13j, -10 + 1j, 8 + 3j, 2.25 + 0j])  # the last: homogeneous
    a = two_phase_spectrum(lab, {0: 2.25, 1: em}, tol=1e-9, workers=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        b = fft_permittivity(lab, {0: 2.25, 1: em}, tol=1e-9, green="willot2015", workers=1)
    assert np.abs(a.diagonal - b.diagonal).max() <= 1e-6 * np.abs(b.diagonal).max()
    assert np.allclose(a.diagonal[-1], 2.25)
    # one run per loading costs the slowest wavelength, not the sum
    assert max(a.metadata["projections"]) <= a.iterations.max() + 3  # + the 3 axes' right-hand sides
    assert sum(a.metadata["projections"]) < b.iterations.sum()


@pytest.mark.parametrize("green", ["willot2015", "willot2014", "continuous"])
def test_laminate_is_exact(green):
    lab = np.zeros((8, 8, 8), dtype=int)
    lab[:, :, 2:5] = 1  # layers normal to z, phase 1 fraction 3/8
    em = np.array([-50 + 20j, -10 + 1j, 12 + 0.5j])
    r = two_phase_spectrum(lab, {0: 2.25, 1: em}, green=green, tol=1e-10, workers=1)
    p = 3 / 8
    arith = (1 - p) * 2.25 + p * em
    harm = 1 / ((1 - p) / 2.25 + p / em)
    assert np.allclose(r.diagonal[:, 0], arith, rtol=1e-8) and np.allclose(r.diagonal[:, 1], arith, rtol=1e-8)
    assert np.allclose(r.diagonal[:, 2], harm, rtol=1e-8)


def test_needs_two_phases():
    lab = np.zeros((4, 4, 4), dtype=int)
    lab[0] = 1
    lab[1] = 2
    with pytest.raises(InvalidInputError, match="two phases"):
        two_phase_spectrum(lab, {0: 1.0, 1: 2.0, 2: 3.0})


@pytest.mark.parametrize("kw,key", [({"directions": [3]}, "directions"), ({"directions": [-1]}, "directions"),
                                    ({"tol": 0.0}, "tol"), ({"tol": 2.0}, "tol"), ({"maxiter": 0}, "maxiter")])
def test_bad_settings_are_refused_by_name(kw, key):
    """As fft_permittivity refuses them (review Q: directions=[3] raised IndexError, [-1] ran e2, tol=2
    returned the one-step answer)."""
    lab = np.zeros((4, 4, 4), dtype=int)
    lab[:, :, :2] = 1
    with pytest.raises(InvalidInputError, match=key):
        two_phase_spectrum(lab, {0: 2.25, 1: np.array([-50 + 20j, -10 + 1j])}, workers=1, **kw)
