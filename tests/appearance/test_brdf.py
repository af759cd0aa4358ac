"""Tests of nmmm.appearance.brdf: energy conservation, reciprocity, Fresnel limits,
Saunderson, table export, bad input.

Independent references: ``tmm`` (Byrnes) for Fresnel reflectances; the published
internal diffuse reflectance of an n = 1.5 interface, r_i = 0.596 (Judd 1942, J. Res.
NBS 29, 329; tabulated in Kortüm, *Reflectance Spectroscopy*, 1969); hemispherical
integrals computed here by brute-force quadrature over outgoing directions (the model's
own albedo tables use a different parameterisation, over flake normals).
"""

import functools

import numpy as np
import pytest
import tmm

from nmmm.appearance.brdf import (
    COMPONENTS,
    ClearCoat,
    PaintBRDF,
    brdf_table,
    clear_dielectric,
    interference_paint,
    metallic_paint,
    opaque_paint,
    rusinkiewicz_to_directions,
    write_brdf_table,
)
from nmmm.appearance.flakes import FlakeLayer, MetalFlakeOptics, ThinFilmFlakeOptics, gaussian_tilt
from nmmm.errors import InvalidInputError

W = np.linspace(400.0, 700.0, 7)


def _dir(theta_deg, phi_deg=0.0):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])


@functools.lru_cache(maxsize=4)
def _hemisphere_rule(n_theta, n_phi):
    """Outgoing directions and cos-weighted solid-angle weights: Gauss–Legendre in θo,
    midpoint in φo (cached: the Golub–Welsch eigenproblem cost more than the BRDF)."""
    x, wx = np.polynomial.legendre.leggauss(n_theta)
    th = 0.25 * np.pi * (x + 1)
    wt = 0.25 * np.pi * wx
    ph = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    T, P = np.meshgrid(th, ph, indexing="ij")
    d = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
    wgt = (wt * np.sin(th) * np.cos(th))[:, None] * (2 * np.pi / n_phi)
    d.flags.writeable = wgt.flags.writeable = False
    return d, wgt


def hemispherical_albedo(brdf, wi, n_theta=160, n_phi=160, w=W):
    """∫ f cos θo dωo by Gauss–Legendre in θo and midpoint in φo, plus the Dirac."""
    d, wgt = _hemisphere_rule(n_theta, n_phi)
    f = brdf(w, wi, d)
    return np.einsum("ij,ijl->l", wgt, f) + brdf.specular_reflectance(w, wi)


class _PerfectMirror:
    """Lossless flake optics (R = 1, T = 0), duck-typed like MetalFlakeOptics."""

    def rt(self, cos_local, wavelength_nm, n_binder):
        shape = np.shape(cos_local) + (np.size(wavelength_nm),)
        return np.ones(shape), np.zeros(shape)


LOSSLESS = {
    "white opaque, smooth coat": opaque_paint(1.0),
    "white opaque, rough coat": opaque_paint(1.0, roughness=0.3),
    "mirror flakes over white": PaintBRDF(ClearCoat(1.5), 1.0, FlakeLayer(_PerfectMirror(), gaussian_tilt(12), 1.5)),
    "mirror flakes, dense, rough coat": PaintBRDF(ClearCoat(1.5, 0.15), 1.0,
                                                   FlakeLayer(_PerfectMirror(), gaussian_tilt(20), 4.0)),
    # TiO2/mica/TiO2 with non-absorbing constant indices: R + T = 1 for each flake
    "dielectric interference flakes over white": PaintBRDF(
        ClearCoat(1.5), 1.0, FlakeLayer(ThinFilmFlakeOptics(((2.5, 120.0), (1.58, 350.0), (2.5, 120.0))),
                                        gaussian_tilt(10), 1.0)),
}


@pytest.mark.parametrize("name", list(LOSSLESS))
@pytest.mark.parametrize("theta", [0.0, 30.0, 60.0, 80.0])
def test_white_furnace_lossless_reflects_everything(name, theta):
    a = hemispherical_albedo(LOSSLESS[name], _dir(theta, 20.0))
    assert np.allclose(a, 1.0, atol=3e-3), a


@pytest.mark.parametrize("brdf", [metallic_paint(), interference_paint(), opaque_paint(0.7, roughness=0.2),
                                  metallic_paint(tilt=25, optical_depth=5.0, body_reflectance=0.9)],
                         ids=["metallic", "interference", "opaque-rough", "metallic-dense"])
def test_lossy_paints_never_gain_energy_and_tables_match_quadrature(brdf):
    for theta in (0.0, 45.0, 75.0):
        wi = _dir(theta)
        a = hemispherical_albedo(brdf, wi)
        assert np.all(a <= 1.0 + 1e-3)
        assert np.all(a > 0)
        # the model's albedo tables (quadrature over flake normals) agree with brute force
        assert np.allclose(brdf.albedo(W, wi), a, atol=3e-3)


@pytest.mark.parametrize("brdf", [metallic_paint(), interference_paint(), opaque_paint(0.4, roughness=0.25),
                                  metallic_paint(roughness=0.1, tilt=5)],
                         ids=["metallic", "interference", "opaque-rough", "metallic-rough-aligned"])
