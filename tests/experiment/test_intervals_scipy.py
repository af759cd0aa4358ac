"""The proportion intervals now come from scipy's ``binomtest(...).proportion_ci`` (issue 23 item 5):
they equal the closed forms nmmm used to write by hand (Wilson 1927 score interval, Clopper-Pearson
beta quantiles) on every k of several n, at several levels, and still broadcast over arrays."""

import numpy as np
import pytest
from scipy import special, stats

from nmmm.experiment.stats import proportion_ci, proportion_ci_clopper_pearson, proportion_ci_wilson


def _wilson_closed_form(k, n, confidence):
    z = special.ndtri(0.5 + confidence / 2)
    p = k / n
    denom = 1 + z**2 / n
    centre = (p + z**2 / (2 * n)) / denom
    half = z / denom * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2))
    lo, hi = np.clip(centre - half, 0, 1), np.clip(centre + half, 0, 1)
    return np.where(k == 0, 0.0, lo), np.where(k == n, 1.0, hi)


def _clopper_pearson_closed_form(k, n, confidence):
    a = 1 - confidence
    with np.errstate(invalid="ignore"):
        lo = np.where(k == 0, 0.0, stats.beta.ppf(a / 2, np.maximum(k, 1), n - k + 1))
        hi = np.where(k == n, 1.0, stats.beta.ppf(1 - a / 2, k + 1, np.maximum(n - k, 1)))
    return lo, hi


@pytest.mark.parametrize("n", [1, 2, 7, 20, 263, 800])
@pytest.mark.parametrize("confidence", [0.8, 0.9, 0.95, 0.99])
def test_same_as_the_closed_forms(n, confidence):
    k = np.arange(n + 1)
    np.testing.assert_allclose(proportion_ci_wilson(k, n, confidence), _wilson_closed_form(k, n, confidence),
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(proportion_ci_clopper_pearson(k, n, confidence),
                               _clopper_pearson_closed_form(k, n, confidence), rtol=0, atol=1e-9)


def test_shapes_scalars_and_ends():
    lo, hi = proportion_ci_wilson(81, 263)
    assert np.ndim(lo) == 0 and np.ndim(hi) == 0
    lo, hi = proportion_ci(np.array([[0, 5], [10, 10]]), np.array([10, 10]), method="exact")
    assert lo.shape == hi.shape == (2, 2)
    assert lo[0, 0] == 0.0 and hi[1, 1] == 1.0 and hi[1, 0] == 1.0
