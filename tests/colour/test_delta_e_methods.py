"""nmmm.colour.delta_e: ΔE*ab, ΔE94, CMC(l:c), ΔE00 (kL:kC:kH), ΔL*/ΔC*/ΔH*, tolerance — against colour-science."""

import colour
import numpy as np
import pytest

from nmmm.colour import DELTA_E_METHODS, delta_e, delta_e2000, delta_lch, within_tolerance
from nmmm.colour.difference import _delta_e2000_k
from nmmm.errors import InvalidInputError

# Sharma, Wu & Dalal (2005) Table 1: pairs 1, 7, 13, 17, 25 with their published ΔE00
SHARMA = [((50.0, 2.6772, -79.7751), (50.0, 0.0, -82.7485), 2.0425),
          ((50.0, 0.0, 0.0), (50.0, -1.0, 2.0), 2.3669),
          ((50.0, 2.5, 0.0), (56.0, -27.0, -3.0), 31.9030),
          ((50.0, 2.5, 0.0), (50.0, 0.0, -2.5), 4.3065),
          ((60.2574, -34.0099, 36.2677), (60.4626, -34.1751, 39.4387), 1.2644)]


def _pairs(n=300, seed=3):
    rng = np.random.default_rng(seed)
    a = np.column_stack([rng.uniform(0, 100, n), rng.uniform(-90, 90, n), rng.uniform(-90, 90, n)])
    b = a + rng.normal(0, 6, (n, 3))
    b[:, 0] = np.clip(b[:, 0], 0, 100)
    return a, b


@pytest.mark.parametrize("method, k, ref", [
    ("CIE 1976", {}, {}),
    ("CIE 1994", {}, {"textiles": False}),
    ("CIE 1994", {"textiles": True}, {"textiles": True}),
    ("CMC", {}, {"l": 2, "c": 1}),
    ("CMC", {"l": 1, "c": 1}, {"l": 1, "c": 1}),
    ("CIE 2000", {}, {"textiles": False}),
    ("CIE 2000", {"kL": 2}, {"textiles": True}),
])
def test_equals_colour_science_on_random_pairs(method, k, ref):
    a, b = _pairs()
    np.testing.assert_allclose(delta_e(a, b, method, **k), colour.delta_E(a, b, method=method, **ref), rtol=1e-12)


def test_aliases_and_hand_computed_delta_e_ab():
    assert delta_e([50, 0, 0], [53, 4, 0], "dE76") == pytest.approx(5.0)
    for alias, name in (("de00", "CIE 2000"), ("CIEDE2000", "CIE 2000"), ("dE94", "CIE 1994"), ("cmc", "CMC")):
        assert delta_e([50, 10, 5], [52, 12, 3], alias) == pytest.approx(delta_e([50, 10, 5], [52, 12, 3], name))
    assert set(DELTA_E_METHODS) == {"CIE 1976", "CIE 1994", "CMC", "CIE 2000"}


def test_delta_e2000_parametric_factors():
    a, b = _pairs()
    # the general-k formula equals colour-science where it has them (1:1:1 and textiles 2:1:1) ...
    np.testing.assert_allclose(_delta_e2000_k(a, b, 1, 1, 1), colour.delta_E(a, b, method="CIE 2000"), rtol=1e-10)
    np.testing.assert_allclose(_delta_e2000_k(a, b, 2, 1, 1), colour.delta_E(a, b, method="CIE 2000", textiles=True),
                               rtol=1e-10)
    # ... and Sharma 2005's published pairs
    for l1, l2, de in SHARMA:
        assert float(_delta_e2000_k(np.array(l1), np.array(l2), 1, 1, 1)) == pytest.approx(de, abs=1e-4)
        assert float(delta_e(l1, l2, "CIE 2000", kL=1.0, kC=1.0, kH=1.0)) == pytest.approx(de, abs=1e-4)
    # a pure lightness step (neutral) scales with 1/kL, a pure chroma step (same hue) with 1/kC
    assert delta_e([50, 0, 0], [54, 0, 0], kL=3) == pytest.approx(delta_e2000([50, 0, 0], [54, 0, 0]) / 3)
    assert delta_e([50, 20, 0], [50, 24, 0], kC=2, kH=1.5) == pytest.approx(delta_e2000([50, 20, 0], [50, 24, 0]) / 2)
    # a pure hue step at constant C* (no rotation term near h 0°) with 1/kH
    h = np.radians(5.0)
    p, q = [50, 20, 0], [50, 20 * np.cos(h), 20 * np.sin(h)]
    assert delta_e(p, q, kH=2, kC=1.3) == pytest.approx(delta_e2000(p, q) / 2, rel=1e-3)


def test_delta_lch_decomposition():
    a, b = _pairs()
    d = delta_lch(a, b)
    np.testing.assert_allclose(np.sum(d**2, axis=-1), colour.delta_E(a, b, method="CIE 1976") ** 2, rtol=1e-9)
    lch_a, lch_b = colour.Lab_to_LCHab(a), colour.Lab_to_LCHab(b)
    np.testing.assert_allclose(d[:, 0], b[:, 0] - a[:, 0])
    np.testing.assert_allclose(d[:, 1], lch_b[:, 1] - lch_a[:, 1], atol=1e-9)
    dh = (lch_b[:, 2] - lch_a[:, 2] + 180) % 360 - 180  # hue turned counter-clockwise -> ΔH* > 0
    big = np.abs(d[:, 2]) > 1e-6
    assert np.all(np.sign(d[big, 2]) == np.sign(dh[big]))
    # CIE 15 definition: ΔH* = 2 √(C1 C2) sin(Δh/2)
    np.testing.assert_allclose(d[:, 2], 2 * np.sqrt(lch_a[:, 1] * lch_b[:, 1]) * np.sin(np.radians(dh) / 2), atol=1e-7)


def test_within_tolerance_pass_fail():
    de, ok = within_tolerance([[50, 0, 0], [50, 0, 0]], [[50.5, 0, 0], [60, 0, 0]], 1.0, "CIE 1976")
    np.testing.assert_allclose(de, [0.5, 10.0])
    assert ok.tolist() == [True, False]
    de, ok = within_tolerance([50, 10, 5], [51, 11, 5], 1.0, "CMC", l=2, c=1)
    assert bool(ok) == (float(colour.delta_E([50, 10, 5], [51, 11, 5], method="CMC")) <= 1.0)


def test_bad_inputs_say_what_is_allowed():
    with pytest.raises(InvalidInputError, match="CIE 1976, CIE 1994, CMC, CIE 2000"):
        delta_e([50, 0, 0], [50, 1, 0], "CIE 1999")
    with pytest.raises(InvalidInputError, match="kL, kC, kH"):
        delta_e([50, 0, 0], [50, 1, 0], "CIE 2000", l=2)
    with pytest.raises(InvalidInputError, match="> 0"):
        delta_e([50, 0, 0], [50, 1, 0], "CMC", l=0)
    with pytest.raises(InvalidInputError, match="tolerance"):
        within_tolerance([50, 0, 0], [50, 1, 0], -1)
