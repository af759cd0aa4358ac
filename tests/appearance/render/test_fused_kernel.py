"""The branch-free fused BRDF kernels (geometry per pair, then wavelength loops whose absent
terms enter with weight 0) equal the NumPy path term by term, for every paint family and
component subset, in float64 and float32 (issue 22 item 5, render speed); the effect-coat kernel
(``fused_kernel.evaluate_effect``: a pigmented basecoat, opaque flakes or flakes that transmit,
flakes in a band or through the whole coat) too, and its parts (issue 18 speed)."""

from dataclasses import replace

import numpy as np
import pytest

from nmmm.appearance.brdf import CoatMedium, clear_dielectric, interference_paint, metallic_paint, opaque_paint

W = np.linspace(380.0, 780.0, 33)


def _medium(w=W):
    return CoatMedium(w, 2e-4 * np.exp(-((w - 480.0) / 60.0) ** 2) + 1e-6, 3e-5, 0.5, 2e4)


def _banded(paint, band=(0.4, 0.8)):
    return paint.with_(flakes=replace(paint.flakes, depth_range=band, edge_fraction=0.02), medium=_medium())


PAINTS = {
    "solid": opaque_paint(0.45),
    "solid rough": opaque_paint(0.3, roughness=0.08),
    "clear": clear_dielectric(1.5, roughness=0.1),
    "metallic": metallic_paint(),
    "metallic rough": metallic_paint(roughness=0.05),
    "pearl": interference_paint(),
    # the effect-coat kernel: whole-coat flakes (no pigment above or below them), then a band
    "metallic pigmented": metallic_paint(roughness=0.05).with_(medium=_medium()),
    "metallic pigmented band": _banded(metallic_paint()),
    "pearl pigmented band": _banded(interference_paint()),
}
SUBSETS = [("specular", "flakes", "base", "multiple"), ("specular", "base", "multiple"), ("flakes",), ("base",),
           ("multiple",), ("specular",)]


def _pairs(n=400, seed=3):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(2, n, 3))
    v[..., 2] = np.abs(v[..., 2])
    v[:, :4] = [(0, 0, 1), (1, 0, 1e-9), (0.6, 0, 0.8), (0, 0.999, 0.0447)]  # normal, grazing
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


@pytest.mark.parametrize("name", list(PAINTS))
def test_fused_kernel_equals_numpy_path(name):
    b = PAINTS[name]
    wi, wo = _pairs()
    for comps in SUBSETS:
        ref = b(W, wi, wo, components=comps, method="numpy")
        assert np.all(np.isfinite(ref))
        np.testing.assert_allclose(b(W, wi, wo, components=comps), ref, rtol=1e-9, atol=1e-14)
        f32 = b(W, wi, wo, components=comps, dtype=np.float32)
        assert f32.dtype == np.float32
        np.testing.assert_allclose(f32, ref, rtol=1e-6, atol=1e-30)  # float32: a few roundings


def test_below_the_surface_is_zero():
    b = PAINTS["metallic"]
    wi, wo = _pairs(50)
    wo[:10, 2] *= -1
    f = b(W, wi, wo, below_surface="zero")
    assert np.all(f[:10] == 0) and np.all(f[10:] > 0)


def test_effect_kernel_attenuation_factors_are_the_tables():
    """The effect kernel reads the pigments' attenuation exp(−c S') (the tables ``_Qd``, ``_Qz``,
    ``_Qb``, 2048 rows) as hi[j // 64] · lo[j % 64] (``fused_kernel._attenuation_factors``): the
    same numbers within 1e-14 relative at every row, and the row after each block edge."""
    from nmmm.appearance.brdf.fused_kernel import _Q_BLOCK, _attenuation_factors

    tab = PAINTS["pearl pigmented band"].prepare(W)
    assert tab.z0 > 0 and tab.dz < 1 and not tab.tau_e_const
    j = np.arange(tab._Qd.shape[0])
    for Q, f in ((tab._Qd, tab.dz), (tab._Qz, tab.z0), (tab._Qb, 1.0 - tab.dz)):
        hi, lo = _attenuation_factors(np.asarray(tab.kappa) * f, tab._s2_step, Q.shape[0])
        assert hi.shape[0] * _Q_BLOCK >= Q.shape[0] and lo.shape[0] == _Q_BLOCK + 1
        np.testing.assert_allclose(hi[j // _Q_BLOCK] * lo[j % _Q_BLOCK], Q, rtol=1e-14, atol=0)
        jj = j[:-1]  # the interpolation's upper row, lo[j % 64 + 1] up to lo[64]
        np.testing.assert_allclose(hi[jj // _Q_BLOCK] * lo[jj % _Q_BLOCK + 1], Q[1:], rtol=1e-14, atol=0)


def test_direction_check_fast_path_is_check_directions():
    """PaintBRDF.evaluate validates directions in one Numba pass (``paint_brdf._checked_directions``):
    check_directions' renormalised vectors to the bit, and its errors for what it refuses."""
    from nmmm.appearance.brdf.paint_brdf import _checked_directions
    from nmmm.appearance.flakes import check_directions
    from nmmm.errors import InvalidInputError

    rng = np.random.default_rng(5)
    v = rng.normal(size=(3000, 2, 3))
    v[..., 2] = np.abs(v[..., 2])
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    v[:1000] *= 1 + rng.uniform(-9e-7, 9e-7, (1000, 2, 1))  # within the tolerance: renormalised
    v[0, 0], v[0, 1], v[1, 0] = (0, 0, 1), (1, 0, 0), (0, 1, -0.0)
    for a in (v, v[0, 0], v[::2], v.astype(np.float32), [[0.6, 0, 0.8]]):
        ref, got = check_directions(a, "wi"), _checked_directions(a, "wi")
        assert got.dtype == ref.dtype and got.shape == ref.shape
        assert np.array_equal(got, ref) and np.array_equal(np.signbit(got), np.signbit(ref))
    for bad in (v[:5] * 1.01, [(0, 0.6, -0.8)], [(np.nan, 0, 1)], [(np.inf, 0, 1)], [(0.0, 1.0)]):
        with pytest.raises(InvalidInputError) as ref:
            check_directions(np.asarray(bad, float), "wo")
        with pytest.raises(InvalidInputError) as got:
            _checked_directions(np.asarray(bad, float), "wo")
        assert str(got.value) == str(ref.value)
