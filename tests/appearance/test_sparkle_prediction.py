"""Sparkle and graininess predicted from the composition (issue 18 item 5).

The metric of nmmm.appearance.sparkle.sparkle_graininess (sparkle density, area fraction,
intensity, graininess) computed on a rendered image of the grey metallic coat (camera along
the normal, a directional light at 15°, 25°, 45° and 75° from it, as in multi-angle sparkle
instruments; 40 µm pixels) agrees with the prediction of
nmmm.appearance.sparkle_prediction from the flake statistics alone (number density,
areas, depths, tilt density, coat index, lobe width): the same metric applied to images
drawn from the compound-Poisson law of the glints per pixel (no flake positions, no
renderer), plus the analytic band-pass graininess.

Tolerances are sampling errors: the sparkle count and the glinting pixels are Poisson
(sqrt(count)), the prediction's spread is that of 12 statistical images; 3 combined standard
errors each.
"""

import numpy as np
import pytest

from nmmm.appearance.render import DirectionalLight, PinholeCamera, render_plate, seed_metallic_plate
from nmmm.appearance.sparkle import sparkle_graininess
from nmmm.appearance.sparkle_prediction import (
    glint_footprint_statistics,
    plate_light_geometry,
    predicted_graininess,
    predicted_sparkle,
)

W550 = np.array([550.0])
PIXEL_UM = 40.0
N_PIX = 160


@pytest.fixture(scope="module")
def setup():
    plate = seed_metallic_plate(cells=(40, 40), rng=3)
    fov = 2 * np.degrees(np.arctan(N_PIX * PIXEL_UM * 1e-3 / 2 / 300.0))
    cam = PinholeCamera((0.0, 0.0, 300.0), (0.0, 0.0, 0.0), fov_deg=fov, resolution=(N_PIX, N_PIX))
    return plate, cam


def _measure_and_predict(plate, cam, illumination_deg, n_sim=12):
    light = DirectionalLight.from_angles(illumination_deg, 90.0, 1.0, 1.0)
    img = render_plate(plate, cam, light, wavelength_nm=W550, glint_spread_deg=1.0)
    measured = sparkle_graininess(img.radiance[..., 0].astype(float), PIXEL_UM)
    A, P, wi, wo, E = plate_light_geometry(cam, light)
    brdf = plate.smooth_brdf

    def ev(comps):
        return brdf.evaluate(W550, wi.reshape(-1, 3), wo.reshape(-1, 3), components=comps)[:, 0].reshape(A.shape) * E

    smooth, flakes = ev(("specular", "base", "multiple")), ev(("flakes",))
    st = glint_footprint_statistics(brdf, plate.flakes, wi, wo, A, glint_spread_deg=1.0)
    sims = [predicted_sparkle(smooth, flakes, st, PIXEL_UM, rng=k) for k in range(n_sim)]
    return measured, sims, predicted_graininess(smooth, flakes, st, PIXEL_UM), st


@pytest.mark.parametrize("illumination_deg", [15.0, 25.0, 45.0, 75.0])
def test_sparkle_and_graininess_of_a_render_match_the_prediction(setup, illumination_deg):
    plate, cam = setup
    m, sims, g_analytic, st = _measure_and_predict(plate, cam, illumination_deg)
    n_px = N_PIX * N_PIX

    def pred(key):
        v = np.array([getattr(s, key) for s in sims])
        return v.mean(), v.std(ddof=1)

    # sparkle density: the count of sparkles is Poisson
    p, sp = pred("density_per_mm2")
    se = np.hypot(np.sqrt(max(m.n_sparkles, 1)) / m.image_area_mm2, sp)
    assert abs(m.density_per_mm2 - p) < 3 * se, (m.density_per_mm2, p, se)
    # area fraction (glinting pixels, Poisson) and the sparkle intensity it scales
    p, sp = pred("area_fraction")
    se = np.hypot(np.sqrt(m.area_fraction * n_px) / n_px, sp)
    assert abs(m.area_fraction - p) < 3 * se, (m.area_fraction, p, se)
    p, sp = pred("sparkle_intensity")
    rel = np.hypot(1 / np.sqrt(m.area_fraction * n_px), sp / p)
    assert abs(m.sparkle_intensity / p - 1) < 3 * rel, (m.sparkle_intensity, p, rel)
    # graininess: the spread of the statistical images is its sampling error
    p, sp = pred("graininess")
    assert abs(m.graininess - p) < 3 * sp, (m.graininess, p, sp)
    assert abs(g_analytic / p - 1) < 0.15, (g_analytic, p)
    # under 1 glinting flake per 40 µm pixel: sparkles are single flakes
    assert float(st.glinting_flakes.mean()) < 0.05


def test_sparkle_falls_with_the_illumination_angle(setup):
    """Sparkle density, measured and predicted, fall from 15° to 75° illumination (fewer
    flakes tilted towards the half vector: p(θh) of the 12° tilt density)."""
    plate, cam = setup
    meas, pred = [], []
    for a in (15.0, 45.0, 75.0):
        m, sims, _, _ = _measure_and_predict(plate, cam, a, n_sim=4)
        meas.append(m.density_per_mm2)
        pred.append(np.mean([s.density_per_mm2 for s in sims]))
    assert np.all(np.diff(meas) < 0) and np.all(np.diff(pred) < 0), (meas, pred)
    assert meas[0] / meas[-1] > 2 and pred[0] / pred[-1] > 2