def test_reciprocity(brdf):
    rng = np.random.default_rng(3)
    v = rng.normal(size=(2, 500, 3))
    v[..., 2] = np.abs(v[..., 2])
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    f1 = brdf(W, v[0], v[1])
    f2 = brdf(W, v[1], v[0])
    assert np.allclose(f1, f2, rtol=1e-10, atol=1e-14)


def _tmm_unpolarized_R(n_list, d_list, theta_deg, wl):
    return 0.5 * sum(tmm.coh_tmm(p, n_list, d_list, np.radians(theta_deg), wl)["R"] for p in "sp")


@pytest.mark.parametrize("theta", [0.0, 20.0, 45.0, 56.31, 70.0, 85.0])
def test_fresnel_limit_clear_dielectric_matches_tmm(theta):
    b = clear_dielectric(1.5)
    R = b.specular_reflectance(W, _dir(theta))
    ref = _tmm_unpolarized_R([1.0, 1.5], [np.inf, np.inf], theta, 550.0)
    assert np.allclose(R, ref, atol=2e-4)  # 0.5° table, linear interpolation


def test_no_flakes_no_pigment_is_a_clear_dielectric():
    """A metallic paint with zero flakes and a black base is only the coat's Fresnel."""
    b = metallic_paint(optical_depth=0.0, body_reflectance=0.0)
    rng = np.random.default_rng(0)
    v = rng.normal(size=(2, 200, 3))
    v[..., 2] = np.abs(v[..., 2])
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    assert np.all(b(W, v[0], v[1]) == 0.0)
    for theta in (10.0, 60.0):
        ref = _tmm_unpolarized_R([1.0, 1.5], [np.inf, np.inf], theta, 500.0)
        assert np.allclose(hemispherical_albedo(b, _dir(theta)), ref, atol=2e-4)


def test_dispersive_coat_follows_its_index():
    from nmmm.materials.models import Cauchy

    b = PaintBRDF(ClearCoat(Cauchy(A=1.5, B=0.004)), 0.0, None)  # B in µm²
    n = 1.5 + 4000.0 / W ** 2  # Cauchy's n(λ) = A + B/λ², here with λ in nm (B = 4000 nm²)
    R = b.specular_reflectance(W, _dir(0.0))
    assert np.allclose(R, ((n - 1) / (n + 1)) ** 2, atol=1e-6)


def test_saunderson_directional_albedo_of_opaque_paint():
    """R(θ) = F(θ) + (1 − F(θ))(1 − r_i) ρ / (1 − r_i ρ), r_i = 0.596 for n = 1.5 (Judd 1942)."""
    rho = np.linspace(0.1, 0.9, W.size)
    b = opaque_paint((W, rho))
    for theta in (0.0, 45.0):
        F = _tmm_unpolarized_R([1.0, 1.5], [np.inf, np.inf], theta, 550.0)
        ri = 0.596
        ref = F + (1 - F) * (1 - ri) * rho / (1 - ri * rho)
        assert np.allclose(hemispherical_albedo(b, _dir(theta)), ref, atol=2e-3)


@pytest.mark.parametrize("ti,to,phi_o", [(0.0, 0.0, 0.0), (10.0, 30.0, 180.0), (10.0, 30.0, 90.0),
                                          (45.0, 70.0, 90.0), (60.0, 20.0, 0.0), (80.0, 85.0, 180.0)])
def test_solid_paint_diffuse_part_is_lambertian_times_fresnel_transmission(ti, to, phi_o):
    """Williams & Clapper (1953): f = (1 − F(θi))(1 − F(θo)) ρ / (π n² (1 − r_i ρ)), with F
    from tmm and r_i = 0.596 for n = 1.5 (Judd 1942); no azimuthal dependence."""
    rho = 0.5
    f = opaque_paint(rho)(W, _dir(ti), _dir(to, phi_o))
    Fi, Fo = (_tmm_unpolarized_R([1.0, 1.5], [np.inf, np.inf], t, 550.0) for t in (ti, to))
    ref = (1 - Fi) * (1 - Fo) * rho / (np.pi * 1.5 ** 2 * (1 - 0.596 * rho))
    # r_i is published to 3 digits: ±0.0005 moves 1/(1 − r_i ρ) by ±3.6e-4
    assert np.allclose(f, ref, rtol=1e-3)


def test_numba_and_numpy_paths_agree():
    rng = np.random.default_rng(5)
    v = rng.normal(size=(2, 300, 3))
    v[..., 2] = np.abs(v[..., 2])
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    for b in (metallic_paint(roughness=0.05), interference_paint()):
        assert np.allclose(b(W, v[0], v[1]), b(W, v[0], v[1], method="numpy"), rtol=1e-9, atol=1e-14)


def test_components_add_up():
    b = metallic_paint(roughness=0.1)
    wi, wo = _dir(45.0), _dir(20.0, 180.0)
    parts = sum(b(W, wi, wo, components=c) for c in COMPONENTS)
    assert np.allclose(parts, b(W, wi, wo))


