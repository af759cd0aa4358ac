"""A size parameter below the series' checked domain (x < 1e-8, down to where x² underflows) is refused
with an InvalidInputError naming the diameter, n_medium and wavelength, by the one-sphere fast path and
the general path alike; it was a bare ZeroDivisionError from the kernel (review R2)."""

import numpy as np
import pytest

from nmmm.errors import InvalidInputError
from nmmm.layers import mie, mie_coated
from nmmm.layers.mie_series import MIN_SIZE_PARAMETER


@pytest.mark.parametrize("args", [
    (1.5 + 0.01j, 1.0, 1e-300, 500.0),   # diameter
    (1.5, 1.0, 5e-324, 500.0),           # the smallest subnormal: x = 0
    (1.5, 1e-320, 100.0, 500.0),         # n_medium
    (1.5, 1.0, 100.0, 1e308),            # wavelength
])
def test_tiny_size_parameter_is_refused_on_both_paths(args):
    n, nm, d, w = args
    with pytest.raises(InvalidInputError, match=r"size parameter x = pi d n_medium / lambda is .* below 1e-08"):
        mie(n, nm, d, w)                             # plain numbers: the fast path hands over to the general one
    with pytest.raises(InvalidInputError, match=r"below 1e-08"):
        mie(n, nm, np.array([d, 100.0]), w)          # arrays: the general path


def test_outer_diameter_below_the_limit_is_refused_for_coated_spheres():
    with pytest.raises(InvalidInputError, match=r"diameter 2e-100 nm.*below 1e-08: a particle"):
        mie_coated(1.5, 1.3, 1.0, 1e-100, 2e-100, 500.0)
    with pytest.raises(InvalidInputError, match=r"diameter 1e-300 nm.*below 1e-150: a core"):
        mie_coated(1.5, 1.3, 1.0, 1e-300, 100.0, 500.0)   # a core that small underflowed in the kernel
    # a core of 1e-100 nm computes, and is no core: the shell alone
    np.testing.assert_allclose(mie_coated(1.5, 1.3, 1.0, 1e-100, 100.0, 500.0).qext, mie(1.3, 1.0, 100.0, 500.0).qext,
                               rtol=1e-12)


def test_at_the_limit_the_rayleigh_law_holds():
    """At x = 1e-8 Q_sca = 8/3 x⁴ |(m²−1)/(m²+2)|² and Q_abs = 4 x Im((m²−1)/(m²+2)) (Bohren & Huffman eqs. 5.8, 5.11)."""
    m, w = 1.5 + 0.1j, 500.0
    d = MIN_SIZE_PARAMETER * w / np.pi
    r = mie(m, 1.0, d, w)
    a = (m**2 - 1) / (m**2 + 2)
    x = np.pi * d / w
    np.testing.assert_allclose(r.qsca, 8 / 3 * x**4 * abs(a) ** 2, rtol=1e-6)
    np.testing.assert_allclose(r.qabs, 4 * x * a.imag, rtol=1e-6)