def test_sparkle_from_composition_without_rendering(setup):
    """The no-render prediction (paint + flake cell + angles) agrees with the metric on the
    rendered images at 15° and 75°, within 3 combined sampling errors."""
    from nmmm.appearance.sparkle_prediction import sparkle_from_composition

    plate, cam = setup
    pred = sparkle_from_composition(plate.smooth_brdf, plate.flakes, (15.0, 75.0), pixel_size_um=PIXEL_UM,
                                    size_px=N_PIX, n_images=6)
    for a in (15.0, 75.0):
        m, _, _, _ = _measure_and_predict(plate, cam, a, n_sim=1)
        p = pred[a]
        se = np.hypot(np.sqrt(m.n_sparkles) / m.image_area_mm2, p["density_per_mm2_sd"])
        assert abs(m.density_per_mm2 - p["density_per_mm2"]) < 3 * se, (a, m.density_per_mm2, p)
        assert abs(m.graininess - p["graininess"]) < 3 * p["graininess_sd"], (a, m.graininess, p)
    assert pred[15.0]["density_per_mm2"] > 2 * pred[75.0]["density_per_mm2"]


def test_sparkle_from_composition_bad_input(setup):
    from nmmm.appearance.sparkle_prediction import sparkle_from_composition
    from nmmm.errors import InvalidInputError

    plate, _ = setup
    with pytest.raises(InvalidInputError, match="illumination_deg"):
        sparkle_from_composition(plate.smooth_brdf, plate.flakes, (95.0,))
    with pytest.raises(InvalidInputError, match="pixel_size_um"):
        sparkle_from_composition(plate.smooth_brdf, plate.flakes, (45.0,), pixel_size_um=0.0)
    with pytest.raises(InvalidInputError, match="glint_spread_deg"):
        sparkle_from_composition(plate.smooth_brdf, plate.flakes, (45.0,), glint_spread_deg=-1.0)


@pytest.mark.parametrize("wavelength_nm", [450.0, 650.0])
def test_weights_of_flakes_that_transmit_follow_the_discrete_flakes(wavelength_nm):
    """Interference flakes (TiO2/mica, τ = 3, flat: σ = 0.5°, one size): a glint's weight is
    a e^{−x ζ}, x the flake layer's optical depth in and out. The prediction's ⟨w²⟩/⟨w⟩² is that
    of the discrete flakes' powers (flake_list_reflection, whose mean is the BRDF's flake term)
    at the mirror geometry, with the BRDF's extinction per direction τ a(μ)(1 − T̄(μ, λ))/μ:
    measured 1.3609/1.2835 (450 nm, 20°/60°) and 1.0059/1.0267 (650 nm) against the prediction's
    1.3609/1.2830 and 1.0058/1.0266; with the mean τ_e it was 1.3071 and 1.1121 at both angles."""
    from nmmm.appearance.brdf import ClearCoat, PaintBRDF, flake_list_reflection, interference_paint
    from nmmm.appearance.flakes import FlakeList, gaussian_tilt

    ref = interference_paint(optical_depth=3.0, tilt=gaussian_tilt(0.5))
    n = 2000
    side = np.sqrt(n * np.pi * 15e3 ** 2 / 4 / 3.0)
    fl = FlakeList.random(ref.flakes.optics, ref.flakes.tilt, n, region_nm=(side, side), mean_diameter_nm=15e3,
                          diameter_cv=0.0, rng=3)
    paint = PaintBRDF(ClearCoat(1.5), 0.0, fl.to_flake_layer())
    w = np.array([wavelength_nm])
    tab = paint.prepare(w)
    assert not tab.tau_e_const  # the flakes transmit
    zeta = fl.optical_depth_above() / fl.optical_depth
    for th in (20.0, 60.0):
        t = np.radians(th)
        wi, wo = np.array([np.sin(t), 0.0, np.cos(t)]), np.array([-np.sin(t), 0.0, np.cos(t)])
        _, power, esc = flake_list_reflection(paint, fl, w, wi)
        p = power[esc, 0]
        discrete = np.mean(p * p) / np.mean(p) ** 2
        st = glint_footprint_statistics(paint, fl, wi, wo, 1e-3, wavelength_nm=wavelength_nm)
        assert abs(float(st.weight_ratio) - discrete) < 2e-3, (th, float(st.weight_ratio), discrete)
        # the mean τ_e (one extinction for every direction) gives another law, far off
        mu = np.cos(np.arcsin(np.sin(t) / 1.5))
        x0 = tab.tau_e[0] * 2 * np.interp(np.degrees(np.arccos(mu)), np.linspace(0, 90, tab.a_tab.size), tab.a_tab) / mu
        e = np.exp(-x0 * zeta)
        assert abs(np.mean(e * e) / np.mean(e) ** 2 - discrete) > 0.02
