"""Kreibig size damping of gold (issue 24 item 1) against published gold-colloid size series.

Independent references:
- W. Haiss, N. T. K. Thanh, J. Aveyard, D. G. Fernig, Anal. Chem. 79, 4215 (2007): measured
  citrate gold colloids in water, 5-100 nm (TEM sizes). Their eq. 11, d = exp(B1 A_spr/A_450 - B2)
  with the parameters fitted to their *experimental* spectra, B1 = 3.00, B2 = 2.20 (5-80 nm,
  11 % mean deviation from TEM); and the peak position fit lambda_spr = lambda0 + L1 exp(L2 d),
  lambda0 = 512 nm, L1 = 6.53 nm, L2 = 0.0216 /nm (d > 25 nm), with water n = 1.333.
- The analytic Drude limit: for a pure Drude metal the correction gives exactly the Drude metal with
  gamma(R) = gamma_bulk + A v_F / R.
"""

import numpy as np
import pytest

from nmmm.errors import InvalidInputError
from nmmm.layers.mie_scattering import mie
from nmmm.materials import FREE_ELECTRON_PARAMETERS, Drude, get, kreibig_damped_eps, size_damped
from nmmm.materials.size_damping import HBAR_EV_S

W = np.arange(400.0, 700.1, 0.5)
WATER = 1.333  # Haiss et al. 2007, water at 20 degC


def _spectrum(d_nm, A):
    au = get("main/Au/Johnson")
    m = size_damped(au, d_nm / 2, A=A) if A is not None else au
    return mie(m.nk(W), WATER, d_nm, W).qext


def _haiss_ratio_diameter(q):
    """Haiss eq. 11 with their experimental B1 = 3.00, B2 = 2.20: diameter (nm) from A_spr/A_450."""
    a_spr = q[W >= 480].max()
    a_450 = q[W == 450.0][0]
    return float(np.exp(3.00 * a_spr / a_450 - 2.20))


def test_drude_limit_is_exact():
    p = FREE_ELECTRON_PARAMETERS["gold"]
    for R, A in [(2.0, 1.0), (5.0, 0.75), (40.0, 1.5)]:
        bulk = Drude(plasma_ev=p.plasma_ev, gamma_ev=p.gamma_bulk_ev)
        g = p.gamma_bulk_ev + A * HBAR_EV_S * p.fermi_velocity_m_s / (R * 1e-9)
        small = Drude(plasma_ev=p.plasma_ev, gamma_ev=g)
        np.testing.assert_allclose(kreibig_damped_eps(bulk.eps(W), W, R, A=A), small.eps(W), rtol=1e-13)


def test_bulk_limit_interband_kept_and_absorption_only_added():
    au = get("main/Au/Johnson")
    eb = au.eps(W)
    np.testing.assert_allclose(kreibig_damped_eps(eb, W, 1e9), eb, rtol=1e-9)  # R -> infinity
    e5 = size_damped(au, 5.0).eps(W)
    assert np.all(e5.imag > eb.imag)  # more damping = more absorption everywhere
    # the change is a Drude difference: it decays like 1/omega^3 in Im, so the interband region
    # (400 nm, 3.1 eV) moves far less than the plasmon region in relative terms
    rel = (e5.imag - eb.imag) / eb.imag
    assert rel[W == 400.0][0] < 0.1 < rel[W == 520.0][0]
    assert size_damped(au, 5.0).range_nm == au.range_nm


def test_haiss_2007_size_series_from_the_ratio_A_spr_over_A_450():
    ds = np.array([5.0, 10.0, 20.0, 40.0, 80.0])
    dev = {}
    for A in (None, 1.0, 1.5):
        d_read = np.array([_haiss_ratio_diameter(_spectrum(d, A)) for d in ds])
        dev[A] = d_read / ds - 1
    # bulk gold: a 5 nm colloid reads as 37 nm (the plasmon is far too strong against the interband
    # absorption at 450 nm); measured deviations: +633 %, +271 %, +94 %, +6 %, +5 %
    assert dev[None][0] > 5.0 and np.mean(np.abs(dev[None])) > 1.5
    # A = 1 (Haiss's own tau_c = R / v_F): +61 %, +41 %, +8 %, -25 %, -14 % (mean 30 %)
    assert np.all(np.abs(dev[1.0]) < 0.65) and np.mean(np.abs(dev[1.0])) < 0.32
    # A = 1.5: +13 %, +3 %, -14 %, -35 %, -22 % (mean 17 %); Haiss's own eq. 11 fits TEM to 11 %
    assert np.all(np.abs(dev[1.5]) < 0.40) and np.mean(np.abs(dev[1.5])) < 0.20


def test_haiss_2007_peak_positions_above_25_nm_are_kept():
    for d in (40.0, 60.0, 80.0, 100.0):
        q = _spectrum(d, 1.0)
        sel = W >= 480
        peak = W[sel][np.argmax(q[sel])]
        haiss = 512.0 + 6.53 * np.exp(0.0216 * d)
        assert abs(peak - haiss) <= 3.5, (d, peak, haiss)


