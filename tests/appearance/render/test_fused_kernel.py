"""The branch-free fused BRDF kernel (geometry per pair, then one wavelength loop whose absent
terms enter with weight 0) equals the NumPy path term by term, for every paint family and
component subset, in float64 and float32 (issue 22 item 5, render speed)."""

import numpy as np
import pytest

from nmmm.appearance.brdf import clear_dielectric, interference_paint, metallic_paint, opaque_paint

W = np.linspace(380.0, 780.0, 33)
PAINTS = {
    "solid": opaque_paint(0.45),
    "solid rough": opaque_paint(0.3, roughness=0.08),
    "clear": clear_dielectric(1.5, roughness=0.1),
    "metallic": metallic_paint(),
    "metallic rough": metallic_paint(roughness=0.05),
    "pearl": interference_paint(),
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
