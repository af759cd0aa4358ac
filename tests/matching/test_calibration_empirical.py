"""The empirical mode of calibration: two-constant Kubelka–Munk, Duncan mixing, Saunderson (issue 17 item 5)."""

import numpy as np
import pytest

from nmmm.errors import InvalidInputError
from nmmm.matching.calibration import LadderSample, _Sample
from nmmm.matching.empirical_km import calibrate_empirical, duncan_mixing, empirical_reflectance, fit_km_constants
from nmmm.recipes.schema import example_path, read_toml, set_key


# --- independent closed forms, written here from the textbooks (not nmmm's code) -------------------
def r_inf(K, S):
    """Kubelka–Munk opaque reflectance R∞ = 1 + K/S − sqrt((K/S)² + 2K/S)."""
    q = K / S
    return 1 + q - np.sqrt(q * q + 2 * q)


def r_over_black(K, S, X):
    """Kubelka (1948) over an ideal black: R0 = sinh(bSX) / (a sinh(bSX) + b cosh(bSX))."""
    a = 1 + K / S
    b = np.sqrt(a * a - 1)
    return np.sinh(b * S * X) / (a * np.sinh(b * S * X) + b * np.cosh(b * S * X))


def r_over(K, S, X, Rg):
    """Kubelka's general form written with R∞ and T: R = R0 + T² Rg / (1 − R0 Rg)."""
    a = 1 + K / S
    b = np.sqrt(a * a - 1)
    den = a * np.sinh(b * S * X) + b * np.cosh(b * S * X)
    R0, T = np.sinh(b * S * X) / den, b / den
    return R0 + T * T * Rg / (1 - R0 * Rg)


def saunderson_sce(Rb, k1, k2):
    return (1 - k1) * (1 - k2) * Rb / (1 - k2 * Rb)


# known colourants per unit fraction (per µm), on 5 wavelengths: a red (absorbs the blue) and a white
K_TRUE = np.array([[40.0, 30.0, 8.0, 1.0, 0.5], [1e-3, 1e-3, 1e-3, 1e-3, 1e-3]])
S_TRUE = np.array([[2.0, 2.5, 3.0, 3.5, 3.0], [8.0, 7.0, 6.0, 5.5, 5.0]])
K1, K2 = 0.045, 0.60


def test_duncan_and_km_match_the_closed_forms():
    c = np.array([0.03, 0.09])
    Km, Sm = duncan_mixing(c, K_TRUE, S_TRUE)
    np.testing.assert_allclose(Km, 0.03 * K_TRUE[0] + 0.09 * K_TRUE[1], rtol=1e-15)
    thick = empirical_reflectance(Km, Sm, 1e4, 0.8, K1, K2)  # 1 cm: opaque
    np.testing.assert_allclose(thick, saunderson_sce(r_inf(Km, Sm), K1, K2), rtol=1e-12)
    for X, Rg in ((5.0, 0.0), (20.0, 0.0), (5.0, 0.8), (40.0, 0.3)):
        got = empirical_reflectance(Km, Sm, X, Rg, K1, K2)
        want = saunderson_sce(r_over_black(Km, Sm, X) if Rg == 0 else r_over(Km, Sm, X, Rg), K1, K2)
        np.testing.assert_allclose(got, want, rtol=1e-10)
    # specular included adds k1: R = k1 + (1 - k1)(1 - k2) Rb / (1 - k2 Rb)
    inc = empirical_reflectance(Km, Sm, 1e4, 0.8, K1, K2, specular="included")
    np.testing.assert_allclose(inc, K1 + saunderson_sce(r_inf(Km, Sm), K1, K2), rtol=1e-12)


def _synthetic_films():
    """Masstone, tints with white, over white and over black, two thicknesses: (c, X µm, Rg)."""
    films = [((0.05, 0.0), 30.0, 0.8), ((0.0, 0.12), 30.0, 0.8), ((0.0, 0.12), 30.0, 0.0), ((0.02, 0.08), 30.0, 0.8),
             ((0.02, 0.08), 30.0, 0.0), ((0.01, 0.09), 15.0, 0.8), ((0.005, 0.1), 15.0, 0.0), ((0.03, 0.06), 20.0, 0.8)]
    c = np.array([f[0] for f in films])
    X = np.array([f[1] for f in films])
    Rg = np.array([f[2] for f in films])
    Km, Sm = c @ K_TRUE, c @ S_TRUE
    R = saunderson_sce(np.where(Rg[:, None] == 0, r_over_black(Km, Sm, X[:, None]),
                                r_over(Km, Sm, X[:, None], Rg[:, None])), K1, K2)
    return c, X, Rg, R