def test_metallic_lightness_falls_away_from_specular():
    """Metallic paints are bright near the specular direction and dark far from it."""
    b = metallic_paint()
    wi = _dir(45.0)
    vals = [b(W, wi, _dir(abs(45 - a), 180.0 if 45 - a > 0 else 0.0)).mean() for a in (15, 25, 45, 75, 110)]
    assert np.all(np.diff(vals) < 0)
    assert vals[0] > 3 * vals[-1]


def test_output_shapes_and_broadcasting():
    b = opaque_paint(0.3)
    wi = _dir(30.0)
    wo = np.stack([_dir(t, 180.0) for t in (0, 20, 40)])
    assert b(W, wi, wo).shape == (3, W.size)
    assert b(W, wi[None, None], wo[None]).shape == (1, 3, W.size)
    assert b(550.0, wi, wo[0]).shape == (1,)


def test_grazing_directions_give_zero():
    b = metallic_paint()
    assert np.all(b(W, np.array([1.0, 0.0, 0.0]), _dir(30.0)) == 0)


# -- bad input ---------------------------------------------------------------------------


def test_direction_below_surface_raises():
    b = opaque_paint(0.5)
    with pytest.raises(InvalidInputError, match="below the surface"):
        b(W, _dir(30.0), np.array([0.0, 0.6, -0.8]))


def test_below_surface_zero_option_for_renderers():
    b = opaque_paint(0.5)
    wo = np.stack([_dir(20.0), np.array([0.0, 0.6, -0.8])])
    f = b(W, _dir(30.0), wo, below_surface="zero")
    assert np.all(f[1] == 0) and np.allclose(f[0], b(W, _dir(30.0), _dir(20.0)))


def test_non_unit_direction_raises():
    with pytest.raises(InvalidInputError, match="unit"):
        opaque_paint(0.5)(W, np.array([0.0, 0.0, 2.0]), _dir(10.0))


def test_negative_flake_density_raises():
    with pytest.raises(InvalidInputError, match=">= 0"):
        metallic_paint(optical_depth=-1.0)
    with pytest.raises(InvalidInputError, match="density"):
        FlakeLayer.from_areal_density(MetalFlakeOptics(1 + 5j), gaussian_tilt(10), -5.0, 15e3)


def test_body_reflectance_outside_unit_interval_raises():
    with pytest.raises(InvalidInputError, match=r"\[0, 1\]"):
        opaque_paint(1.2)(W, _dir(0.0), _dir(10.0))


def test_absorbing_coat_raises():
    with pytest.raises(InvalidInputError, match="absorbs"):
        PaintBRDF(ClearCoat(1.5 + 0.1j))(W, _dir(0.0), _dir(10.0))


def test_unphysical_coat_index_raises():
    from nmmm.materials.models import Cauchy

    with pytest.raises(InvalidInputError, match="µm"):  # B given in nm² where µm² is meant
        PaintBRDF(ClearCoat(Cauchy(A=1.5, B=4000.0)))(W, _dir(0.0), _dir(10.0))


def test_unknown_component_raises():
    with pytest.raises(InvalidInputError, match="component"):
        opaque_paint(0.5)(W, _dir(0.0), _dir(10.0), components="sheen")


# -- table export --------------------------------------------------------------------------


def test_rusinkiewicz_coordinates_geometry():
    th, td, pd = 25.0, 40.0, 70.0
    wi, wo = rusinkiewicz_to_directions(th, td, pd)
    h = (wi + wo) / np.linalg.norm(wi + wo)
    assert np.isclose(np.degrees(np.arccos(h[2])), th)
    assert np.isclose(np.degrees(np.arccos(wi @ h)), td)
    assert np.isclose(np.linalg.norm(wi), 1) and np.isclose(np.linalg.norm(wo), 1)


def test_brdf_table_values_and_files(tmp_path):
    b = metallic_paint(roughness=0.05)
    ds = brdf_table(b, W, n_theta_h=12, n_theta_d=10, n_phi_d=8, reduce=None)
    assert ds["brdf"].dims == ("theta_h_deg", "theta_d_deg", "phi_d_deg", "wavelength_nm")
    i, j, k = 5, 3, 2
    th, td, pd = (float(ds[c][x]) for c, x in (("theta_h_deg", i), ("theta_d_deg", j), ("phi_d_deg", k)))
    wi, wo = rusinkiewicz_to_directions(th, td, pd)
    assert np.allclose(ds["brdf"].values[i, j, k], b(W, wi, wo))
    red = brdf_table(b, W, n_theta_h=12, n_theta_d=10, n_phi_d=8)
    assert red["brdf"].dims == ("theta_h_deg", "theta_d_deg", "wavelength_nm")
    p = write_brdf_table(tmp_path / "t.nc", opaque_paint(0.5), W, n_theta_h=6, n_theta_d=6, n_phi_d=4)
    import xarray as xr

    with xr.open_dataset(p, engine="h5netcdf") as back:
        assert back["brdf"].shape == (6, 6, W.size)
        assert "specular_reflectance" in back
    pc = write_brdf_table(tmp_path / "t.csv", opaque_paint(0.5), W, n_theta_h=4, n_theta_d=4, n_phi_d=2)
    assert pc.read_text().splitlines()[0] == "theta_h_deg,theta_d_deg,wavelength_nm,brdf_per_sr"


