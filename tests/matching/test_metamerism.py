"""CIEDE2000 residuals and the CIE special metamerism index (issue 17 items 2, 3)."""

import numpy as np
import pytest

from nmmm.matching import delta_e2000_residuals, delta_lch, metamerism_index

# Sharma, Wu & Dalal (2005) Table 1: pairs 1, 7, 13, 17, 25 with their published ΔE00
SHARMA = [((50.0, 2.6772, -79.7751), (50.0, 0.0, -82.7485), 2.0425),
          ((50.0, 0.0, 0.0), (50.0, -1.0, 2.0), 2.3669),
          ((50.0, 2.5, 0.0), (56.0, -27.0, -3.0), 31.9030),
          ((50.0, 2.5, 0.0), (73.0, 25.0, -18.0), 27.1492),
          ((60.2574, -34.0099, 36.2677), (60.4626, -34.1751, 39.4387), 1.2644)]


@pytest.mark.parametrize("a, b, de", SHARMA)
def test_residual_norm_is_the_published_de00(a, b, de):
    assert np.linalg.norm(delta_e2000_residuals(a, b)) == pytest.approx(de, abs=1e-4)


def test_residual_norm_is_colour_sciences_de00_on_random_pairs():
    import colour

    rng = np.random.default_rng(3)
    a = np.column_stack([rng.uniform(5, 95, 400), rng.uniform(-80, 80, 400), rng.uniform(-80, 80, 400)])
    b = a + rng.normal(0, 4, a.shape)
    b[:, 0] = np.clip(b[:, 0], 0, 100)
    np.testing.assert_allclose(np.linalg.norm(delta_e2000_residuals(a, b), axis=-1),
                               colour.delta_E(a, b, method="CIE 2000"), rtol=1e-9, atol=1e-9)


def test_delta_lch_decomposes_de_ab():
    a, b = np.array([50.0, 20.0, 10.0]), np.array([48.0, 15.0, 18.0])
    dL, dC, dH = delta_lch(a, b)
    assert dL == pytest.approx(-2.0)
    assert dC == pytest.approx(np.hypot(15, 18) - np.hypot(20, 10))
    assert dL**2 + dC**2 + dH**2 == pytest.approx(np.sum((b - a) ** 2))
    assert dH > 0  # hue turns from a* towards b*


W = np.arange(380.0, 781.0, 10.0)
STD = 0.25 + 0.35 * np.exp(-((W - 600) / 70) ** 2)


def _lab_colour(R, ill):
    """CIELAB through colour-science alone (ASTM E308), as a user of colour would compute it."""
    import warnings

    import colour

    warnings.filterwarnings("ignore", message=".*Trimming.*")  # colour-science trims to the CMF range
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    sd = colour.SpectralDistribution(R, W)
    xyz = colour.sd_to_XYZ(sd, cmfs, colour.SDS_ILLUMINANTS[ill], method="ASTM E308") / 100
    white = colour.sd_to_XYZ(colour.SpectralDistribution(np.ones_like(W), W), cmfs, colour.SDS_ILLUMINANTS[ill],
                             method="ASTM E308") / 100
    return colour.XYZ_to_Lab(xyz, colour.XYZ_to_xy(white))


def test_isomeric_pair_has_index_zero():
    assert metamerism_index(W, STD, STD.copy(), "A") == pytest.approx(0.0, abs=1e-9)


def test_constructed_metameric_pair_gives_the_cie15_value():
    """A metameric black (in the null space of the D65 weighting) added to the standard: the pair
    matches under D65 and differs under A; the index is ΔE00 under A, computed here with colour."""
    from nmmm.colour import spectra_to_lab, weighting_factors

    Wd65 = weighting_factors(W, "D65")
    _, _, vt = np.linalg.svd(Wd65.T)
    black = vt[5] / np.abs(vt[5]).max()  # orthogonal to the three D65 weighting columns
    smp = STD + 0.15 * black
    assert np.all(smp > 0)
    np.testing.assert_allclose(spectra_to_lab(W, smp, "D65"), spectra_to_lab(W, STD, "D65"), atol=1e-9)
    import colour

    expected = colour.delta_E(_lab_colour(STD, "A"), _lab_colour(smp, "A"), method="CIE 2000")
    got = metamerism_index(W, STD, smp, "A", "D65")
    assert expected > 0.2  # a visible change under A
    assert got == pytest.approx(expected, rel=1e-6)


def test_imperfect_pair_uses_the_additive_correction():
    import colour

    smp = STD * 1.03  # not a match under D65 either
    lr_s, lr_m = _lab_colour(STD, "D65"), _lab_colour(smp, "D65")
    lt_s, lt_m = _lab_colour(STD, "FL11"), _lab_colour(smp, "FL11")
    expected = colour.delta_E(lt_s, lt_m - (lr_m - lr_s), method="CIE 2000")
    assert metamerism_index(W, STD, smp, "TL84") == pytest.approx(expected, abs=1e-6)


def test_negative_corrected_lightness_is_said_not_silently_clipped():
    """A near-black standard against a bright blue sample: the additive correction (L*_A(sample) -
    L*_D65(sample) + L*_D65(standard)) falls below 0; the index warns that the pair is no near match."""
    import warnings

    from nmmm.colour import spectra_to_lab
    from nmmm.matching.metamerism import metamerism_index

    w = np.arange(400.0, 701.0, 10.0)
    std, smp = np.full(w.size, 0.001), np.where(w < 520, 0.6, 0.0)
    L = {ill: spectra_to_lab(w, r, ill)[0] for ill, r in (("A", smp), ("D65", smp))}
    expected = L["A"] - L["D65"] + spectra_to_lab(w, std, "D65")[0]
    assert expected < 0
    with pytest.warns(UserWarning, match=rf"L\* under A to {expected:.2f} < 0 \(clipped to 0\).*not a metamerism index"):
        metamerism_index(w, std, smp, "A")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        metamerism_index(w, smp, smp * 1.01, "A")  # a near match: no warning
