"""The fused coarse-grid passes of the plate renderer equal the NumPy expressions they replace
(issue 22 item 5: no (pixels × wavelengths) float64 temporaries)."""

import numpy as np

from nmmm.appearance.brdf import metallic_paint, opaque_paint
from nmmm.appearance.render.plate.coarse_grid import accumulate_light, add_environment


def _dirs(rng, n):
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2])
    v[:5] = [(0, 0, 1), (1, 0, 0), (0, 1, 1e-9), (0.6, 0, 0.8), (0, -1, 0)]  # normal, grazing
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def test_light_and_environment_passes_equal_the_numpy_expressions():
    rng = np.random.default_rng(4)
    w = np.linspace(380.0, 780.0, 41)
    wi, wo = _dirs(rng, 3000), _dirs(rng, 3000)
    s1, s2 = rng.uniform(0, 2, 3000), rng.uniform(0, 2, 3000)
    sp1, sp2, env = rng.uniform(0, 1, 41), rng.uniform(0, 1, 41), rng.uniform(0, 1, 41)
    for brdf in (metallic_paint(), opaque_paint(0.4)):
        f = brdf.evaluate(w, wi, wo)
        ref = f * s1[:, None] * sp1[None, :] + f * s2[:, None] * sp2[None, :] + brdf.albedo(w, wo) * env[None, :]
        out = np.zeros((3000, 41), np.float32)
        accumulate_light(out, f, s1, sp1, True)
        accumulate_light(out, f, s2, sp2, False)
        add_environment(out, brdf, w, wo, env, False)
        np.testing.assert_allclose(out, ref, rtol=2e-6, atol=1e-7 * np.abs(ref).max())
        only_env = np.full((3000, 41), np.nan, np.float32)
        add_environment(only_env, brdf, w, wo, env, True)
        np.testing.assert_allclose(only_env, brdf.albedo(w, wo) * env[None, :], rtol=2e-6, atol=1e-9)