def test_solid_hematite_paint_from_layers_matches_saunderson_0_d():
    """The BRDF of a layers.PaintFilm base, integrated over the hemisphere at normal
    incidence, equals nmmm.layers' 0°/d Kubelka–Munk + Saunderson reflectance (its k2
    from its own quadrature of the internal Fresnel reflectance)."""
    from nmmm.appearance.brdf import opaque_paint_from_film
    from nmmm.layers.distributions import lognormal
    from nmmm.demo.hematite import hematite
    from nmmm.layers.paint import PaintFilm, paint_reflectance

    w = np.arange(400.0, 701.0, 50.0)
    film = PaintFilm(hematite(), 1.55, lognormal(150.0, 1.25, n_nodes=12), 0.07, 20e3, 0.8, 0.0)
    b = opaque_paint_from_film(film, w)
    ref = paint_reflectance(film, w, solver="km", specular="included").reflectance
    assert np.allclose(hemispherical_albedo(b, _dir(0.0), w=w), ref, atol=1e-3)


@pytest.mark.parametrize("brdf", [metallic_paint(), interference_paint(), metallic_paint(tilt=25, optical_depth=4.0)],
                         ids=["metallic", "interference", "metallic-dense"])
def test_multiple_lobe_azimuth_modes_carry_no_energy(brdf):
    """The azimuthal Fourier modes of the multiple-scattering lobe (ms_azimuth) average to
    zero over the outgoing azimuth (midpoint rule, exact for cos(mφ), m < 64): the φ-mean
    of the "multiple" term equals its 0th mode f_KC (1 + c_0) (c_0 the polar shape from the
    transport, ms_azimuth.lobe_tables); and the multiply scattered light is brighter on the
    specular side (φ = 0) than opposite (φ = 180°)."""
    import copy

    from nmmm.appearance.brdf.ms_azimuth import lobe_factor

    tab = brdf.prepare(W)
    t0 = copy.copy(tab)  # the tables without the modes m >= 1
    t0._ms_modes_spectral = tab._ms_modes_spectral.copy()
    t0._ms_modes_spectral[..., 1:] = 0.0
    for theta_i, theta_o in ((45.0, 30.0), (60.0, 70.0), (20.0, 5.0)):
        wi = _dir(theta_i, 180.0)
        ph = (np.arange(64) + 0.5) * 360.0 / 64
        wo = np.stack([_dir(theta_o, p) for p in ph])
        f = brdf(W, wi, wo, components=("multiple",))
        wi64 = np.tile(wi, (64, 1))
        f0 = t0.evaluate(wi64, wo, frozenset({"multiple"}))  # the 0th mode alone
        if not getattr(tab, "fuses_ms_azimuth", False):
            f0 = f0 * (1.0 + lobe_factor(t0, wi64, wo))
        assert np.allclose(f.mean(axis=0), f0.mean(axis=0), rtol=1e-9, atol=1e-14)
        fw, bw = brdf(W, wi, np.stack([_dir(theta_o, 0.0), _dir(theta_o, 180.0)]), components=("multiple",))
        assert np.all(fw >= bw) and np.all(fw[bw > 0] > bw[bw > 0])


# --- pigmented basecoat (CoatMedium): radiative transfer in the coat (issue 18) --------------

def _medium(mu_a=0.0, mu_s=5e-5, g=0.6, h=2e4):
    from nmmm.appearance.brdf import CoatMedium

    return CoatMedium(W, mu_a, mu_s, g, h)


LOSSLESS_MEDIUM = {
    "mirror flakes in a scattering coat": PaintBRDF(ClearCoat(1.5), 1.0, FlakeLayer(_PerfectMirror(), gaussian_tilt(12), 1.5),
                                                    medium=_medium()),
    "mirror flakes in a band, dense white pigment, rough coat": PaintBRDF(
        ClearCoat(1.5, 0.2), 1.0, FlakeLayer(_PerfectMirror(), gaussian_tilt(20), 3.0, (0.4, 0.9)),
        medium=_medium(mu_s=2e-4, g=0.3)),
    "white pigment alone (no flakes)": PaintBRDF(ClearCoat(1.5), 1.0, None, medium=_medium(mu_s=5e-4, g=0.2)),
}


@pytest.mark.parametrize("name", list(LOSSLESS_MEDIUM))
@pytest.mark.parametrize("theta", [0.0, 30.0, 60.0, 80.0])
def test_white_furnace_lossless_pigmented_coat(name, theta):
    """A lossless effect coat (lossless pigments and flakes, white substrate) reflects all
    the light at every incidence: brute-force hemispherical integral of evaluate."""
    a = hemispherical_albedo(LOSSLESS_MEDIUM[name], _dir(theta, 20.0))
    assert np.allclose(a, 1.0, atol=3e-3), a


