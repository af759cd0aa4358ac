"""colour-science interop (issue 23 item 3): every spectra entry point of nmmm.colour takes a
SpectralDistribution / MultiSpectralDistributions alone, spectra come back as them, and the CIE
weighting is colour-science's ASTM E308 — checked against colour.sd_to_XYZ(..., method="ASTM E308")
called on each distribution separately (an independent route through colour-science)."""

import warnings

import colour
import numpy as np
import pytest

from nmmm.colour import (
    as_spectral_distributions,
    spectra_to_lab,
    spectra_to_srgb,
    spectra_to_xyz,
    weighting_factors,
    white_point,
)
from nmmm.errors import InvalidInputError

CMFS = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
CHECKER = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]


def _e308(sd, illuminant="D65"):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return np.asarray(colour.sd_to_XYZ(sd, CMFS, colour.SDS_ILLUMINANTS[illuminant], method="ASTM E308"))


@pytest.mark.parametrize("step", [5.0, 10.0, 20.0])
@pytest.mark.parametrize("illuminant", ["D65", "A"])
def test_weighting_is_astm_e308(step, illuminant):
    w = np.arange(380.0, 780.1, step)
    sds = [colour.SpectralDistribution(np.interp(w, sd.wavelengths, sd.values), w, name=n) for n, sd in CHECKER.items()]
    R = np.stack([sd.values for sd in sds])
    ours = spectra_to_xyz(w, R, illuminant=illuminant)
    ref = np.stack([_e308(sd, illuminant) for sd in sds])
    np.testing.assert_allclose(ours, ref, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(weighting_factors(w, illuminant)[:, 1].sum(), 100.0, rtol=1e-12)


def test_distributions_alone_are_accepted():
    sd = CHECKER["dark skin"]
    w, v = sd.wavelengths, sd.values
    np.testing.assert_allclose(spectra_to_xyz(sd), _e308(sd), rtol=1e-9)
    np.testing.assert_array_equal(spectra_to_lab(sd), spectra_to_lab(w, v))
    np.testing.assert_array_equal(spectra_to_srgb(sd), spectra_to_srgb(w, v))
    np.testing.assert_array_equal(spectra_to_lab(w, sd), spectra_to_lab(w, v))  # as values, on the same grid
    np.testing.assert_array_equal(white_point(sd), white_point(w))
    msds = colour.colorimetry.sds_and_msds_to_msds(list(CHECKER.values()))
    lab = spectra_to_lab(msds, illuminant="A", observer="10")
    assert lab.shape == (24, 3)
    np.testing.assert_allclose(lab[0], spectra_to_lab(w, v, illuminant="A", observer="10"), rtol=1e-12)
    with pytest.raises(InvalidInputError, match="not on wavelength_nm"):
        spectra_to_lab(np.arange(400.0, 701.0, 10.0), sd)
    with pytest.raises(InvalidInputError, match="alone"):
        spectra_to_xyz(sd, v)


def test_spectra_returned_as_distributions():
    w = np.arange(380.0, 781.0, 10.0)
    R = np.stack([np.linspace(0.1, 0.9, w.size), np.full(w.size, 0.5)])
    msds = as_spectral_distributions(w, R, labels=["ramp", "grey"])
    assert isinstance(msds, colour.MultiSpectralDistributions) and list(msds.labels) == ["ramp", "grey"]
    np.testing.assert_array_equal(msds.values.T, R)
    np.testing.assert_allclose(spectra_to_xyz(msds), spectra_to_xyz(w, R), rtol=1e-12)
    sd = as_spectral_distributions(w, R[0], name="ramp")
    assert isinstance(sd, colour.SpectralDistribution) and sd.name == "ramp"
    with pytest.raises(InvalidInputError):
        as_spectral_distributions(w, R[:, :-1])


def test_illuminant_values_on_the_grid_keep_the_interval_sum():
    """An illuminant given only as values on the grid has no 1 nm data for E308: the documented
    fallback weights each sample by its interval (D65 sampled at 5 nm lands within 0.05 of E308)."""
    w = np.arange(380.0, 781.0, 5.0)
    s = np.asarray(colour.SDS_ILLUMINANTS["D65"][w])
    np.testing.assert_allclose(white_point(w, illuminant=s), white_point(w, "D65"), atol=0.05)


@pytest.mark.parametrize("step", [2.0, 40.0])
def test_other_intervals_are_e308_of_the_linear_interpolation_to_1nm(step):
    w = np.arange(380.0, 780.1, step)
    R = np.stack([np.interp(w, sd.wavelengths, sd.values) for sd in CHECKER.values()])
    w1 = np.arange(380.0, 781.0)
    ref = np.stack([_e308(colour.SpectralDistribution(np.interp(w1, w, r), w1)) for r in R])
    np.testing.assert_allclose(spectra_to_xyz(w, R), ref, rtol=1e-9, atol=1e-9)