def test_a_synthetic_ladder_with_known_k_and_s_is_recovered():
    c, X, Rg, R = _synthetic_films()
    fit = slice(0, 7)  # the last film is left out
    K, S, rms = fit_km_constants(c[fit], X[fit], Rg[fit], R[fit], K1, K2)
    np.testing.assert_allclose(K[0], K_TRUE[0], rtol=1e-4)
    np.testing.assert_allclose(S, S_TRUE, rtol=1e-4)
    assert np.all(K[1] < 0.05) and rms.max() < 1e-8
    pred = empirical_reflectance(c[7] @ K, c[7] @ S, X[7], Rg[7], K1, K2)
    np.testing.assert_allclose(pred, R[7], atol=1e-6)
    # with measurement noise 0.002 the left-out film is still predicted to about the noise
    noisy = R + np.random.default_rng(3).normal(0, 0.002, R.shape)
    K, S, rms = fit_km_constants(c[fit], X[fit], Rg[fit], noisy[fit], K1, K2)
    assert np.abs(empirical_reflectance(c[7] @ K, c[7] @ S, X[7], Rg[7], K1, K2) - R[7]).max() < 0.01


def test_more_unknowns_than_data_is_refused():
    c, X, Rg, R = _synthetic_films()
    with pytest.raises(InvalidInputError, match="more unknowns than data"):
        fit_km_constants(c[:3], X[:3], Rg[:3], R[:3], K1, K2)  # 4 unknowns per wavelength, 3 films


def _ladder(substrates=None):
    raw, _, _ = read_toml(example_path("hematite_tint"))
    spec = {"white": (0.0, 0.12, 0.8), "masstone": (0.05, 0.0, 0.8), "1:1": (0.04, 0.04, 0.8), "1:4": (0.02, 0.08, 0.8),
            "1:4 over black": (0.02, 0.08, 0.0), "1:9": (0.01, 0.09, 0.8), "1:2": (0.03, 0.06, 0.8)}
    out = []
    for name, (h, r, g) in spec.items():
        rr = set_key(set_key(set_key(raw, "pigments.0.fraction", h), "pigments.1.fraction", r), "film.substrate_reflectance", g)
        s = _Sample(LadderSample(name, rr, np.zeros(16)), "hematite")
        out.append(LadderSample(name, rr, s.reflectance(1.0, 1.0)))
    return out


@pytest.fixture(scope="module")
def ladder():
    return _ladder()


def test_calibrate_empirical_on_a_recipe_ladder(ladder):
    cal = calibrate_empirical(ladder, left_out=("1:2",))
    assert cal.colourants == ("hematite", "rutile")
    assert cal.specular == "excluded"  # the tint is measured de:8
    # k1 from the epoxy's Cauchy index (A 1.566, B 0.00796 µm², C 0.00014 µm⁴): Fresnel at normal incidence;
    # k2 its diffuse internal reflectance, above Judd's 0.596 for n = 1.5 as n is higher (1.59-1.62)
    lam = cal.wavelength_nm / 1000
    n = 1.566 + 0.00796 / lam**2 + 0.00014 / lam**4
    np.testing.assert_allclose(cal.k1, ((n - 1) / (n + 1)) ** 2, rtol=1e-6)
    assert np.all((cal.k2 > 0.62) & (cal.k2 < 0.67)) and np.all(np.diff(cal.k2) < 0)
    assert set(cal.de00_after) == {s.name for s in ladder}
    # adding-doubling 'measurements' are not a KM world: the empirical constants reproduce them to about 1 ΔE00
    assert cal.de00_after["1:2"] < 1.5
    rows = cal.table()
    assert len(rows) == 16 and rows[0]["wavelength_nm"] == 400 and rows[0]["K_hematite_per_um"] > rows[-1]["K_hematite_per_um"]


def test_a_ladder_whose_recipes_differ_in_what_the_empirical_fit_cannot_use(ladder):
    other = LadderSample("bigger grains", set_key(ladder[3].recipe, "pigments.0.diameter_nm", 300), ladder[3].reflectance)
    with pytest.raises(InvalidInputError, match=r"pigment 'hematite' differs .*diameter_nm"):
        calibrate_empirical(ladder[:3] + [other])
    binder = LadderSample("other binder", set_key(ladder[3].recipe, "compounds.epoxy", {"n": 1.5}), ladder[3].reflectance)
    with pytest.raises(InvalidInputError, match=r"differs from sample 'white' in \[compounds\]"):
        calibrate_empirical(ladder[:3] + [binder])
    with pytest.raises(InvalidInputError, match="more unknowns than data"):
        calibrate_empirical(ladder[:3])
    with pytest.raises(InvalidInputError, match="left_out names"):
        calibrate_empirical(ladder, left_out=("nope",))


def _fresnel_unpolarised(n, theta_i_deg):
    """Fresnel reflectance (s and p averaged) from a medium of index n into air, at internal angle θ_i."""
    ti = np.radians(theta_i_deg)
    tt = np.arcsin(n * np.sin(ti))
    rs = (n * np.cos(ti) - np.cos(tt)) / (n * np.cos(ti) + np.cos(tt))
    rp = (np.cos(ti) - n * np.cos(tt)) / (np.cos(ti) + n * np.cos(tt))
    return 0.5 * (rs**2 + rp**2)