def _red_metallic():
    w = np.linspace(380.0, 780.0, 41)
    mu_a = 2e-4 * np.exp(-((w - 470.0) / 60.0) ** 2) + 1e-6  # absorbs blue-green: a red pigment
    from nmmm.appearance.brdf import CoatMedium

    med = CoatMedium(w, mu_a, 3e-5, 0.5, 2e4)
    return metallic_paint(optical_depth=1.5, tilt=10.0, body_reflectance=0.2).with_(medium=med)


def test_pigmented_coat_reciprocity_and_paths_agree():
    brdf = _red_metallic()
    rng = np.random.default_rng(5)
    v = rng.normal(size=(2, 500, 3))
    v[..., 2] = np.abs(v[..., 2])
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    f1, f2 = brdf(W, v[0], v[1]), brdf(W, v[1], v[0])
    assert np.allclose(f1, f2, rtol=1e-10, atol=1e-14)
    assert np.allclose(brdf(W, v[0], v[1], method="numpy"), f1, rtol=1e-9, atol=1e-13)
    for theta in (0.0, 45.0, 75.0):  # energy: never above 1, the tables equal brute force
        a = hemispherical_albedo(brdf, _dir(theta))
        assert np.all(a <= 1.0 + 1e-3) and np.allclose(brdf.albedo(W, _dir(theta)), a, atol=3e-3)


def test_pigments_colour_the_flake_light_and_hide_buried_flakes():
    """The red pigment between the flakes darkens the flake lobe most in the blue-green (its
    absorption band); flakes deeper in the coat under the same pigment reflect less."""
    red = _red_metallic()
    grey = metallic_paint(optical_depth=1.5, tilt=10.0, body_reflectance=0.2)
    wi, wo = _dir(45.0, 180.0), _dir(30.0, 0.0)  # 15° aspecular
    ratio = red(W, wi, wo, components=("flakes",)) / grey(W, wi, wo, components=("flakes",))
    assert np.all(ratio < 1.0) and ratio[1] < ratio[-1]  # 450 nm absorbed more than 700 nm
    fl = red.flakes
    deep = red.with_(flakes=FlakeLayer(fl.optics, fl.tilt, fl.optical_depth, (0.5, 1.0)))
    assert np.all(deep(W, wi, wo, components=("flakes",)) < red(W, wi, wo, components=("flakes",)))


def test_clear_medium_is_the_paint_without_medium():
    """A CoatMedium with no pigment gives the same single-scattering terms (to rounding), the
    same multiple-scattering amount F_ms, and a lobe shape within 0.5 % of the maximum."""
    from nmmm.appearance.brdf import CoatMedium

    m = metallic_paint()
    m2 = m.with_(medium=CoatMedium.clear(2e4))
    rng = np.random.default_rng(6)
    v = rng.normal(size=(2, 300, 3))
    v[..., 2] = np.abs(v[..., 2])
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    comps = ("specular", "flakes", "base")
    assert np.allclose(m(W, v[0], v[1], components=comps), m2(W, v[0], v[1], components=comps), rtol=1e-12, atol=1e-15)
    f1, f2 = m(W, v[0], v[1]), m2(W, v[0], v[1])  # lobe shape at 7 vs 3 wavelength nodes (lobe_tables)
    assert np.abs(f1 - f2).max() < 5e-3 * f1.max()  # measured 2.1e-4 (1.8e-3 before the shared shape tables)
    assert np.allclose(m.prepare(W).Fms, m2.prepare(W).Fms, rtol=1e-3)  # doubling steps differ: 7.7e-4


@pytest.mark.parametrize("kwargs, match", [
    ({"mu_a": -1e-4}, "mu_a_per_nm and mu_s_per_nm must be >= 0"),
    ({"g": 1.0}, "g .* must lie in"),
    ({"h": 0.0}, "thickness_nm must be > 0"),
])
def test_coat_medium_bad_input(kwargs, match):
    with pytest.raises(InvalidInputError, match=match):
        _medium(**kwargs)


def test_flake_depth_range_bad_input():
    with pytest.raises(InvalidInputError, match="depth_range must satisfy 0 <= z0 < z1 <= 1"):
        FlakeLayer(_PerfectMirror(), gaussian_tilt(10), 1.0, (0.6, 0.4))
    with pytest.raises(InvalidInputError, match="medium must be a CoatMedium"):
        PaintBRDF(ClearCoat(1.5), 0.5, None, medium=0.3)


def test_coat_medium_from_layers_film_coefficients():
    """The pigments of a nmmm.layers film (Mie hematite in a resin) as the coat medium."""
    from nmmm.appearance.brdf import CoatMedium
    from nmmm.layers.distributions import lognormal
    from nmmm.layers.paint import PaintFilm, film_coefficients

    film = PaintFilm(pigment=2.9 + 0.05j, binder=1.5, distribution=lognormal(250.0, 1.2, n_nodes=6),
                     volume_fraction=0.01, thickness_nm=2e4)
    co = film_coefficients(film, W)
    med = CoatMedium.from_coefficients(co, 2e4)
    ka, ks, g = med.on_grid(W)
    assert np.allclose(ka, co.mu_a_per_nm * 2e4) and np.allclose(ks, co.mu_s_per_nm * 2e4) and np.allclose(g, co.g)
    bare = metallic_paint(optical_depth=1.0, body_reflectance=0.3)
    paint = bare.with_(medium=med)
    a = paint.albedo(W, _dir(45.0))
    assert np.all((a > 0) & (a < 1)) and not np.allclose(a, bare.albedo(W, _dir(45.0)), atol=1e-3)


