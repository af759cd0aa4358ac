"""Interference (TiO2 on mica) pigment: against tmm's inc_tmm and the analytic quarter-wave
condition; colour sequence against the pearl-pigment literature."""

import numpy as np
import pytest
import tmm

from nmmm.errors import InvalidInputError
from nmmm.layers.interference import (
    interference_colours,
    muscovite,
    platelet_reflectance,
    platelet_stack,
)

N_TIO2, N_MICA, N_BINDER = 2.5, 1.58, 1.5


@pytest.mark.parametrize("pol", ["s", "p"])
def test_platelet_against_tmm_inc(pol):
    """Database TiO2 and the mica model, evaluated per wavelength and passed to tmm."""
    wl = np.array([400.0, 480.0, 560.0, 640.0, 720.0])
    ang = np.array([0.0, 30.0, 60.0])
    d = 130.0
    st = platelet_stack(d, 350.0, binder=N_BINDER, binder_thickness_nm=15000.0)
    res = st.rt(wl, ang)
    tio2 = st.layers[1].material
    mica = st.layers[2].material
    c_list = ["i", "i", "c", "i", "c", "i"]
    d_list = [np.inf, 15000.0, d, 350.0, d, np.inf]
    for i, w in enumerate(wl):
        n_list = [1.0, N_BINDER, complex(tio2.nk(w)), complex(mica.nk(w)), complex(tio2.nk(w)), N_BINDER]
        for j, a in enumerate(ang):
            ref = tmm.inc_tmm(pol, n_list, d_list, c_list, np.radians(a), w)
            assert getattr(res, "R" + pol)[i, j] == pytest.approx(ref["R"], abs=1e-12)
            assert getattr(res, "T" + pol)[i, j] == pytest.approx(ref["T"], abs=1e-12)


def test_quarter_wave_maximum_analytic():
    # a film of higher index than both neighbours reflects most at lambda = 4 n d / (2m + 1)
    # (Macleod 2010 §3.2); two such films separated by incoherent mica add incoherently:
    # R = R1 + T1^2 R2 / (1 - R1 R2) with R1 = R2 (lossless, same film).
    d = 160.0
    wl = np.linspace(450.0, 620.0, 3401)
    R = platelet_reflectance(d, wl, 0.0, tio2=N_TIO2, mica=N_MICA, binder=N_BINDER, binder_thickness_nm=None)
    lam_max = 4 * N_TIO2 * d / 3
    assert wl[np.argmax(R)] == pytest.approx(lam_max, abs=0.1)
    r1 = ((N_BINDER * N_MICA - N_TIO2**2) / (N_BINDER * N_MICA + N_TIO2**2)) ** 2
    expected = r1 + (1 - r1) ** 2 * r1 / (1 - r1 * r1)
    peak = float(platelet_reflectance(d, lam_max, 0.0, tio2=N_TIO2, mica=N_MICA, binder=N_BINDER, binder_thickness_nm=None))
    assert peak == pytest.approx(expected, rel=1e-12)


def test_muscovite_index():
    # n_D = 1.58 (Maile et al. 2005), inside muscovite's n_beta..n_gamma (Deer, Howie & Zussman)
    m = muscovite()
    assert float(m.n(589.3)) == pytest.approx(1.58, abs=1e-3)
    assert np.all(np.diff(m.n(np.linspace(380, 780, 9))) < 0)  # normal dispersion
    assert np.all(m.k(np.linspace(380, 780, 9)) == 0)


def test_colour_sequence_with_thickness():
    """Pearl pigments run silver -> gold -> red/violet -> blue -> green with growing TiO2
    (Maile, Pfaff & Reynders 2005, Fig. 6; Pfaff 2008): check the sign pattern of a*, b*."""
    wl = np.arange(380.0, 781.0, 5.0)
    d = np.array([45.0, 80.0, 110.0, 125.0, 150.0])
    lab, srgb = interference_colours(wl, platelet_reflectance(d, wl, 0.0))
    chroma = np.hypot(lab[:, 1], lab[:, 2])
    assert chroma[0] < 10  # silver: nearly neutral
    assert lab[1, 2] > 20  # gold: yellow (b* > 0)
    assert lab[2, 1] > 20 and lab[2, 2] < -20  # violet/purple
    assert lab[3, 2] < -20  # blue
    assert lab[4, 1] < -15  # green (a* < 0)
    assert srgb.shape == (5, 3) and np.all((srgb >= 0) & (srgb <= 1))


def test_colour_shifts_blue_with_angle():
    # the reflectance maximum moves to shorter wavelengths at oblique incidence (cos theta in the film)
    wl = np.linspace(400.0, 700.0, 3001)
    R = platelet_reflectance(160.0, wl, np.array([0.0, 60.0]), tio2=N_TIO2, mica=N_MICA, binder=N_BINDER)
    lam0, lam60 = wl[np.argmax(R[:, 0])], wl[np.argmax(R[:, 1])]
    # quarter-wave condition with the refraction angle in the film: lambda = 4 n d cos(theta_f) / 3
    cos_f = np.sqrt(1 - (np.sin(np.radians(60.0)) / N_TIO2) ** 2)
    assert lam60 < lam0
    assert lam60 == pytest.approx(4 * N_TIO2 * 160.0 * cos_f / 3, abs=0.2)


def test_bad_input():
    with pytest.raises(InvalidInputError):
        platelet_stack(-10.0)
    with pytest.raises(InvalidInputError):
        platelet_stack(100.0, mica_thickness_nm=0.0)
    with pytest.raises(InvalidInputError):
        platelet_stack(np.nan)