def test_band_broadens_and_weakens_below_25_nm():
    def fwhm_and_peak(d, A):
        q = _spectrum(d, A) / d  # per particle volume-ish: compare shapes
        sel = W >= 470
        qq, ww = q[sel], W[sel]
        i = np.argmax(qq)
        base = q[W == 450.0][0]
        half = base + (qq[i] - base) / 2  # half height above the 450 nm interband level
        above = ww[qq >= half]
        return above.max() - above.min(), qq[i] / base
    w5, r5 = fwhm_and_peak(5.0, 1.0)
    w20, r20 = fwhm_and_peak(20.0, 1.0)
    wb5, rb5 = fwhm_and_peak(5.0, None)
    assert w5 > w20 and r5 < r20  # intrinsic size region: wider and weaker as d falls
    assert w5 > wb5 * 1.2 and r5 < rb5


def test_bad_inputs_say_what_is_right():
    au = get("main/Au/Johnson")
    with pytest.raises(InvalidInputError, match="A must be"):
        size_damped(au, 5.0, A=-1).eps(500.0)
    with pytest.raises(InvalidInputError, match="no free-electron parameters"):
        size_damped(au, 5.0, metal="unobtainium")
    with pytest.raises(InvalidInputError):
        size_damped(au, 0.0)


def test_only_free_electron_metals_and_the_metal_from_the_key():
    # a dielectric (silica: Re eps 2.1) would get a false k from the Drude correction (it got k = 0.245);
    # silver data were damped with gold's free-electron parameters by default
    with pytest.raises(InvalidInputError, match=r"Re eps = 2\.1\d* >= 0 at 400 nm.*free-electron metals"):
        size_damped("main/SiO2/Malitson", 5.0, metal="gold")
    ag = size_damped("main/Ag/Johnson", 5.0)
    assert ag.metadata["metal"] == "silver" and size_damped("main/Au/Johnson", 5.0).metadata["metal"] == "gold"
    # silver's own parameters (Rakic 1998 LD fit): the correction equals kreibig_damped_eps with them
    bulk, w = get("main/Ag/Johnson"), np.array([400.0, 550.0])
    np.testing.assert_allclose(ag.eps(w), kreibig_damped_eps(bulk.eps(w), w, 5.0, metal="silver"), rtol=1e-14)
    assert np.all(np.abs(ag.eps(w) - kreibig_damped_eps(bulk.eps(w), w, 5.0, metal="gold")) > 1e-3)
    with pytest.raises(InvalidInputError, match="metal='gold', but the key names silver"):
        size_damped("main/Ag/Johnson", 5.0, metal="gold")
    with pytest.raises(InvalidInputError, match=r"cannot tell which metal.*give metal="):
        size_damped(Drude(plasma_ev=9.0, gamma_ev=0.05), 5.0)
    p = FREE_ELECTRON_PARAMETERS["gold"]  # explicit parameters for an unnamed Drude metal
    assert size_damped(Drude(plasma_ev=9.0, gamma_ev=0.05), 5.0, metal=p).metadata["metal"] == "custom"


def test_recipe_key_size_damping():
    from nmmm.errors import RecipeError
    from nmmm.recipes.run import build_materials
    from nmmm.recipes.schema import load_recipe

    text = """
name = "gold 10 nm"
[spectral]
start_nm = 400
stop_nm = 700
step_nm = 10
[compounds.gold]
database = "main/Au/Johnson"
size_damping = { radius_nm = 5, A = 1.0 }
[compounds.silica]
database = "main/SiO2/Malitson"
[[levels]]
name = "ruby"
host = "silica"
  [[levels.inclusions]]
  compound = "gold"
  fraction = 0.0005
  radius_nm = 5
[plate]
compound = "ruby"
thickness_nm = [1e5]
"""
    mats = build_materials(load_recipe(text))
    w = np.arange(400.0, 701.0, 10.0)
    np.testing.assert_allclose(mats["gold"].eps(w), size_damped(get("main/Au/Johnson"), 5.0).eps(w), rtol=1e-13)
    with pytest.raises((RecipeError, ValueError), match="radius_nm"):
        load_recipe(text.replace("radius_nm = 5, A", "radius = 5, A"))
    # the damping is of the inclusions' spheres: a different radius is refused when the recipe is read
    with pytest.raises(RecipeError, match=r"levels\[0\]\.inclusions\[0\]\.radius_nm: 20 nm, but compounds\.gold"
                                          r"\.size_damping\.radius_nm is 5 nm"):
        load_recipe(text.replace("  radius_nm = 5", "  radius_nm = 20"))
    # the metal comes from the key (silver's parameters for main/Ag), a contradiction or a dielectric is refused
    ag = build_materials(load_recipe(text.replace("main/Au/Johnson", "main/Ag/Johnson")))["gold"]
    np.testing.assert_allclose(ag.eps(w), size_damped(get("main/Ag/Johnson"), 5.0, metal="silver").eps(w), rtol=1e-13)
    with pytest.raises(RecipeError, match=r"compounds\.gold: .*metal='gold', but the key names silver"):
        build_materials(load_recipe(text.replace("main/Au/Johnson", "main/Ag/Johnson").replace("A = 1.0", "A = 1.0, metal = 'gold'")))
    with pytest.raises(RecipeError, match=r"compounds\.gold: .*Re eps = 2\.1.*free-electron metals"):
        build_materials(load_recipe(text.replace("main/Au/Johnson", "main/SiO2/Malitson")))