# --- finite flakes: rough faces and scattering rims (issue 18) -----------------------------

def test_roughened_narrow_tilt_is_the_ggx_facet_distribution():
    """Nearly parallel flakes (σ = 0.5°) with GGX faces: the facet-normal density per sr is
    GGX's D(h) cos θ_h (clear_coat.ggx_distribution, Walter et al. 2007)."""
    from nmmm.appearance.brdf import ggx_distribution

    alpha = 0.1
    t = gaussian_tilt(0.5).roughened(alpha)
    th = np.radians(np.array([5.0, 10.0, 20.0, 40.0]))
    ref = ggx_distribution(np.cos(th), alpha) * np.cos(th)
    assert np.allclose(t.pdf(np.cos(th)), ref, rtol=0.03)  # measured ≤ 1.3 %
    assert gaussian_tilt(5.0).roughened(0.0) is not None


def _rough_rim_flakes(optics=None, sigma=8.0, tau=1.5, alpha=0.06, fe=0.1):
    from nmmm.appearance.flakes import aluminium_flakes

    return FlakeLayer(optics if optics is not None else aluminium_flakes(), gaussian_tilt(sigma), tau,
                      surface_roughness=alpha, edge_fraction=fe)


@pytest.mark.parametrize("theta", [0.0, 45.0, 80.0])
def test_white_furnace_rough_flakes_with_rims(theta):
    # coat α = 0.15 as above: at α = 0.1, 80°, the 160-node brute-force rule itself misses
    # 0.0075 of the coat's grazing GGX lobe (a white opaque paint alike; 400 nodes: 5e-5)
    p = PaintBRDF(ClearCoat(1.5, 0.15), 1.0, _rough_rim_flakes(_PerfectMirror(), tau=2.5, alpha=0.1, fe=0.2))
    assert np.allclose(hemispherical_albedo(p, _dir(theta, 20.0)), 1.0, atol=3e-3)


def test_rough_flakes_with_rims_reciprocity():
    p = PaintBRDF(ClearCoat(1.5), 0.3, _rough_rim_flakes())
    rng = np.random.default_rng(8)
    v = rng.normal(size=(2, 400, 3))
    v[..., 2] = np.abs(v[..., 2])
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    assert np.allclose(p(W, v[0], v[1]), p(W, v[1], v[0]), rtol=1e-10, atol=1e-14)


def test_rough_flake_faces_keep_lightness_falling_to_110_aspecular():
    """The grey metallic with rough flake faces (GGX α = 0.1) and rims (20 µm flakes): L*
    falls monotonically from 15° to 110° aspecular, and falls more from 75° to 110° than
    with ideal mirror flakes (the long GGX tail), while the flop stays metallic."""
    from dataclasses import replace

    from nmmm.appearance.brdf import grey_metallic_paint
    from nmmm.appearance.flakes import edge_scatter_fraction
    from nmmm.appearance.multiangle import flop_index_alman1987, multiangle_lab

    w = np.linspace(380.0, 780.0, 41)
    asp = (15.0, 25.0, 45.0, 75.0, 110.0)
    base = grey_metallic_paint()
    rough = base.with_(flakes=replace(base.flakes, surface_roughness=0.1, edge_fraction=edge_scatter_fraction(20e3)))
    L0 = multiangle_lab(base, w, asp).lab[:, 0]
    L1 = multiangle_lab(rough, w, asp).lab[:, 0]
    assert np.all(np.diff(L1) < 0), L1
    assert L1[3] - L1[4] > 2.0 * (L0[3] - L0[4]), (L0, L1)  # measured 3.2 vs 0.8
    assert flop_index_alman1987(L1[0], L1[2], L1[4]) > 5.0


def test_edge_scatter_fraction_and_bad_input():
    from nmmm.appearance.flakes import edge_scatter_fraction

    assert edge_scatter_fraction(20e3, 500.0) == pytest.approx(0.1)
    assert edge_scatter_fraction(1e3, 500.0) == 0.5  # capped
    with pytest.raises(InvalidInputError, match="mean_diameter_nm must be > 0"):
        edge_scatter_fraction(0.0)
    with pytest.raises(InvalidInputError, match="edge_fraction .* must lie in"):
        FlakeLayer(_PerfectMirror(), gaussian_tilt(10), 1.0, edge_fraction=1.0)
    with pytest.raises(InvalidInputError, match="surface_roughness .* must lie in"):
        FlakeLayer(_PerfectMirror(), gaussian_tilt(10), 1.0, surface_roughness=-0.1)


