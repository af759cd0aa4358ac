"""flake_deposit_capacity: how full the rigid deposit model fills a layer (issue 18, a fraction that cannot fit)."""

import numpy as np
import pytest

from nmmm.errors import InvalidInputError
from nmmm.microstructure import flake_deposit
from nmmm.microstructure.flakes import flake_deposit_capacity

# a small cell of the grey metallic's flakes (20 µm × 300 nm, 6° spread) in a 10 µm layer: ~1 ms a deposit
COMP = dict(box_nm=(150e3, 150e3, 10e3), diameter_nm=("lognormal", 20e3, 6e3), thickness_nm=300.0, tilt_std_deg=6.0)


def test_capacity_is_deterministic_sorted_and_seeded_by_reference_cells():
    a = flake_deposit_capacity(**COMP, realisations=16)
    assert np.array_equal(a, flake_deposit_capacity(**COMP, realisations=16))
    assert a.shape == (16,) and np.all(np.diff(a) >= 0) and np.all((a > 0) & (a < 1))
    assert not np.array_equal(a, flake_deposit_capacity(**COMP, realisations=16, seed=7))


def test_capacity_predicts_how_often_the_deposit_overflows():
    # one cell overflows at phi exactly when the flakes laid before its first overflow hold less than phi: the share of
    # reference capacities below phi is the share of seeds refused (here 0.5 and ~0.1 by construction, 120 seeds)
    caps = flake_deposit_capacity(**COMP, realisations=120)
    for q in (0.5, 0.1):
        phi = float(np.quantile(caps, q))
        refused = 0
        for s in range(120):
            try:
                flake_deposit(fraction=phi, seed=1000 + s, **COMP)
            except InvalidInputError as exc:
                assert exc.n_fit < exc.n_flakes
                refused += 1
        assert refused / 120 == pytest.approx(q, abs=0.15), (q, refused)


def test_the_wider_the_tilt_spread_the_emptier_the_full_layer():
    # rigid flakes rest on the highest point under them: even flat ones leave binder voids (~0.12 of 300 nm flakes
    # with 100 nm gaps in a 10 µm layer), and tilted ones build towers that reach the top early (6°: ~0.023)
    med = [float(np.median(flake_deposit_capacity(**dict(COMP, tilt_std_deg=s), realisations=8))) for s in (0, 3, 6, 15)]
    assert med[0] > 0.08 and med[0] > med[1] > med[2] > med[3], med


def test_bad_arguments():
    with pytest.raises(InvalidInputError, match="realisations"):
        flake_deposit_capacity(**COMP, realisations=0)
    with pytest.raises(InvalidInputError, match="tilt_std_deg"):
        flake_deposit_capacity(**dict(COMP, tilt_std_deg=-1.0))
