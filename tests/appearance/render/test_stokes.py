"""Issue 19 item 7: the paint's Fresnel reflections as Mueller matrices (from nmmm.layers.fresnel's
r_s, r_p) and the polarized plate render (Stokes images, the view through a linear polarizer),
checked against Fresnel's closed-form equations (Born & Wolf §1.5.3) and Brewster's angle."""

import numpy as np
import pytest

from nmmm.appearance.brdf import grey_metallic_paint, opaque_paint
from nmmm.appearance.brdf.mueller import (
    coat_reflection_mueller,
    coat_transmission_mueller,
    degree_of_polarization,
    flake_reflection_mueller,
    polarizer_intensity,
    reflection_mueller,
    stokes_rotation,
)
from nmmm.appearance.render import PaintedPlate, PinholeCamera, PointLight, UniformEnvironment, render_plate
from nmmm.appearance.render.plate.stokes import render_plate_stokes
from nmmm.errors import InvalidInputError
from nmmm.layers import fresnel

W = np.arange(400.0, 701.0, 20.0)


def _born_wolf(theta_deg, n):
    """Rs, Rp of a dielectric from Fresnel's sine and tangent laws (Born & Wolf eqs. 1.5(35))."""
    ti = np.radians(theta_deg)
    tt = np.arcsin(np.sin(ti) / n)
    rs = np.sin(ti - tt) ** 2 / np.sin(ti + tt) ** 2
    rp = np.tan(ti - tt) ** 2 / np.tan(ti + tt) ** 2
    return rs, rp


def test_coat_mueller_matches_fresnel_sine_and_tangent_laws():
    from nmmm.appearance.brdf import ClearCoat

    th = np.array([5.0, 20.0, 40.0, np.degrees(np.arctan(1.5)), 70.0, 85.0])
    M = coat_reflection_mueller(ClearCoat(1.5), [550.0], np.cos(np.radians(th)))[:, 0]
    rs, rp = _born_wolf(th, 1.5)
    np.testing.assert_allclose(M[:, 0, 0], (rs + rp) / 2, rtol=1e-10)
    np.testing.assert_allclose(M[:, 1, 0] / M[:, 0, 0], (rs - rp) / (rs + rp), rtol=1e-9)
    # Brewster's angle arctan(n): the reflected light is fully s-polarized, DoP = 1
    assert M[3, 1, 0] / M[3, 0, 0] == pytest.approx(1.0, abs=1e-12)
    # a dielectric adds no retardance below Brewster's angle (rp rs* real, < 0 in the Verdet sign)
    assert np.all(np.abs(M[:, 2, 3]) < 1e-12)
    # energy: reflected + transmitted unpolarized power = 1, for s and for p light
    T = coat_transmission_mueller(ClearCoat(1.5), [550.0], np.cos(np.radians(th)))[:, 0]
    for s in (np.array([1, 1, 0, 0]), np.array([1, -1, 0, 0])):
        np.testing.assert_allclose((M @ s)[:, 0] + (T @ s)[:, 0], 1.0, atol=1e-12)


def test_metal_flake_mueller_is_physical_and_retarding():
    """Al flakes in the binder: every pure input state gives an output with DoP <= 1, and the
    metal's phase difference turns +45 deg linear light partly circular (S3 != 0)."""
    paint = grey_metallic_paint()
    cos = np.cos(np.radians([0.0, 30.0, 60.0, 80.0]))
    M = flake_reflection_mueller(paint.flakes.optics, W, cos, 1.5)
    rng = np.random.default_rng(0)
    v = rng.normal(size=(50, 3))
    S = np.c_[np.ones(50), v / np.linalg.norm(v, axis=1, keepdims=True)]
    out = np.einsum("alij,sj->alsi", M, S)
    assert np.all(out[..., 0] > 0)
    assert np.all(degree_of_polarization(out) <= 1 + 1e-9)
    s45 = np.einsum("alij,j->ali", M, [1.0, 0.0, 1.0, 0.0])
    assert np.abs(s45[2:, :, 3] / s45[2:, :, 0]).min() > 0.05
    # unpolarized M00 equals the flake's unpolarized reflectance used by the BRDF
    R, _ = paint.flakes.optics.rt(cos, W, 1.5)
    np.testing.assert_allclose(M[..., 0, 0], R, rtol=1e-9)