@pytest.mark.parametrize("theta", [0.0, 30.0, 60.0, 80.0])
def test_white_furnace_rough_rim_flakes_in_a_scattering_band(theta):
    """Everything the shipped effect recipes switch on at once (review O): rough faces, rims, a flake depth band and a
    scattering (non-absorbing) pigment, lossless flakes over a white substrate: all light comes back."""
    p = PaintBRDF(ClearCoat(1.5, 0.15), 1.0, FlakeLayer(_PerfectMirror(), gaussian_tilt(8), 1.5, (0.2, 0.9),
                                                       surface_roughness=0.05, edge_fraction=0.1),
                  medium=_medium(mu_s=1e-4, g=0.5))
    assert np.allclose(hemispherical_albedo(p, _dir(theta, 20.0)), 1.0, atol=3e-3)


def test_shipped_red_metallic_reciprocity():
    """The red metallic as a user gets it (EffectCoat from the shipped recipe: hematite medium, flake band) with the
    recipe's face_roughness = 0.05 and edge_width_nm = 500 keys on: f(wi, wo) = f(wo, wi) to 1e-10 (review O)."""
    import tomllib

    from nmmm.recipes.run import _effect_coat
    from nmmm.recipes.schema import example_path, parse_recipe, set_key

    raw = tomllib.loads(example_path("red_metallic").read_text())
    raw = set_key(set_key(raw, "effect.flakes.face_roughness", 0.05), "effect.flakes.edge_width_nm", 500.0)
    rec = parse_recipe(raw, base_dir=example_path("red_metallic").parent)
    paint, _ = _effect_coat(rec, w=W).brdf(W)
    assert paint.medium is not None and paint.flakes.surface_roughness > 0 and paint.flakes.edge_fraction > 0
    rng = np.random.default_rng(11)
    v = rng.normal(size=(2, 400, 3))
    v[..., 2] = np.abs(v[..., 2])
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    assert np.allclose(paint(W, v[0], v[1]), paint(W, v[1], v[0]), rtol=1e-10, atol=1e-14)


def test_lobe_shape_is_one_kind_along_the_spectrum():
    """The multiple lobe's polar shape c_0 is one kind for the whole paint, not node by node: the
    shipped Fe2O3/mica pearl once had the transport's shape at 480 and 780 nm and the separable one
    at the other 7 nodes, its lobe factor jumping 0.03 -> 0.21 -> 0.05 over 430-530 nm. Since issue
    18 (the tracer with flakes that reflect and transmit: ms_azimuth.lobe_tables) it is the
    transport's at every node although c̄_0 exceeded 5 % there (0.05-0.27); Al flakes keep the
    transport's shape. That c̄_0 was F_ms's error (the exact single light subtracted from the node
    transport's total): with F_ms from the transport's own split (coat_transport) it is ≤ 3e-4."""
    import tomllib

    from nmmm.recipes.run import _effect_coat
    from nmmm.recipes.schema import example_path, parse_recipe

    w = np.linspace(380.0, 780.0, 41)
    rec = parse_recipe(tomllib.loads(example_path("fe2o3_mica_pearl").read_text()),
                       base_dir=example_path("fe2o3_mica_pearl").parent)
    paint, _ = _effect_coat(rec, w=w).brdf(w)
    tab = paint.prepare(w)
    assert tab._ms_modes_spectral.shape[2] > 3 and np.all(np.abs(tab.ms_shape_mean) < 1e-3)  # measured 2.6e-4
    # c_0 non-zero at every node (before issue 18's rule: zero at all 9; before that at 7 of them)
    assert tab.ms_lobe_shape == "transport"
    assert np.all(np.any(tab._ms_modes_spectral[..., 0] != 0.0, axis=(0, 1)))
    al = metallic_paint().prepare(w)
    assert al.ms_lobe_shape == "transport" and np.all(np.abs(al.ms_shape_mean) <= 0.05)


@pytest.mark.parametrize("metal, nodes", [("main/Al/Rakic", 3), ("main/Cu/Johnson", 9)])
def test_plain_lobe_shape_wavelength_nodes_follow_the_flake_colour(metal, nodes):
    """The plain path keeps its lobe-shape tables at 3 wavelength nodes only where they are linear in λ
    between them (Al); a coloured metal (Cu) keeps 9. Against the tables at all 41 wavelengths, the
    multiple lobe f_KC (1 + c_0 + 2 Σ c_m cos m φ) within 3 % of its maximum (Cu at 3 nodes: 8.6 %)."""
    import copy

    from nmmm.appearance.brdf.ms_azimuth import azimuth_modes, lobe_factor
    from nmmm.materials import get

    w = np.linspace(380.0, 780.0, 41)
    tab = metallic_paint(optics=MetalFlakeOptics(get(metal), metal)).prepare(w)
    assert tab._ms_nodes.size == nodes and tab.ms_lobe_shape == "transport"
    ref = copy.copy(tab)
    azimuth_modes(ref, n_nodes=w.size, n_probe=w.size)
    rng = np.random.default_rng(4)
    v = rng.normal(size=(2, 2000, 3))
    v[..., 2] = np.abs(v[..., 2])
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    f_kc = tab.evaluate(v[0], v[1], frozenset({"multiple"}))  # the separable lobe (plain path: s apart)
    f, f_ref = f_kc * (1.0 + lobe_factor(tab, v[0], v[1])), f_kc * (1.0 + lobe_factor(ref, v[0], v[1]))
    err = np.abs(f - f_ref).max() / f_ref.max()
    assert err < 0.03, err  # measured Al 0.003, Cu 0.016 (at 3 nodes 0.086)


