"""Colorimetry (nmmm.colour) against colour-science and published values.

This folder has no ``__init__.py`` on purpose: as a package it would be importable as ``colour``
(pytest puts ``tests/`` on ``sys.path``) and shadow colour-science itself.
"""

import colour
import numpy as np
import pytest

import nmmm
from nmmm.colour import delta_e2000, spectra_to_lab, spectra_to_srgb, spectra_to_xyz, xyz_to_srgb


def test_perfect_white_reflector():
    w = np.arange(380, 781, 5.0)
    for ill in ("D65", "A", "D50"):
        np.testing.assert_allclose(spectra_to_lab(w, np.ones_like(w), illuminant=ill), [100, 0, 0], atol=1e-9)


def test_matches_colour_science_integration_on_1nm_grid():
    w = np.arange(360, 781, 1.0)
    rng = np.random.default_rng(1)
    R = 0.2 + 0.6 * rng.random((3, w.size))
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(colour.SpectralShape(360, 780, 1))
    ill = colour.SDS_ILLUMINANTS["D65"].copy().align(colour.SpectralShape(360, 780, 1))
    for r, xyz in zip(R, spectra_to_xyz(w, R)):
        sd = colour.SpectralDistribution(dict(zip(w, r)))
        ref = colour.sd_to_XYZ(sd, cmfs, ill, method="Integration")
        np.testing.assert_allclose(xyz, ref, rtol=2e-3)


def test_colour_checker_dark_skin_lab():
    # colour-science's ColorChecker N Ohta 'dark skin' reflectance under D65: compare with colour's
    # own pipeline (sd_to_XYZ ASTM E308 then XYZ_to_Lab) on the same data
    sd = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]["dark skin"]
    w = np.arange(380, 781, 5.0)
    r = sd.copy().align(colour.SpectralShape(380, 780, 5)).values
    ref_xyz = colour.sd_to_XYZ(sd, illuminant=colour.SDS_ILLUMINANTS["D65"])
    ref_lab = colour.XYZ_to_Lab(ref_xyz / 100, colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"])
    assert delta_e2000(spectra_to_lab(w, r), ref_lab) < 0.3


def test_delta_e2000_sharma_test_data():
    # Sharma, Wu & Dalal (2005), Table 1, pairs 1 and 7
    assert delta_e2000([50.0, 2.6772, -79.7751], [50.0, 0.0, -82.7485]) == pytest.approx(2.0425, abs=1e-4)
    assert delta_e2000([50.0, 0.0, 0.0], [50.0, -1.0, 2.0]) == pytest.approx(2.3669, abs=1e-4)


def test_stack_and_vectorisation():
    w = np.arange(380, 781, 1.0)
    R = np.random.default_rng(2).random((100000, w.size))
    lab = spectra_to_lab(w, R)
    assert lab.shape == (100000, 3)
    lab2 = spectra_to_lab(w, R[:10].reshape(2, 5, -1))
    np.testing.assert_allclose(lab2.reshape(10, 3), lab[:10])


def test_white_is_srgb_white():
    w = np.arange(380, 781, 5.0)
    np.testing.assert_allclose(spectra_to_srgb(w, np.ones_like(w)), [1, 1, 1], atol=2e-3)


def test_bad_inputs():
    w = np.arange(380, 781, 5.0)
    with pytest.raises(nmmm.InvalidInputError):
        spectra_to_lab(w, np.full_like(w, np.nan))
    with pytest.raises(nmmm.InvalidInputError):
        spectra_to_lab(w, np.ones(10))
    with pytest.raises(nmmm.InvalidInputError, match="illuminant"):
        spectra_to_lab(w, np.ones_like(w), illuminant="D66")
    with pytest.raises(nmmm.OutOfRangeError):
        spectra_to_lab(np.arange(380, 831, 5.0), np.ones(91))  # D65 in colour-science stops at 780 nm
    with pytest.raises(nmmm.InvalidInputError, match="last axis of 3"):
        delta_e2000([50.0, 2.0], [50.0, 2.0, 3.0])
    with pytest.raises(nmmm.InvalidInputError, match="NaN"):
        delta_e2000([np.nan, 2.0, 3.0], [50.0, 2.0, 3.0])
    with pytest.raises(nmmm.InvalidInputError, match="NaN"):
        xyz_to_srgb([np.nan, 20.0, 30.0])
    with pytest.raises(nmmm.InvalidInputError, match="Y > 0"):
        xyz_to_srgb([10.0, 20.0, 30.0], white_xyz=[0.0, 0.0, 0.0])


def test_truncated_grid_warns():
    w = np.arange(500, 511, 1.0)
    with pytest.warns(UserWarning, match="truncated"):
        spectra_to_lab(w, np.ones_like(w))
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        spectra_to_lab(np.arange(400, 701, 5.0), np.ones(61))