def test_stokes_rotation_and_polarizer():
    d = np.array([0.0, 0.0, 1.0])
    S = np.array([1.0, 1.0, 0.0, 0.0])  # polarized along x
    R = stokes_rotation(np.array([np.cos(0.3), np.sin(0.3), 0.0]), np.array([1.0, 0.0, 0.0]), d)
    out = R @ S  # polarized along the axis at 0.3 rad in the new frame
    np.testing.assert_allclose(out, [1.0, np.cos(0.6), np.sin(0.6), 0.0], atol=1e-12)
    # Malus's law
    for a in (0.0, 30.0, 90.0, 137.0):
        assert polarizer_intensity(out, a) == pytest.approx(np.cos(np.radians(a) - 0.3) ** 2, abs=1e-12)


def _brewster_camera(res=(64, 48)):
    thB = np.degrees(np.arctan(1.5))
    e = np.radians(90.0 - thB)
    return PinholeCamera((0.0, -400 * np.cos(e), 400 * np.sin(e)), (0, 0, 0), (0, 0, 1), 20, res)


def test_coat_reflection_dop_is_fresnel_and_one_at_brewster():
    """A black smooth-coated plate (n = 1.5) under a uniform sky: every plate pixel's degree of
    polarization equals (Rs - Rp)/(Rs + Rp) from the sine/tangent laws at its own viewing angle; it
    reaches 1 at Brewster's angle (56.31 deg), where a vertical polarizer removes the coat's
    reflection and a horizontal one passes it all (S0 through 0 deg + 90 deg = S0)."""
    cam = _brewster_camera()
    plate = PaintedPlate(opaque_paint(0.0))
    sky = UniformEnvironment("D65", 1.0)
    st = render_plate_stokes(plate, cam, [], sky, wavelength_nm=W, coarse_step=1)
    np.testing.assert_array_equal(st.stokes[0], render_plate(plate, cam, [], sky, wavelength_nm=W, coarse_step=1).radiance)
    on = st.on_plate
    th = np.degrees(np.arccos(-cam.pixel_directions()[..., 2]))
    rs, rp = _born_wolf(th, 1.5)
    # the polarized part is Fresnel's: sqrt(S1² + S2²) = (Rs - Rp)/2 x sky radiance (within the 1.6e-4 of
    # the BRDF's piecewise-linear table of F(θ) and float32 storage)
    lin = np.hypot(st.stokes[1], st.stokes[2])[on] / sky.spectral(W)[None, :]
    np.testing.assert_allclose(lin, np.broadcast_to(((rs - rp) / 2)[on][:, None], lin.shape), rtol=5e-4)
    # the degree of polarization S1/S0: S0 is render_plate's albedo-table radiance (within 0.25 % of the
    # exact Fresnel reflectance at 59 deg), so DoP matches (Rs - Rp)/(Rs + Rp) within 3e-3
    dop = st.degree_of_polarization()
    np.testing.assert_allclose(dop[on], ((rs - rp) / (rs + rp))[on], atol=3e-3)
    k = np.argmax(np.where(on, dop, 0))
    assert dop.flat[k] > 0.999 and abs(th.flat[k] - np.degrees(np.arctan(1.5))) < 0.5
    # polarized along s: horizontal in this image (the camera is in the source's vertical plane)
    aop = st.angle_of_polarization_deg()
    assert np.abs(aop[on]).max() < 12.0
    i0, i90 = st.through_polarizer(0.0).radiance, st.through_polarizer(90.0).radiance
    np.testing.assert_allclose((i0 + i90)[on], st.stokes[0][on], rtol=1e-5)
    rows = np.nonzero(on.any(axis=1))[0]
    mid = rows[rows.size // 2]
    assert i90[mid, 30:34].mean() < 2e-3 * i0[mid, 30:34].mean()


def test_polarized_render_of_rough_and_metallic_paints():
    """Rough coat and statistical Al flakes under a lamp and a sky: physical Stokes vectors (DoP <= 1),
    S0 unchanged, the rough coat's highlight polarized along s (S1 > 0 in the camera's vertical plane),
    the metal flakes' light slightly elliptical; the diffuse body depolarizing (a pure Lambertian-like
    body with no coat reflection -> no polarization left once the coat's share is removed)."""
    cam = PinholeCamera((0.0, -300.0, 300.0), (0, 0, 0), (0, 0, 1), 35, (60, 40))
    lamp = PointLight((0.0, 200.0, 300.0), "D65", 1.0)
    sky = UniformEnvironment("D65", 0.1)
    for paint in (opaque_paint(0.3, roughness=0.15), grey_metallic_paint()):
        st = render_plate_stokes(PaintedPlate(paint), cam, [lamp], sky, wavelength_nm=W, env_step=6)
        on = st.on_plate
        S = np.moveaxis(st.stokes, 0, -1)[on]
        assert np.all(degree_of_polarization(S) <= 1 + 1e-6)
        if paint.flakes is None:  # the coat's reflection: s-polarized (horizontal here)
            assert np.mean(S[..., 1]) > 0
        else:  # light that crossed the coat twice to the flakes and back: p-polarized (Tp > Ts), and
            # the metal's retardance makes it slightly elliptical
            assert np.mean(S[..., 1]) < 0
            assert np.abs(S[..., 3]).max() > 0
    # a body-only paint (white body, smooth coat) seen at normal incidence: the coat's Dirac of the
    # sky is unpolarized at 0 deg, the body depolarizing -> DoP ~ 0 at the image centre
    cam0 = PinholeCamera((0.0, 0.0, 500.0), (0, 0, 0), (0, 1, 0), 5, (9, 9))
    st0 = render_plate_stokes(PaintedPlate(opaque_paint(0.8)), cam0, [PointLight((0, 200, 400))], sky,
                              wavelength_nm=W)
    assert st0.degree_of_polarization()[4, 4] < 1e-3


def test_stokes_exr_and_bad_input(tmp_path):
    import OpenEXR

    from nmmm.appearance.render.exr import read_spectral_exr

    cam = _brewster_camera((16, 12))
    st = render_plate_stokes(PaintedPlate(opaque_paint(0.2)), cam, [], UniformEnvironment("D65", 1.0), wavelength_nm=W)
    p = st.write_exr(tmp_path / "stokes.exr")
    with OpenEXR.File(str(p), separate_channels=True) as f:
        names = set(f.channels())
        s1 = np.asarray(f.channels()["S1.500,000000nm"].pixels)
    assert {f"S{k}.400,000000nm" for k in range(4)} <= names
    np.testing.assert_allclose(s1, st.stokes[1, :, :, 5], rtol=1e-6)
    w, v, _, _ = read_spectral_exr(p)
    np.testing.assert_allclose(v, st.stokes[0], rtol=1e-6)
    with pytest.raises(InvalidInputError, match="env_step"):
        render_plate_stokes(PaintedPlate(opaque_paint(0.2)), cam, [], UniformEnvironment("D65", 1.0), env_step=0)
    with pytest.raises(InvalidInputError, match="polarizer angle_deg"):
        st.through_polarizer(float("nan"))
    with pytest.raises(InvalidInputError, match=r"\[0, 1\]"):
        coat_reflection_mueller(opaque_paint(0.1).coat, W, [1.5])


def test_glints_carry_the_flake_chain_and_average_to_the_statistical_term():
    """A plate with a discrete flake cell: S0 is render_plate's image; the glints' polarization is the
    flake chain's, so the plate-mean S1/S0 equals the statistical flake BRDF's (measured -0.0242 vs
    -0.0245) and no pixel exceeds DoP 1."""
    from nmmm.appearance.render.plate import seed_metallic_plate

    plate = seed_metallic_plate(cells=(60, 40))
    cam = PinholeCamera((0.0, -150.0, 200.0), (0, 0, 0), (0, 0, 1), 30, (120, 80))
    lamp = PointLight((0.0, 100.0, 200.0), "D65", 1.0)
    st = render_plate_stokes(plate, cam, [lamp], None, wavelength_nm=W)
    assert st.metadata["glints_polarized"] and st.metadata["n_glints"] > 1000
    np.testing.assert_array_equal(st.stokes[0], render_plate(plate, cam, [lamp], wavelength_nm=W).radiance)
    sm = render_plate_stokes(PaintedPlate(plate.smooth_brdf, size_mm=plate.size_mm), cam, [lamp], None,
                             wavelength_nm=W)
    on = st.on_plate
    ratio = [x.stokes[1][on].mean() / x.stokes[0][on].mean() for x in (st, sm)]
    assert ratio[0] < 0 and ratio[0] == pytest.approx(ratio[1], rel=0.05)
    assert np.all(degree_of_polarization(np.moveaxis(st.stokes, 0, -1)[on]) <= 1 + 1e-6)


def _unit(v):
    return v / np.linalg.norm(v)


def _jones_interface(E, k_in, k_out, normal, a_s, a_p):
    """A 3-D field vector E through an interface: s = k_in x normal, p = k x s on each side (the
    convention of rp = -rs at normal incidence), amplitudes a_s, a_p (power factors included)."""
    s = _unit(np.cross(k_in, normal))
    return a_s * np.dot(E, s) * s + a_p * np.dot(E, np.cross(k_in, s)) * np.cross(k_out, s)


def _hecht_r(n1, n2, ci):
    ct = np.sqrt(1 - (n1 * np.sqrt(1 - ci ** 2) / n2) ** 2 + 0j)
    return (n1 * ci - n2 * ct) / (n1 * ci + n2 * ct), (n2 * ci - n1 * ct) / (n2 * ci + n1 * ct)


def _hecht_t(n1, n2, ci, ct):
    f = np.sqrt(n2 * ct / (n1 * ci))
    return 2 * n1 * ci / (n1 * ci + n2 * ct) * f, 2 * n1 * ci / (n2 * ci + n1 * ct) * f


def _refract(k, n1, n2):  # through z = 0 (normal +z), k pointing down
    c = -k[2]
    r = n1 / n2
    return _unit(r * k + (r * c - np.sqrt(1 - r * r * (1 - c * c))) * np.array([0.0, 0.0, 1.0]))


def _jones_stokes(fields_out, x, wo):
    """Stokes (normalised) of the incoherent sum of output fields, in the frame x, y = wo x x;
    S3 = 2 Im(E_y E_x*) (e^{-iwt} fields: S3 > 0 rotating from x to y)."""
    y = np.cross(wo, x)
    S = np.zeros(4)
    for E in fields_out:
        ex, ey = np.dot(E, x), np.dot(E, y)
        S += [abs(ex) ** 2 + abs(ey) ** 2, abs(ex) ** 2 - abs(ey) ** 2, 2 * (ex * np.conj(ey)).real,
              2 * (ey * np.conj(ex)).imag]
    return S / S[0]


def test_flake_chain_and_microfacet_stokes_equal_a_3d_jones_calculation():
    """The rotations between planes of incidence, checked without any Stokes algebra: unpolarized light
    (two orthogonal 3-D field vectors) refracted into the coat, mirrored by an Al flake whose normal is
    the binder half vector, refracted out (Hecht's amplitude formulas, Snell's law in 3-D, explicit s and
    p unit vectors at each interface), projected on the camera frame — equals the Stokes state of
    ``_flake_chain`` for random directions, S3 included; likewise one GGX microfacet of a rough coat
    (normal = the half vector) against the coat term of ``_polarized_terms``."""
    from nmmm.appearance.render.plate.stokes import _flake_chain, _polarized_terms
    from nmmm.materials import as_material

    paint = grey_metallic_paint()  # coat n = 1.5 (no dispersion), Al flakes
    n = 1.5
    w = np.array([450.0, 650.0])
    nk = np.asarray(as_material(paint.flakes.optics.material).nk(w), complex)
    rough = opaque_paint(0.3, roughness=0.2)
    rng = np.random.default_rng(3)
    dirs = rng.normal(size=(40, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    dirs = dirs[dirs[:, 2] > 0.25][:12]
    wi_all, wo_all = dirs[:6], dirs[6:12]
    ref = np.array([0.3, 0.9, 0.1])
    xc_all = np.array([_unit(ref - np.dot(ref, v) * v) for v in wo_all])
    got = _flake_chain(paint, w, wi_all, wo_all, xc_all)
    got_facet = _polarized_terms(rough, w, wi_all, wo_all, xc_all, flakes=False)
    got_facet = got_facet / got_facet[..., :1]
    for q, (wi, wo, xc) in enumerate(zip(wi_all, wo_all, xc_all)):
        k0 = -wi
        e1 = _unit(np.cross(k0, [0.3, 0.5, 0.8]))
        inputs = (e1.astype(complex), np.cross(k0, e1).astype(complex))
        k1 = _refract(k0, 1.0, n)
        k2 = -_refract(-wo, 1.0, n)  # the binder direction that leaves the coat along wo
        m = _unit(-k1 + k2)
        for j in range(w.size):
            t_in = _hecht_t(1.0, n, wi[2], -k1[2])
            r_fl = _hecht_r(n, nk[j], np.dot(-k1, m))
            t_out = _hecht_t(n, 1.0, k2[2], wo[2])
            out = [_jones_interface(_jones_interface(_jones_interface(E, k0, k1, [0, 0, 1.0], *t_in), k1, k2, m, *r_fl),
                                    k2, wo, [0, 0, 1.0], *t_out) for E in inputs]
            np.testing.assert_allclose(got[q, j], _jones_stokes(out, xc, wo), atol=1e-9)
            h = _unit(wi + wo)
            facet = [_jones_interface(E, k0, wo, h, *_hecht_r(1.0, n, np.dot(wi, h))) for E in inputs]
            np.testing.assert_allclose(got_facet[q, j], _jones_stokes(facet, xc, wo), atol=1e-9)
    assert np.abs(got[..., 3]).max() > 1e-3  # the metal's retardance is exercised