def test_the_surface_correction_follows_the_geometry_of_the_ladder():
    """0:d includes the specular component like di:8; at 0:45a / 45a:0 the diffuse flux leaves
    towards the 45° viewer: R = (1 − k1)(1 − R_F(45°)) R_b / (n² (1 − k2 R_b)) (Saunderson 1942;
    Völz 2001 §3.4), written here from Fresnel's equations."""
    base = _ladder()
    for geometry, specular in (("0:d", "included"), ("di:8", "included"), ("de:8", "excluded"), ("45a:0", "excluded")):
        lad = [LadderSample(s.name, set_key(s.recipe, "measurement.geometry", geometry), s.reflectance) for s in base[:4]]
        cal = calibrate_empirical(lad)
        assert (cal.specular, cal.geometry) == (specular, geometry)
        if geometry.startswith("45"):
            lam = cal.wavelength_nm / 1000
            n = 1.566 + 0.00796 / lam**2 + 0.00014 / lam**4
            ex = (1 - _fresnel_unpolarised(n, np.degrees(np.arcsin(np.sin(np.radians(45.0)) / n)))) / n**2
            np.testing.assert_allclose(cal.exit_factor, ex, rtol=1e-9)
        else:
            assert cal.exit_factor is None
    # K and S of known colourants are recovered from films 'measured' at 45a:0 with that form
    c, X, Rg, _ = _synthetic_films()
    Km, Sm = c @ K_TRUE, c @ S_TRUE
    n = 1.55
    ex = (1 - _fresnel_unpolarised(n, np.degrees(np.arcsin(np.sin(np.radians(45.0)) / n)))) / n**2
    Rb = np.where(Rg[:, None] == 0, r_over_black(Km, Sm, X[:, None]), r_over(Km, Sm, X[:, None], Rg[:, None]))
    R = (1 - K1) * ex * Rb / (1 - K2 * Rb)
    np.testing.assert_allclose(empirical_reflectance(Km, Sm, X[:, None], Rg[:, None], K1, K2, exit_factor=ex), R, rtol=1e-12)
    K, S, rms = fit_km_constants(c[:7], X[:7], Rg[:7], R[:7], K1, K2, exit_factor=ex)
    np.testing.assert_allclose(S, S_TRUE, rtol=1e-4)
    np.testing.assert_allclose(K[0], K_TRUE[0], rtol=1e-4)


def test_a_ladder_without_a_contrast_pair_that_shows_through_says_so():
    """K and S of films that hide are fixed as a ratio, not in scale: measured with noise 0.002, films
    over white only (or a pair over white and black that hides) give K, S many times off where no pair
    shows contrast, and within a few % where a thin pair differs by 0.02 or more — and the calibration
    says where (IdentifiabilityWarning), from the measured spectra, not from its own fit."""
    from nmmm.matching.empirical_km import CONTRAST, _identifiability
    from nmmm.matching.recipe_match import IdentifiabilityWarning

    def films(spec):
        c, X, Rg = np.array([f[0] for f in spec]), np.array([f[1] for f in spec]), np.array([f[2] for f in spec])
        Km, Sm = c @ K_TRUE, c @ S_TRUE
        return c, X, Rg, saunderson_sce(np.where(Rg[:, None] == 0, r_over_black(Km, Sm, X[:, None]),
                                                 r_over(Km, Sm, X[:, None], Rg[:, None])), K1, K2)

    over_white = [((0.05, 0.0), 60.0, 0.8), ((0.0, 0.12), 60.0, 0.8), ((0.04, 0.04), 60.0, 0.8), ((0.02, 0.08), 60.0, 0.8),
                  ((0.01, 0.09), 60.0, 0.8)]
    w = np.array([400.0, 450.0, 500.0, 550.0, 600.0])
    cases = {"no pair": (over_white, "no two fitted films share a recipe"),
             "a pair that hides": (over_white + [((0.02, 0.08), 60.0, 0.0)], "differ by at most 0.01"),
             "a thin pair": (over_white + [((0.01, 0.09), 5.0, 0.8), ((0.01, 0.09), 5.0, 0.0)], "at 2 of 5 wavelengths (400-450 nm)")}
    for name, (spec, said) in cases.items():
        c, X, Rg, R = films(spec)
        with pytest.warns(IdentifiabilityWarning, match=r"ratio far better than in scale") as rec:
            notes = _identifiability(c, X, Rg, R, w, ("red", "white"))
        assert len(notes) == 1 and said in notes[0] and len(rec) == 1, (name, notes)
    contrast = np.abs(R[-1] - R[-2])
    assert np.all(contrast[:2] <= CONTRAST) and np.all(contrast[2:] >= 0.02)
    errors = []
    for seed in (1, 2, 3):
        noisy = R + np.random.default_rng(seed).normal(0, 0.002, R.shape)
        K, S, _ = fit_km_constants(c, X, Rg, noisy, K1, K2)
        errors.append(np.abs(np.log(S / S_TRUE)).max(axis=0))
    errors = np.array(errors)
    assert np.all(errors[:, 2:] < np.log(1.10)) and errors[:, :2].max() > np.log(5), errors
    # as many films as unknowns: said as well
    c, X, Rg, R = films(over_white[:4])
    with pytest.warns(IdentifiabilityWarning):
        notes = _identifiability(c, X, Rg, R, w, ("red", "white"))
    assert "4 fitted films for 4 unknowns" in notes[0]