def test_opaque_flakes_keep_the_tau_e_extinction_path():
    """Issue 18 gave flakes that transmit an extinction per direction, τ a(μ) (1 − T̄(μ, λ)) / μ
    (``_Tables.optical_path``). Opaque flakes keep τ_e S, S = a(μi')/μi' + a(μo')/μo', computed as
    before, so that their tables and BRDF stay bit for bit: summing the two directions' optical
    paths instead, (a_i/μ_i) τ_e + (a_o/μ_o) τ_e against (a_i/μ_i + a_o/μ_o) τ_e, had moved the
    metallic paint's float64 BRDF by up to 3.3e-15 and the pigmented coat's by 8e-16. Checked
    here: the single-flake albedo tables and the NumPy path of the pigmented coat never call
    optical_path for opaque flakes, and give the same numbers with it disabled."""
    from nmmm.appearance.brdf.flake_lobe import flake_single_scattering_albedo

    mua = np.cos(np.radians([0.0, 30.0, 60.0, 85.0]))
    for paint in (metallic_paint(), _red_metallic()):
        tab = paint.prepare(W)
        assert tab.tau_e_const
        ref = flake_single_scattering_albedo(tab, mua)

        def refuse(mu):
            raise AssertionError("optical_path used for opaque flakes")

        tab.optical_path = refuse
        try:
            got = flake_single_scattering_albedo(tab, mua)
            assert all(np.array_equal(g, r) for g, r in zip(got, ref))
            if paint.medium is not None:
                paint(W, _dir(45.0, 180.0)[None], _dir(30.0, 0.0)[None], method="numpy")
        finally:
            del tab.optical_path


def _pigmented_pearl(w):
    from nmmm.appearance.brdf import CoatMedium

    med = CoatMedium(w, 2e-4 * np.exp(-((w - 480.0) / 60.0) ** 2) + 1e-6, 3e-5, 0.5, 2e4)
    return interference_paint().with_(medium=med)


@pytest.mark.parametrize("coat", ["pigmented", "plain"])
def test_transmitting_flakes_kernel_equals_numpy_path(coat):
    """Flakes that transmit, in a pigmented coat (the effect kernel) and in a plain one (the fused
    kernel, ``fused_kernel._kernel``): the flake layer's transmission in and out is the table
    exp(−τ a(μ) (1 − T̄(μ, λ)) / μ) on the 0.5° angle nodes, interpolated (``_Tables._ext_exp``, one
    table for both kernels and both NumPy paths: no exp per pair and wavelength; the wavelength
    loop vectorises). Physics: the interpolated table is within 1e-5 relative of the exponential
    of the interpolated optical path over the escape cone (measured 1.9e-6 on the pigmented coat's
    BRDF; plain TiO2/mica: 6e-6 at the critical angle, 1e-7 below 41.5°); the kernel equals the
    NumPy path (1e-9, float32 1e-6) and stays reciprocal (1e-10)."""
    from nmmm.appearance.brdf.effect_tables import _EffectTables
    from nmmm.appearance.brdf.tables import _Tables

    w = np.linspace(380.0, 780.0, 41)
    paint = _pigmented_pearl(w) if coat == "pigmented" else interference_paint()
    tab = paint.prepare(w)
    assert not tab.tau_e_const
    assert type(tab) is (_EffectTables if coat == "pigmented" else _Tables)
    assert _EffectTables._ext_exp is _Tables._ext_exp
    mu = np.cos(np.radians(np.linspace(0.0, 41.8, 400)))
    e_tab = _lerp_table_for_test(tab._ext_exp(), mu, tab.step)
    np.testing.assert_allclose(e_tab, np.exp(-tab.optical_path(mu)), rtol=1e-5)
    rng = np.random.default_rng(11)
    v = rng.normal(size=(2, 2000, 3))
    v[..., 2] = np.abs(v[..., 2])
    v[:, :3] = [(0, 0, 1), (1, 0, 1e-9), (0, 0.999, 0.0447)]
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    f = paint(w, v[0], v[1])
    np.testing.assert_allclose(f, paint(w, v[0], v[1], method="numpy"), rtol=1e-9, atol=1e-14)
    for comps in (("flakes",), ("base",)):
        np.testing.assert_allclose(paint(w, v[0], v[1], components=comps),
                                   paint(w, v[0], v[1], components=comps, method="numpy"), rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(paint(w, v[0], v[1], dtype=np.float32), f, rtol=1e-6, atol=1e-30)
    np.testing.assert_allclose(paint(w, v[1], v[0]), f, rtol=1e-10, atol=1e-14)


def _lerp_table_for_test(table, mu, step):
    from nmmm.appearance.brdf.interpolation import _deg, _lerp_table

    return _lerp_table(table, _deg(mu), step)
