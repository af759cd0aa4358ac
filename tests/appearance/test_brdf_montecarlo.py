"""Monte-Carlo check of the metallic-paint BRDF for ABSORBING paints (issue 8).

:class:`nmmm.appearance.brdf.PaintBRDF` adds flake–flake, flake–base and coat-underside
interreflections as a smooth diffuse term (``"multiple"``) whose amount for absorbing
paints comes from an angle-averaged bounce model; the white-furnace test only checks
it for lossless paints. Here an independent photon tracer of the same physical model
(as documented in nmmm.appearance.brdf / flakes.py) gives the reference:

    air | smooth clear coat, n = 1.5 | flake layer of optical depth τ | Lambertian base ρ

- top interface: unpolarised Fresnel (own formula, Born & Wolf §1.5) both ways, total
  internal reflection beyond the critical angle;
- flake layer: flakes spread uniformly in depth, τ = flake area per unit area; a ray
  along u crossing a depth slice dτ meets a flake of normal m with probability
  p(m)|u·m| dω_m dτ / |u_z| (p the tilt density per sr). Sampled by *delta tracking*:
  candidate events at rate 1/|u_z| per unit τ, a normal drawn from p
  (``TiltDistribution.sample``), accepted as a real collision with probability |u·m|
  (so the mean projected area a(u) of the model is never used). Flakes are two-sided
  opaque mirrors, reflectance R(|u·m|) from the complex Fresnel formula (own code) with
  the aluminium n, k of ``aluminium_flakes()``;
- base: Lambertian, albedo ρ, directly under the flake layer.

Photons carry a spectral weight (one geometry for all wavelengths, weights × R(λ), ×ρ);
at the coat the escaping fraction T is tallied and the rest (1 − T) goes on reflected
(weight splitting); Russian roulette below 1e-3. Estimates, with standard errors from
the per-photon spread: (a) the directional-hemispherical albedo (the Dirac Fresnel
reflection added analytically), (b) the BRDF averaged over coarse outgoing bins,
∫_bin f cos θ dω / ∫_bin cos θ dω (subsurface light only; the Dirac is not in
``evaluate``). Run this file directly (``python tests/appearance/test_brdf_montecarlo.py``)
for the full comparison table.

Measured (2·10^5 photons per incidence, ρ = 0.3, σ = 12°, Al Rakić, n = 1.5, smooth
coat; λ = 550 nm, MC standard error ≈ 0.0008; 450 and 650 nm alike):

    directional-hemispherical albedo   τ = 1                           τ = 2
    θi     MC      model (old)      model (now)    MC      model (old)      model (now)
     0°   0.394   0.414 (+0.020)   0.397 (+0.004)  0.448   0.556 (+0.108)   0.451 (+0.003)
    30°   0.372   0.390 (+0.019)   0.373 (+0.001)  0.423   0.536 (+0.113)   0.425 (+0.002)
    45°   0.353   0.372 (+0.020)   0.354 (+0.001)  0.402   0.520 (+0.119)   0.404 (+0.002)
    60°   0.356   0.375 (+0.019)   0.357 (+0.001)  0.402   0.521 (+0.119)   0.403 (+0.001)
    75°   0.459   0.475 (+0.016)   0.460 (+0.001)  0.493   0.597 (+0.103)   0.496 (+0.003)

    split at θi = 45°, 550 nm     Fresnel  one flake  base only  multiple
    MC, τ = 1                     0.050    0.207      0.0174     0.078
    model old / now, τ = 1        0.050    0.207      0.0174     0.098 / 0.080
    MC, τ = 2                     0.050    0.237      0.0024     0.112
    model old / now, τ = 2        0.050    0.237      0.0025     0.231 / 0.114

The single-scattering terms (one flake; base with its coat interreflections) always
agreed. The ``"multiple"`` term was too large (×1.25 at τ = 1, ×2.05 at τ = 2): the old
bounce operator of ``_Tables._ms_factor`` (now ``multiple_scattering_factor``) kept only single flake
scattering per pass and lost 20–40 % of the lossless light per bounce, which weighted ms/ms⁰ towards short,
little-absorbed paths. It is now adding–doubling of the azimuth-averaged flake layer
(exactly conservative when lossless); the albedo agrees to ≤ 0.004 (asserted:
4 SE + 0.01). The *shape* of the multiply scattered light was off until the lobe got its
azimuthal Fourier modes (``nmmm.appearance.brdf.ms_azimuth``: modes 1–6 of the multiply
scattered part from adding–doubling per mode): the tracer's is brighter on the specular
side. Bin averages at θi = 45° (θo 60–80°, |φo| 0–60° / 60–120° / 120–180°, 1/sr):
τ = 1 MC 0.163 / 0.050 / 0.024, model without modes 0.148 / 0.055 / 0.035 (−9 %, +9 %,
+46 %), with modes 0.163 / 0.050 / 0.025; τ = 2 MC 0.198 / 0.057 / 0.023, without
0.172 / 0.065 / 0.043 (−13 %, +14 %, +86 %), with 0.198 / 0.058 / 0.024. The comparison
of every bin (``test_binned_brdf_matches_mc``, then 4 SE + 10 %) was ``xfail(strict=True)``
and now passes.

Issue 18: ``trace_coat`` extends the tracer to a pigmented basecoat (pigment absorption
κa(λ) as a weight along every flight, grey Henyey–Greenstein scattering κs, g; flakes in a
depth band) and to finite flakes (GGX-rough faces: a facet drawn around each flake normal by
an exact 3-D rotation; rims scattering diffusely with probability f_e). Against
``PaintBRDF(..., medium=CoatMedium(...))`` (6·10^4 photons, 0/45/70°, 450/550/650 nm): albedo
within 0.006 for the pigment cases and 0.005 for the finite-flake cases, every bin at 45°
within 9 % (mostly ≤ 5 %), asserted 4 SE + 0.01 and 4 SE + 10 % as above.

Review O: the bins are now asserted within 4 SE + 0.1 % (``MODEL_TOL_BINS``: the model's bin
quadrature, n_quad = 24 against 96, measured ≤ 1.4e-4) — a statistical bound at 6·10^4 photons
(bin SE 1–5 %), where every bin of every case passes. At 6·10^5 photons (bin SE ≤ 1.6 %) the
model error showed: largest |model − MC| / MC over the 36 bins (and bins beyond 4 SE) — flakes
τ = 1: 2.3 % (0), τ = 2: 1.5 % (0), red-ish absorber 4.7 % (0), pigment above a flake band 5.2 %
(2), dense forward scatterer 6.9 % (4), rough faces 4.0 % (0), rims 5.3 % (4), rough + rims +
pigment 3.7 % (1); the pigment cases' albedo was off by up to 0.0063 (z up to 8).

Review P located it, three causes, each by its own experiment:

1. The polar quadrature of the transport (``ms_azimuth.gauss_nodes``): one Gauss rule over
   0–90° put the coat's critical angle between nodes, the internal diffuse reflectance came out
   0.5914 at 48 nodes (0.5981 at 160; exact 0.59635), so light trapped under the coat, hence
   F_ms of absorbing paints, was 1–2 % too high (dense scatterer at 45°: multiple 0.1726 vs MC
   0.1701 ± 0.0004 at 550 nm). Split at the critical angle it converges from 24 nodes.
2. The lobe's polar shape: f_ms⁰ = (1 − E⁰(θi))(1 − E⁰(θo)) F_ms / (π (1 − Ē⁰)) is separable;
   the transport's own multiply scattered radiance (``ms_azimuth.lobe_tables``: c_0, with the
   modes) fits the tracer where the separable lobe is 2–5 % off (bins of the dense scatterer
   then within 2.6 SE instead of 5.3).
3. Rims: this tracer sent rim light uniformly over the sphere, capture ∝ the projected area
   a(ui): not reciprocal, f ∝ a(μi)/(μi μo) in a thin layer, 0.0224 (0° → 65–75°) against
   0.0077 (70° → 0–10°), as that analytic form says (0.0233 and 0.0080) — Helmholtz reciprocity
   holds for every passive medium, so the tracer (and the model, which had the same kernel)
   was wrong. Rims now emit ∝ a(uo) (``_rim_emission``; ``test_tracer_rims_are_reciprocal``
   checks reciprocity and the analytic single scattering), and the model's transport alike.

At 6·10^5 photons (1.2·10^6 for the dense scatterer and the rims) every bin of every case is
now within 2.6 SE (largest |model − MC| / MC: τ = 1 1.8 %, τ = 2 1.5 %, red-ish absorber 1.3 %,
pigment above a band 2.0 %, dense scatterer 1.2 %, rough faces 1.4 %, rims 1.2 %, rough + rims
+ pigment 2.1 %) and the albedo at 0/45/70° within 0.002 (|z| ≤ 2.3) at 2·10^5 photons; the slow
``test_model_error_resolved_at_6e5_photons`` asserts the bins of the six pigment and finite-flake
cases at 6·10^5 photons with the same 4 SE + 0.1 %. ``MODEL_TOL_ALBEDO`` (0.01) is kept for the
quick test.

Issue 18, flakes that reflect AND transmit (interference flakes): :class:`StackFlake` gives the tracer a
flake's R(θ, λ) and T(θ, λ) from its own thin-film :class:`nmmm.layers.Stack` (unpolarised, the binder on
both sides, the reversed stack for light from below; nothing of the BRDF model); at a hit the photon is
reflected with the grey probability R̄/(R̄ + T̄) or goes straight on (:func:`_flake_hit`, spectral weights
R/p, T/(1 − p)). Checked by a white furnace (lossless flake: 1.00000 ± 0.00001) and the exact two-stream
solution for flat flakes, asymmetric lossy stack (``test_tracer_transmitting_flakes_white_furnace_and_two_flux``).

Against it, the shipped Fe2O3/mica pearl's coat (deposit tilt, τ = 0.72, n = 1.5, primer 0.15) with its own
flakes and with TiO2/mica (120 nm anatase, 400 nm mica), θi = 45°, the bins above, n_quad = 96 (the narrow
deposit tilt leaves 24 1 % low in the specular bin). Per case and wavelength (450 / 550 / 650 nm): largest
|model − MC| / MC over the 12 bins, largest |z|, bins beyond 4 SE + 0.1 %, albedo model − MC:

    model as it was (extinction with the flakes' mean transmission T̄; pearl 4·10^6 photons, bin SE ≤ 0.64 %)
      pearl, separable lobe (what it used)  2.3/3.3/4.0 %  |z| 4.7/5.3/11.7  1/3/4 bins   −0.0001/+0.0001/−0.0005
      pearl, transport lobe                 1.5/1.7/2.2 %  |z| 4.2/4.1/6.4   0/0/3 bins   −0.0001/−0.0000/−0.0008
    TiO2/mica (2·10^6 photons, SE ≤ 0.85 %): albedo +0.023 / +0.044 at 550 / 650 nm (z 300), its multiple term
      ×25–40 (F_ms 0.153 where the tracer's multiple light is 0.0009 of the incident)
    now (extinction per direction, τ a(μ) (1 − T̄(μ, λ)) / μ, T̄(μ) the flakes' T averaged over the normals a ray
    along μ meets: ``_Tables.optical_path``)
      pearl, separable lobe                 2.6/2.5/2.6 %  |z| 5.4/5.8/7.1   2/3/5 bins   −0.0001/−0.0002/−0.0000
      pearl, transport lobe (now used)      2.0/1.5/0.9 %  |z| 4.1/4.4/2.8   0/1/0 bins   −0.0001/−0.0003/−0.0003
      TiO2/mica, separable lobe             2.2/0.7/2.5 %  |z| 3.2/1.5/5.6   0/0/3 bins   +0.0002/+0.0001/−0.0000
      TiO2/mica, transport lobe (now used)  1.9/0.8/1.0 %  |z| 2.2/1.6/2.7   0/0/0 bins   −0.0001/+0.0001/−0.0002

Component by component (hemispherical, θi = 45°) the mean transmission was the error: TiO2/mica at 550 / 650
nm one flake 0.0098 / 0.0330 against the tracer's 0.0101 / 0.0360, substrate 0.0568 / 0.0466 against 0.0608 /
0.0551 (T(θ) at 550 nm is 0.95–1.0 up to 60° and falls to 0 at grazing incidence: T̄ = 0.93 over-attenuates the
escaping directions) — and the transport's kernel, renormalised to the mean extinction, reflected too much in
the escape cone (550 nm: ×1.5 at normal incidence, ×2.3 at 20°, ×0.15 at 80°), hence F_ms. With the extinction
per direction: one flake 0.0101 / 0.0359, substrate 0.0608 / 0.0551, multiple 0.0009 / 0.0038 against 0.0009
/ 0.0040. The lobe's shape (the multiple term's bins, model / tracer, min–max over the bins): pearl transport
0.79–0.85 / 0.87–0.91 / 0.96–0.98, separable 0.69–1.11 / 0.78–1.19 / 0.90–1.19; TiO2/mica transport 0.95–1.01 /
0.90–1.14 / 0.92–0.96, separable 0.88–1.16 / 0.97–1.08 / 0.76–1.33: the transport's shape, which
ms_azimuth.lobe_tables now keeps for these paints (their c̄_0 > 5 % had switched them to the separable lobe).
Left then: the pearl's multiple amount 10–20 % low at 450–550 nm (a small term; not transmission, the same for
an opaque flake with the pearl's R(θ)). F_ms subtracted the exact terms-2–3 albedo from the node transport's total,
whose own one-flake light was 0.45 % low (narrow tilt, 48 × 32 nodes); F_ms now takes the transport's own split
(96 × 96 nodes): 1.007 / 1.008 / 1.005 of the tracer's (``test_transmitting_flakes_multiple_amount``).
"""

import numpy as np
import pytest

from nmmm.appearance.brdf import metallic_paint
from nmmm.appearance.flakes import aluminium_flakes, gaussian_tilt

N_COAT = 1.5
RHO = 0.3
SIGMA_DEG = 12.0
WAVELENGTHS = np.array([450.0, 550.0, 650.0])


# --------------------------------------------------------------------------------------
# independent Fresnel formulae (Born & Wolf §1.5.2), unpolarised


def fresnel_dielectric(cos_i, n1, n2):
    """(R_s + R_p)/2 for real indices; 1 beyond the critical angle."""
    cos_i = np.clip(np.abs(cos_i), 0.0, 1.0)
    sin_t2 = (n1 / n2) ** 2 * (1.0 - cos_i ** 2)
    tir = sin_t2 >= 1.0
    cos_t = np.sqrt(np.clip(1.0 - sin_t2, 0.0, 1.0))
    with np.errstate(invalid="ignore", divide="ignore"):  # 0/0 at grazing TIR, replaced by 1
        rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)
        rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t)
    return np.where(tir | (cos_i == 0), 1.0, 0.5 * (rs * rs + rp * rp))


def fresnel_metal(cos_i, n1, n2):
    """(|r_s|² + |r_p|²)/2 from a real index n1 onto complex n2 = n + ik; broadcasts
    ``cos_i`` (...) against ``n2`` (L,) -> (..., L)."""
    c = np.clip(np.abs(cos_i), 0.0, 1.0)[..., None]
    n2 = np.asarray(n2, complex)
    cos_t = np.sqrt(1.0 - (n1 / n2) ** 2 * (1.0 - c ** 2) + 0j)
    rs = (n1 * c - n2 * cos_t) / (n1 * c + n2 * cos_t)
    rp = (n2 * c - n1 * cos_t) / (n2 * c + n1 * cos_t)
    return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)


class StackFlake:
    """A flake that reflects AND transmits: a thin-film stack (``layers`` top to bottom, the
    (material, thickness_nm[, coherent]) tuples of :class:`nmmm.layers.Stack`) embedded in the
    binder of index ``n`` on both sides. R and T are (R_s + R_p)/2 and (T_s + T_p)/2 from
    ``Stack.rt`` (transfer matrices, validated against tmm / pyElli in tests/layers) on a 0.05° grid
    of the local angle in the binder, 90° added as R = 1, T = 0; the model's BRDF code is not used.
    Light meeting the flake from below (u·m > 0) sees the reversed stack (``symmetric`` says
    whether the two faces differ). Transmitted light keeps its direction (a plane-parallel flake
    with the binder on both sides). ``flake(c)`` for signed cosines c = u·m (k,) -> (R, T) (k, L)."""

    def __init__(self, layers, wavelength_nm, n, step_deg=0.05):
        from nmmm.layers import Stack

        self.wavelength_nm = np.asarray(wavelength_nm, float)
        self.L = self.wavelength_nm.size
        self.step = step_deg
        ang = np.arange(0.0, 90.0 - 0.5 * step_deg, step_deg)
        tabs = []
        for lay in (list(layers), list(layers)[::-1]):
            r = Stack(lay, ambient=n, substrate=n).rt(self.wavelength_nm, ang)
            R = 0.5 * (np.asarray(r.Rs) + np.asarray(r.Rp)).T  # (A, L)
            T = 0.5 * (np.asarray(r.Ts) + np.asarray(r.Tp)).T
            tabs.append((np.vstack([R, np.ones((1, self.L))]), np.vstack([T, np.zeros((1, self.L))])))
        self.top, self.bottom = tabs
        self.symmetric = bool(np.allclose(tabs[0][0], tabs[1][0], atol=1e-12)
                              and np.allclose(tabs[0][1], tabs[1][1], atol=1e-12))
        self.angle_deg = np.append(ang, 90.0)

    def __call__(self, c):
        c = np.asarray(c, float)
        th = np.degrees(np.arccos(np.clip(np.abs(c), 0.0, 1.0)))
        x = np.interp(th, self.angle_deg, np.arange(self.angle_deg.size))
        i = np.minimum(x.astype(int), self.angle_deg.size - 2)
        f = (x - i)[:, None]
        low = (c > 0)[:, None]

        def at(tab):
            return tab[i] * (1.0 - f) + tab[i + 1] * f

        R = np.where(low, at(self.bottom[0]), at(self.top[0]))
        T = np.where(low, at(self.bottom[1]), at(self.top[1]))
        return R, T


def _flake_hit(c, nk_metal, n, rng):
    """A real flake hit at signed local cosines c (k,): (reflect (k,) bool, weight factor (k, L)).
    Metal (``nk_metal`` complex n + ik): always reflected, × Fresnel R(λ). Transmitting flake
    (``nk_metal`` a :class:`StackFlake`): reflected with the grey probability p = R̄/(R̄ + T̄)
    (means over λ), weight × R(λ)/p, else transmitted, × T(λ)/(1 − p) — unbiased for every λ;
    absorption 1 − R − T stays in the weights."""
    if not isinstance(nk_metal, StackFlake):
        return np.ones(c.size, bool), fresnel_metal(c, n, nk_metal)
    R, T = nk_metal(c)
    rb, tb = R.mean(axis=1), T.mean(axis=1)
    p = np.where(rb + tb > 0, rb / np.where(rb + tb > 0, rb + tb, 1.0), 0.5)
    refl = rng.random(c.size) < p
    fac = np.where(refl[:, None], R / np.where(p > 0, p, 1.0)[:, None], T / np.where(p < 1, 1.0 - p, 1.0)[:, None])
    return refl, fac


# --------------------------------------------------------------------------------------
# the photon tracer


def trace_paint(theta_i_deg, tau, nk_metal, tilt, rho=RHO, n=N_COAT, n_photons=200_000, theta_edges_deg=(),
                phi_edges_deg=(), seed=1, max_events=100_000):
    """Trace photons incident at ``theta_i_deg`` (azimuth 180°, so the mirror direction is
    at φ = 0°) into the paint.

    Returns a dict: ``albedo`` (L,) and ``albedo_se`` (directional-hemispherical
    reflectance, Dirac included), ``specular`` (L,), and, when bin edges are given,
    ``bins`` / ``bins_se`` (nθ, nφ, L): the bin-averaged BRDF (1/sr) of the subsurface
    light, φ folded onto [0°, 180°] (the paint is isotropic).
    """
    rng = np.random.default_rng(seed)
    L = nk_metal.L if isinstance(nk_metal, StackFlake) else np.size(nk_metal)
    N = int(n_photons)
    te = np.radians(np.asarray(theta_edges_deg, float))
    pe = np.asarray(phi_edges_deg, float)
    nb_t, nb_p = max(te.size - 1, 0), max(pe.size - 1, 0)
    # incident: external direction of travel, refracted into the coat
    ti = np.radians(theta_i_deg)
    mu_i = np.cos(ti)
    F_in = float(fresnel_dielectric(mu_i, 1.0, n))
    s_int = np.sin(ti) / n
    d = np.tile([s_int, 0.0, -np.sqrt(1.0 - s_int * s_int)], (N, 1))  # travelling down, towards +x
    w = np.full((N, L), 1.0 - F_in)
    depth = np.zeros(N)  # optical depth below the top of the flake layer, 0..tau
    idx = np.arange(N)
    esc_total = np.zeros((N, L))
    n_flake = np.zeros(N, int)  # real flake hits, base hits, coat reflections per photon
    n_base = np.zeros(N, int)
    n_coat = np.zeros(N, int)
    esc_single = np.zeros(L)  # the model's "flakes" term: one flake, straight out
    esc_base = np.zeros(L)  # the model's "base" term: no flake hit at all
    esc_bins = np.zeros((N, nb_t, nb_p, L)) if nb_t and nb_p else None
    for _ in range(max_events):
        if idx.size == 0:
            break
        uz = d[:, 2]
        # candidate event (majorant rate 1/|u_z| per unit optical depth)
        ds = -np.log1p(-rng.random(idx.size)) * np.abs(uz)
        new = depth + np.where(uz < 0, ds, -ds)
        at_base = new >= tau
        at_top = new <= 0.0
        inside = ~(at_base | at_top)
        # --- flake candidates: draw a normal, accept with probability |u·m|
        if np.any(inside):
            k = np.flatnonzero(inside)
            m = tilt.sample(k.size, rng)
            c = np.sum(d[k] * m, axis=1)
            real = rng.random(k.size) < np.abs(c)
            kr = k[real]
            if kr.size:
                cr = c[real]
                mr = m[real]
                refl, fac = _flake_hit(cr, nk_metal, n, rng)
                w[kr] *= fac
                kr, cr, mr = kr[refl], cr[refl], mr[refl]  # the transmitted keep their direction
                d[kr] = d[kr] - 2.0 * cr[:, None] * mr
                n_flake[idx[kr]] += 1
            depth[inside] = new[inside]
        # --- base: Lambertian reflection (cosine-weighted upward direction), weight × ρ
        if np.any(at_base):
            k = np.flatnonzero(at_base)
            u1, u2 = rng.random(k.size), rng.random(k.size)
            r = np.sqrt(u1)
            phi = 2 * np.pi * u2
            d[k] = np.column_stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1.0 - u1)])
            w[k] *= rho
            depth[k] = tau
            n_base[idx[k]] += 1
        # --- the coat's top (the clear binder between adds nothing): split escape/reflect
        if np.any(at_top):
            k = np.flatnonzero(at_top)
            dk = d[k]
            sxy2 = n * n * (dk[:, 0] ** 2 + dk[:, 1] ** 2)
            ok = sxy2 < 1.0
            mu_o = np.sqrt(np.clip(1.0 - sxy2, 0.0, 1.0))
            T = np.where(ok, 1.0 - fresnel_dielectric(mu_o, 1.0, n), 0.0)
            out_w = w[k] * T[:, None]
            esc_total[idx[k]] += out_w
            gk = idx[k]
            esc_single += out_w[(n_flake[gk] == 1) & (n_base[gk] == 0) & (n_coat[gk] == 0)].sum(axis=0)
            esc_base += out_w[n_flake[gk] == 0].sum(axis=0)
            n_coat[gk] += 1
            if esc_bins is not None and np.any(ok):
                th_o = np.arccos(mu_o)
                ph_o = np.degrees(np.abs(np.arctan2(dk[:, 1], dk[:, 0])))  # folded onto [0, 180]
                it = np.searchsorted(te, th_o, side="right") - 1
                ip = np.searchsorted(pe, ph_o, side="right") - 1
                good = ok & (it >= 0) & (it < nb_t) & (ip >= 0) & (ip < nb_p)
                np.add.at(esc_bins, (idx[k][good], it[good], ip[good]), out_w[good])
            w[k] *= (1.0 - T)[:, None]
            d[k, 2] = -dk[:, 2]
            depth[k] = 0.0
        # --- Russian roulette on the largest spectral weight
        wmax = w.max(axis=1)
        low = wmax < 1e-3
        if np.any(low):
            kl = np.flatnonzero(low)
            survive = rng.random(kl.size) < 0.1
            w[kl[survive]] *= 10.0
            w[kl[~survive]] = 0.0
        alive = w.max(axis=1) > 0
        if not np.all(alive):
            idx, d, w, depth = idx[alive], d[alive], w[alive], depth[alive]
    else:  # pragma: no cover
        raise RuntimeError("photons still alive after max_events")
    F_spec = np.full(L, F_in)
    out = {
        "albedo": F_spec + esc_total.mean(axis=0),
        "albedo_se": esc_total.std(axis=0) / np.sqrt(N),
        "specular": F_spec,
        "single_flake": esc_single / N,
        "base": esc_base / N,
        "multiple": esc_total.mean(axis=0) - (esc_single + esc_base) / N,
    }
    if esc_bins is not None:
        proj = 0.5 * (np.sin(te[1:]) ** 2 - np.sin(te[:-1]) ** 2)[:, None] * (2 * np.radians(np.diff(pe)))[None, :]
        out["bins"] = esc_bins.mean(axis=0) / proj[..., None]
        out["bins_se"] = esc_bins.std(axis=0) / np.sqrt(N) / proj[..., None]
    return out


# --------------------------------------------------------------------------------------
# the tracer extended to a pigmented coat (issue 18): pigments scatter (Henyey–Greenstein)
# and absorb between and above the flakes


def _hg_scatter(d, g, rng):
    """New directions after Henyey–Greenstein scattering of unit directions d (N, 3)."""
    N = d.shape[0]
    xi = rng.random(N)
    if abs(g) < 1e-6:
        ct = 1.0 - 2.0 * xi
    else:
        ct = (1.0 + g * g - ((1.0 - g * g) / (1.0 - g + 2.0 * g * xi)) ** 2) / (2.0 * g)
    ct = np.clip(ct, -1.0, 1.0)
    st = np.sqrt(1.0 - ct * ct)
    ph = 2 * np.pi * rng.random(N)
    # an orthonormal frame around d
    a = np.where(np.abs(d[:, 2:3]) < 0.9, np.array([[0.0, 0.0, 1.0]]), np.array([[1.0, 0.0, 0.0]]))
    t1 = np.cross(a, d)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(d, t1)
    return ct[:, None] * d + (st * np.cos(ph))[:, None] * t1 + (st * np.sin(ph))[:, None] * t2


def _frame_rotate(local, n):
    """Vectors given in a frame whose z axis is n (N, 3) -> the surface frame."""
    a = np.where(np.abs(n[:, 2:3]) < 0.9, np.array([[0.0, 0.0, 1.0]]), np.array([[1.0, 0.0, 0.0]]))
    t1 = np.cross(a, n)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(n, t1)
    return local[:, :1] * t1 + local[:, 1:2] * t2 + local[:, 2:3] * n


def _rough_facets(m, alpha, rng):
    """Facet normals of rough flake faces: GGX (D(h) cos θ_h, Walter et al. 2007 sampling
    tan θ = α sqrt(ξ/(1−ξ))) around each flake normal m (N, 3), by an exact 3-D rotation."""
    xi = rng.random(m.shape[0])
    th = np.arctan(alpha * np.sqrt(xi / (1.0 - xi)))
    ph = 2 * np.pi * rng.random(m.shape[0])
    loc = np.column_stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)])
    h = _frame_rotate(loc, m)
    return h * np.where(h[:, 2:3] < 0, -1.0, 1.0)


def _rim_emission(N, tilt, alpha, rng):
    """Directions of light scattered by flake rims: density ∝ a(u) = E_m |u·m| over the whole
    sphere (the flakes' projected area along u, the same average over the (rough) normals that
    sets how often a ray meets a flake), by rejection: a uniform direction kept with
    probability |u·m'| for a fresh normal m'. With capture ∝ a(ui) the kernel a(ui) a(uo) is
    reciprocal; uniform emission (this tracer until review P) gave a thin layer
    f ∝ a(μi)/(μi μo), f(0° → 70°) / f(70° → 0°) = 2.9 (``test_tracer_rims_are_reciprocal``)."""
    out = np.empty((N, 3))
    todo = np.arange(N)
    while todo.size:
        ct = 1.0 - 2.0 * rng.random(todo.size)
        st = np.sqrt(1.0 - ct * ct)
        ph = 2 * np.pi * rng.random(todo.size)
        u = np.column_stack([st * np.cos(ph), st * np.sin(ph), ct])
        m = tilt.sample(todo.size, rng)
        if alpha > 0:
            m = _rough_facets(m, alpha, rng)
        keep = rng.random(todo.size) < np.abs(np.sum(u * m, axis=1))
        out[todo[keep]] = u[keep]
        todo = todo[~keep]
    return out


def trace_coat(theta_i_deg, tau, nk_metal, tilt, kappa_a, kappa_s, g, band=(0.0, 1.0), rho=RHO, n=N_COAT,
               n_photons=100_000, theta_edges_deg=(), phi_edges_deg=(), seed=1, max_events=200_000,
               surface_roughness=0.0, edge_fraction=0.0, split_bins=False):
    """Photons in a pigmented basecoat: depth z ∈ [0, 1] (fraction of the coat), pigment of
    vertical optical thickness κa(λ) (absorption, applied as the weight exp(−κa Δz/|u_z|)
    along every flight) and κs (scattering, grey, Henyey–Greenstein g), flakes of optical
    depth τ uniform in ``band``; Lambertian substrate ρ at z = 1; coat top as in
    :func:`trace_paint`. Delta tracking with majorant (τ/Δz + κs)/|u_z| per unit z. Returns
    the dict of :func:`trace_paint` (``single_flake``: one flake and nothing else, ``base``:
    no flake and no pigment scattering). Finite flakes: ``surface_roughness`` (GGX α of the
    faces: the mirror is a facet drawn around the flake normal) and ``edge_fraction`` (a hit
    flake scatters diffusely from its rim with this probability, weight × the metal's
    Fresnel reflectance at the hit angle, new direction from :func:`_rim_emission`; counted
    as pigment-like scattering). Flakes that transmit: ``nk_metal`` a :class:`StackFlake`
    (:func:`_flake_hit`: reflected or transmitted straight on, spectral weights; ``single_flake``
    then counts one reflection and any number of transmissions; ``transmissions``: the mean number
    of flake transmissions per photon); no rims for these. ``split_bins``: the bins also per term,
    ``bins_single_flake``, ``bins_base``, ``bins_multiple`` (and ``bins_se_…``)."""
    if isinstance(nk_metal, StackFlake) and edge_fraction > 0:
        raise ValueError("rims of transmitting flakes are not traced")
    rng = np.random.default_rng(seed)
    L = nk_metal.L if isinstance(nk_metal, StackFlake) else np.size(nk_metal)
    ka = np.broadcast_to(np.asarray(kappa_a, float), (L,))
    z0, z1 = band
    rate_f = tau / (z1 - z0)
    maj = rate_f + kappa_s
    N = int(n_photons)
    te = np.radians(np.asarray(theta_edges_deg, float))
    pe = np.asarray(phi_edges_deg, float)
    nb_t, nb_p = max(te.size - 1, 0), max(pe.size - 1, 0)
    ti = np.radians(theta_i_deg)
    F_in = float(fresnel_dielectric(np.cos(ti), 1.0, n))
    s_int = np.sin(ti) / n
    d = np.tile([s_int, 0.0, -np.sqrt(1.0 - s_int * s_int)], (N, 1))
    w = np.full((N, L), 1.0 - F_in)
    z = np.zeros(N)
    idx = np.arange(N)
    esc_total = np.zeros((N, L))
    n_flake = np.zeros(N, int)  # flake reflections (a transmission through a flake is no scattering)
    n_trans = np.zeros(N, int)
    n_pig = np.zeros(N, int)
    n_base = np.zeros(N, int)
    n_coat = np.zeros(N, int)
    esc_single = np.zeros(L)
    esc_base = np.zeros(L)
    esc_ms = np.zeros((N, L))  # per photon, the light of the model's "multiple" term (for its standard error)
    esc_bins = np.zeros((N, nb_t, nb_p, L)) if nb_t and nb_p else None
    # the bins split as the model's terms: one flake and nothing else, no flake and no pigment, the rest
    part_bins = np.zeros((2, N, nb_t, nb_p, L)) if esc_bins is not None and split_bins else None
    for _ in range(max_events):
        if idx.size == 0:
            break
        uz = d[:, 2]
        dzs = -np.log1p(-rng.random(idx.size)) * np.abs(uz) / maj if maj > 0 else np.full(idx.size, np.inf)
        new = z + np.where(uz < 0, dzs, -dzs)
        at_base = new >= 1.0
        at_top = new <= 0.0
        inside = ~(at_base | at_top)
        # absorption along the flight (to the event or to the boundary)
        flight = np.where(at_base, 1.0 - z, np.where(at_top, z, dzs)) / np.abs(uz)
        w *= np.exp(-np.outer(flight, ka))
        if np.any(inside):
            k = np.flatnonzero(inside)
            zk = new[k]
            pig = rng.random(k.size) < kappa_s / maj
            kp = k[pig]
            if kp.size:
                d[kp] = _hg_scatter(d[kp], g, rng)
                n_pig[idx[kp]] += 1
            kf = k[~pig & (zk >= z0) & (zk <= z1)]
            if kf.size:
                m = tilt.sample(kf.size, rng)
                if surface_roughness > 0:
                    m = _rough_facets(m, surface_roughness, rng)
                c = np.sum(d[kf] * m, axis=1)
                real = rng.random(kf.size) < np.abs(c)
                kr = kf[real]
                if kr.size:
                    cr, mr = c[real], m[real]
                    refl, fac = _flake_hit(cr, nk_metal, n, rng)
                    w[kr] *= fac
                    n_trans[idx[kr[~refl]]] += 1
                    kr, cr, mr = kr[refl], cr[refl], mr[refl]  # the transmitted keep their direction
                    rim = rng.random(kr.size) < edge_fraction
                    ke, km = kr[rim], kr[~rim]
                    d[km] = d[km] - 2.0 * cr[~rim, None] * mr[~rim]
                    n_flake[idx[km]] += 1
                    if ke.size:
                        d[ke] = _rim_emission(ke.size, tilt, surface_roughness, rng)
                        n_pig[idx[ke]] += 1
            z[inside] = new[inside]
        if np.any(at_base):
            k = np.flatnonzero(at_base)
            u1, u2 = rng.random(k.size), rng.random(k.size)
            r = np.sqrt(u1)
            phi = 2 * np.pi * u2
            d[k] = np.column_stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1.0 - u1)])
            w[k] *= rho
            z[k] = 1.0
            n_base[idx[k]] += 1
        if np.any(at_top):
            k = np.flatnonzero(at_top)
            dk = d[k]
            sxy2 = n * n * (dk[:, 0] ** 2 + dk[:, 1] ** 2)
            ok = sxy2 < 1.0
            mu_o = np.sqrt(np.clip(1.0 - sxy2, 0.0, 1.0))
            T = np.where(ok, 1.0 - fresnel_dielectric(mu_o, 1.0, n), 0.0)
            out_w = w[k] * T[:, None]
            esc_total[idx[k]] += out_w
            gk = idx[k]
            clean = (n_pig[gk] == 0) & (n_coat[gk] == 0)
            one = clean & (n_flake[gk] == 1) & (n_base[gk] == 0)
            none = (n_flake[gk] == 0) & (n_pig[gk] == 0)
            esc_single += out_w[one].sum(axis=0)
            esc_base += out_w[none].sum(axis=0)
            esc_ms[gk[~(one | none)]] += out_w[~(one | none)]
            n_coat[gk] += 1
            if esc_bins is not None and np.any(ok):
                th_o = np.arccos(mu_o)
                ph_o = np.degrees(np.abs(np.arctan2(dk[:, 1], dk[:, 0])))
                it = np.searchsorted(te, th_o, side="right") - 1
                ip = np.searchsorted(pe, ph_o, side="right") - 1
                good = ok & (it >= 0) & (it < nb_t) & (ip >= 0) & (ip < nb_p)
                np.add.at(esc_bins, (idx[k][good], it[good], ip[good]), out_w[good])
                if part_bins is not None:
                    for j, sel in enumerate((good & one, good & none)):
                        np.add.at(part_bins[j], (idx[k][sel], it[sel], ip[sel]), out_w[sel])
            w[k] *= (1.0 - T)[:, None]
            d[k, 2] = -dk[:, 2]
            z[k] = 0.0
        wmax = w.max(axis=1)
        low = wmax < 1e-3
        if np.any(low):
            kl = np.flatnonzero(low)
            survive = rng.random(kl.size) < 0.1
            w[kl[survive]] *= 10.0
            w[kl[~survive]] = 0.0
        alive = w.max(axis=1) > 0
        if not np.all(alive):
            idx, d, w, z = idx[alive], d[alive], w[alive], z[alive]
    else:  # pragma: no cover
        raise RuntimeError("photons still alive after max_events")
    out = {
        "albedo": F_in + esc_total.mean(axis=0),
        "albedo_se": esc_total.std(axis=0) / np.sqrt(N),
        "specular": np.full(L, F_in),
        "single_flake": esc_single / N,
        "base": esc_base / N,
        "multiple": esc_total.mean(axis=0) - (esc_single + esc_base) / N,
        "multiple_se": esc_ms.std(axis=0) / np.sqrt(N),
        "transmissions": n_trans.mean(),
    }
    if esc_bins is not None:
        proj = 0.5 * (np.sin(te[1:]) ** 2 - np.sin(te[:-1]) ** 2)[:, None] * (2 * np.radians(np.diff(pe)))[None, :]
        out["bins"] = esc_bins.mean(axis=0) / proj[..., None]
        out["bins_se"] = esc_bins.std(axis=0) / np.sqrt(N) / proj[..., None]
        if part_bins is not None:
            rest = esc_bins - part_bins.sum(axis=0)
            for key, x in (("single_flake", part_bins[0]), ("base", part_bins[1]), ("multiple", rest)):
                out["bins_" + key] = x.mean(axis=0) / proj[..., None]
                out["bins_se_" + key] = x.std(axis=0) / np.sqrt(N) / proj[..., None]
    return out


def _wi(theta_deg):
    t = np.radians(theta_deg)
    return np.array([-np.sin(t), 0.0, np.cos(t)])  # light from φ = 180°: mirror at φ = 0°


# --------------------------------------------------------------------------------------
# fixtures and tests

THETA_EDGES = (0.0, 20.0, 40.0, 60.0, 80.0)
PHI_EDGES = (0.0, 60.0, 120.0, 180.0)
N_PHOTONS = 60_000
MODEL_TOL_ALBEDO = 0.01  # absolute: ~3 % of these albedos (model tables and quadrature)
# relative, on the bin-averaged BRDF: the model's own quadrature error only (bin_average n_quad = 24 against 96:
# <= 1.4e-4 for every case of this file, review O); the rest of the allowance is statistical, N_SE standard errors
MODEL_TOL_BINS = 1e-3
N_SE = 4.0


@pytest.fixture(scope="module")
def setup():
    optics = aluminium_flakes()
    return optics.material.nk(WAVELENGTHS), gaussian_tilt(SIGMA_DEG)


@pytest.fixture(scope="module")
def traces(setup):
    nk, tilt = setup
    out = {}
    for tau in (1.0, 2.0):
        for th in (0.0, 45.0, 70.0):
            edges = (THETA_EDGES, PHI_EDGES) if th == 45.0 else ((), ())
            out[tau, th] = trace_paint(th, tau, nk, tilt, n_photons=N_PHOTONS, theta_edges_deg=edges[0],
                                       phi_edges_deg=edges[1], seed=int(10 * tau + th))
    return out


def _paint(tau):
    return metallic_paint(optical_depth=tau, tilt=SIGMA_DEG, body_reflectance=RHO, coat=N_COAT)


def _hemisphere_component(paint, theta_i, components):
    """∫ f cos θ dω over the hemisphere for some BRDF components (bin averages × bin
    projected solid angles; fine bins so the flake lobe is resolved)."""
    te = np.linspace(0.0, 90.0, 19)
    pe = np.linspace(0.0, 360.0, 25)
    b = paint.bin_average(WAVELENGTHS, _wi(theta_i), te, pe, components=components, n_quad=8)
    t = np.radians(te)
    proj = 0.5 * (np.sin(t[1:]) ** 2 - np.sin(t[:-1]) ** 2)[:, None] * np.radians(np.diff(pe))[None, :]
    return np.einsum("ab,abl->l", proj, b)


def test_tracer_white_furnace_and_saunderson(setup):
    """The tracer itself: lossless flakes (|n2| → ∞) over a white base reflect all light;
    without flakes it gives Saunderson's directional reflectance
    R = F(θ) + (1 − F(θ)) (1 − r_i) ρ / (1 − ρ r_i), r_i = 2∫ R_int μ dμ computed here
    (0.596 for n = 1.5, Judd 1942)."""
    _, tilt = setup
    r = trace_paint(45.0, 2.0, np.array([1e8j]), tilt, rho=1.0, n_photons=20_000, seed=3)
    assert r["albedo"][0] == pytest.approx(1.0, abs=1e-3)
    mu = np.linspace(0.0, 1.0, 200_001)
    r_i = 2 * np.trapezoid(fresnel_dielectric(mu, N_COAT, 1.0) * mu, mu)
    assert r_i == pytest.approx(0.596, abs=2e-3)
    for th in (0.0, 60.0):
        F = fresnel_dielectric(np.cos(np.radians(th)), 1.0, N_COAT)
        ref = F + (1 - F) * (1 - r_i) * RHO / (1 - RHO * r_i)
        r = trace_paint(th, 0.0, np.array([1e8j]), tilt, n_photons=50_000, seed=4)
        assert abs(r["albedo"][0] - ref) < N_SE * r["albedo_se"][0] + 1e-3


def test_tracer_rims_are_reciprocal(setup):
    """The rims of the tracer, alone in a thin layer (τ = 0.1, lossless, no coat, black base):
    f(0° → 65–75°) = f(70° → 0–10°) as Helmholtz reciprocity demands of any passive medium,
    and both equal the analytic single scattering f = (a_i/μi)(a_o/(A μo))(1 − e^−τX)/X,
    X = a_i/μi + a_o/μo, A = ∫_4π a dω (a the flakes' projected area; multiple scattering
    ≤ 3 % at τ = 0.1). Isotropic emission (until review P) gave 0.0224 against 0.0077 (×2.9)."""
    _, tilt = setup
    tau = 0.1
    te = (0.0, 10.0, 65.0, 75.0)
    out = {}
    for th in (0.0, 70.0):
        out[th] = trace_coat(th, tau, np.array([1e8j]), tilt, np.zeros(1), 0.0, 0.0, rho=0.0, n=1.0 + 1e-9,
                             n_photons=200_000, theta_edges_deg=te, phi_edges_deg=(0.0, 180.0), seed=5,
                             edge_fraction=1.0)
    fwd, fwd_se = out[0.0]["bins"][2, 0, 0], out[0.0]["bins_se"][2, 0, 0]
    bwd, bwd_se = out[70.0]["bins"][0, 0, 0], out[70.0]["bins_se"][0, 0, 0]
    assert abs(fwd - bwd) < N_SE * np.hypot(fwd_se, bwd_se) + 0.03 * fwd, (fwd, bwd)
    mu = np.linspace(0.0, 1.0, 20_001)
    A = 4 * np.pi * np.trapezoid(tilt.projected_mean(mu), mu)

    def f_bin(th_i, lo, hi):
        mi = np.cos(np.radians(th_i))
        ai = float(tilt.projected_mean(np.array([mi]))[0])
        t = np.radians(np.linspace(lo, hi, 2001))
        mo = np.cos(t)
        ao = tilt.projected_mean(mo)
        X = ai / mi + ao / mo
        f = (ai / mi) * ao / (A * mo) * -np.expm1(-tau * X) / X
        w = np.sin(t) * mo
        return np.trapezoid(f * w, t) / np.trapezoid(w, t)

    for got, se, ref in ((fwd, fwd_se, f_bin(0.0, 65.0, 75.0)), (bwd, bwd_se, f_bin(70.0, 0.0, 10.0))):
        assert abs(got - ref) < N_SE * se + 0.03 * ref, (got, ref)


@pytest.mark.parametrize("tau", [1.0, 2.0])
def test_single_scattering_terms_match_mc(traces, tau):
    """The model's "flakes" and "base" terms (hemispherically integrated) equal the
    tracer's photons that met one flake and left, and those that never met a flake."""
    paint = _paint(tau)
    for th in (0.0, 45.0, 70.0):
        r = traces[tau, th]
        tol = N_SE * r["albedo_se"] + 0.003
        flakes = _hemisphere_component(paint, th, ("flakes",))
        base = _hemisphere_component(paint, th, ("base",))
        assert np.all(np.abs(flakes - r["single_flake"]) < tol), (tau, th, flakes, r["single_flake"])
        assert np.all(np.abs(base - r["base"]) < tol), (tau, th, base, r["base"])
        assert np.allclose(paint.specular_reflectance(WAVELENGTHS, _wi(th)), r["specular"], atol=1e-3)


@pytest.mark.parametrize("tau", [1.0, 2.0])
def test_total_albedo_matches_mc(traces, tau):
    paint = _paint(tau)
    for th in (0.0, 45.0, 70.0):
        r = traces[tau, th]
        a = paint.albedo(WAVELENGTHS, _wi(th))
        tol = N_SE * r["albedo_se"] + MODEL_TOL_ALBEDO
        assert np.all(np.abs(a - r["albedo"]) < tol), (tau, th, a, r["albedo"])


@pytest.mark.parametrize("tau", [1.0, 2.0])
def test_binned_brdf_matches_mc(traces, tau):
    r = traces[tau, 45.0]
    b = _paint(tau).bin_average(WAVELENGTHS, _wi(45.0), THETA_EDGES, PHI_EDGES, n_quad=24)
    tol = N_SE * r["bins_se"] + MODEL_TOL_BINS * r["bins"]
    assert np.all(np.abs(b - r["bins"]) < tol), (tau, b[..., 1], r["bins"][..., 1])


if __name__ == "__main__":  # the comparison table
    optics = aluminium_flakes()
    nk_al, tilt_g = optics.material.nk(WAVELENGTHS), gaussian_tilt(SIGMA_DEG)
    for tau_ in (1.0, 2.0):
        paint_ = _paint(tau_)
        for th_ in (0.0, 30.0, 45.0, 60.0, 75.0):
            r_ = trace_paint(th_, tau_, nk_al, tilt_g, n_photons=200_000)
            a_ = paint_.albedo(WAVELENGTHS, _wi(th_))
            print(f"tau={tau_:g} theta_i={th_:4.0f}  MC {np.round(r_['albedo'], 4)} ± {np.round(r_['albedo_se'], 4)}"
                  f"  model {np.round(a_, 4)}  model-MC {np.round(a_ - r_['albedo'], 4)}"
                  f"  (MC one flake {np.round(r_['single_flake'], 4)}, base {np.round(r_['base'], 4)},"
                  f" multiple {np.round(r_['multiple'], 4)})")


@pytest.mark.parametrize("tau", [1.0, 2.0])
def test_binned_brdf_near_normal_matches_mc(traces, tau):
    """Outgoing bins within 20° of the normal (θi = 45°), where the azimuth-free shape of
    the multiple lobe matters least: within 4 SE + quadrature (MODEL_TOL_BINS)."""
    r = traces[tau, 45.0]
    b = _paint(tau).bin_average(WAVELENGTHS, _wi(45.0), THETA_EDGES[:2], PHI_EDGES, n_quad=24)
    tol = N_SE * r["bins_se"][:1] + MODEL_TOL_BINS * r["bins"][:1]
    assert np.all(np.abs(b - r["bins"][:1]) < tol), (tau, b[..., 1], r["bins"][:1, :, 1])


# --------------------------------------------------------------------------------------
# pigments between and above the flakes (issue 18): the tracer with a pigmented basecoat

H_COAT_NM = 2e4
PIGMENT_CASES = {
    # name: (κa(λ) at 450/550/650 nm, κs, g, flake band, τ) — κ = μ H, vertical optical thicknesses
    "red-ish absorber, uniform": ((0.6, 0.1, 0.02), 0.8, 0.5, (0.0, 1.0), 1.0),
    "pigment above a flake band": ((0.6, 0.1, 0.02), 0.8, 0.5, (0.3, 0.8), 1.0),
    "dense forward scatterer": ((2.0, 0.3, 0.05), 4.0, 0.7, (0.0, 1.0), 1.5),
}


def _pigmented_paint(case):
    from nmmm.appearance.brdf import ClearCoat, CoatMedium, PaintBRDF
    from nmmm.appearance.flakes import FlakeLayer

    ka, ks, g, band, tau = PIGMENT_CASES[case]
    med = CoatMedium(WAVELENGTHS, np.asarray(ka) / H_COAT_NM, ks / H_COAT_NM, g, H_COAT_NM)
    return PaintBRDF(ClearCoat(N_COAT), RHO, FlakeLayer(aluminium_flakes(), gaussian_tilt(SIGMA_DEG), tau, band),
                     medium=med)


@pytest.fixture(scope="module")
def pigment_traces(setup):
    nk, tilt = setup
    out = {}
    for i, (case, (ka, ks, g, band, tau)) in enumerate(PIGMENT_CASES.items()):
        for th in (0.0, 45.0, 70.0):
            edges = (THETA_EDGES, PHI_EDGES) if th == 45.0 else ((), ())
            out[case, th] = trace_coat(th, tau, nk, tilt, np.asarray(ka), ks, g, band, n_photons=N_PHOTONS,
                                       theta_edges_deg=edges[0], phi_edges_deg=edges[1], seed=100 + 7 * i + int(th))
    return out


def test_coat_tracer_without_pigment_is_the_flake_tracer(setup):
    """trace_coat with κ = 0 and the flakes through the whole coat is trace_paint's physics:
    the same albedo and single-scattering split within their statistical errors."""
    nk, tilt = setup
    a = trace_paint(45.0, 1.0, nk, tilt, n_photons=40_000, seed=11)
    b = trace_coat(45.0, 1.0, nk, tilt, np.zeros(3), 0.0, 0.0, n_photons=40_000, seed=12)
    for key in ("albedo", "single_flake", "base"):
        assert np.all(np.abs(a[key] - b[key]) < N_SE * np.hypot(a["albedo_se"], b["albedo_se"]) + 1e-3), key


@pytest.mark.parametrize("case", list(PIGMENT_CASES))
def test_pigmented_coat_albedo_and_single_terms_match_mc(pigment_traces, case):
    """Radiative transfer in the pigmented coat (CoatMedium): the model's one-flake and
    substrate terms (attenuated by the pigments) and its total albedo (F_ms from
    adding–doubling with the pigments' scattering) against the tracer. Measured: albedo
    within 0.006 at 0/45/70°, 450–650 nm."""
    paint = _pigmented_paint(case)
    for th in (0.0, 45.0, 70.0):
        r = pigment_traces[case, th]
        a = paint.albedo(WAVELENGTHS, _wi(th))
        assert np.all(np.abs(a - r["albedo"]) < N_SE * r["albedo_se"] + MODEL_TOL_ALBEDO), (case, th, a, r["albedo"])
        tol = N_SE * r["albedo_se"] + 0.003
        flakes = _hemisphere_component(paint, th, ("flakes",))
        base = _hemisphere_component(paint, th, ("base",))
        assert np.all(np.abs(flakes - r["single_flake"]) < tol), (case, th, flakes, r["single_flake"])
        assert np.all(np.abs(base - r["base"]) < tol), (case, th, base, r["base"])


@pytest.mark.parametrize("case", list(PIGMENT_CASES))
def test_pigmented_coat_binned_brdf_matches_mc(pigment_traces, case):
    """Every reported bin at θi = 45° (θo 0–80°, |φo| 0–180°, three wavelengths) within
    4 SE + quadrature (MODEL_TOL_BINS), as for the flakes alone (module docstring: the model error at 6e5 photons)."""
    r = pigment_traces[case, 45.0]
    b = _pigmented_paint(case).bin_average(WAVELENGTHS, _wi(45.0), THETA_EDGES, PHI_EDGES, n_quad=24)
    tol = N_SE * r["bins_se"] + MODEL_TOL_BINS * r["bins"]
    assert np.all(np.abs(b - r["bins"]) < tol), (case, b[..., 1], r["bins"][..., 1])


# finite flakes: rough faces (GGX facets drawn around each flake normal, exact 3-D rotation in
# the tracer; small-angle composition in the model) and rims scattering diffusely (∝ the flakes'
# projected area both ways: reciprocal)
FINITE_CASES = {
    # name: (σ tilt, GGX α of the faces, edge fraction, τ, pigment (κa at 450/550/650, κs, g) or None)
    "rough faces": (6.0, 0.1, 0.0, 1.0, None),
    "rims (edge fraction 0.15)": (12.0, 0.0, 0.15, 1.5, None),
    "rough + rims in a pigmented coat": (6.0, 0.08, 0.1, 1.0, ((0.6, 0.1, 0.02), 0.8, 0.5)),
}


@pytest.mark.parametrize("case", list(FINITE_CASES))
def test_finite_flakes_match_mc(setup, case):
    """Albedo at 0/45/70° within 4 SE + 0.01 (measured ≤ 0.005) and every bin at 45° within
    4 SE + quadrature (MODEL_TOL_BINS) for flakes with rough faces and scattering rims."""
    from nmmm.appearance.brdf import ClearCoat, CoatMedium, PaintBRDF
    from nmmm.appearance.flakes import FlakeLayer

    nk, _ = setup
    sig, alpha, fe, tau, pig = FINITE_CASES[case]
    ka, ks, g = pig if pig is not None else ((0.0, 0.0, 0.0), 0.0, 0.0)
    ka = np.asarray(ka, float)
    tilt = gaussian_tilt(sig)
    med = CoatMedium(WAVELENGTHS, ka / H_COAT_NM, ks / H_COAT_NM, g, H_COAT_NM) if pig is not None else None
    paint = PaintBRDF(ClearCoat(N_COAT), RHO, FlakeLayer(aluminium_flakes(), tilt, tau, surface_roughness=alpha,
                                                         edge_fraction=fe), medium=med)
    for th in (0.0, 45.0, 70.0):
        edges = (THETA_EDGES, PHI_EDGES) if th == 45.0 else ((), ())
        r = trace_coat(th, tau, nk, tilt, ka, ks, g, n_photons=N_PHOTONS, theta_edges_deg=edges[0],
                       phi_edges_deg=edges[1], seed=300 + int(th), surface_roughness=alpha, edge_fraction=fe)
        a = paint.albedo(WAVELENGTHS, _wi(th))
        assert np.all(np.abs(a - r["albedo"]) < N_SE * r["albedo_se"] + MODEL_TOL_ALBEDO), (case, th, a, r["albedo"])
        if th == 45.0:
            b = paint.bin_average(WAVELENGTHS, _wi(45.0), THETA_EDGES, PHI_EDGES, n_quad=24)
            tol = N_SE * r["bins_se"] + MODEL_TOL_BINS * r["bins"]
            assert np.all(np.abs(b - r["bins"]) < tol), (case, b[..., 1], r["bins"][..., 1])


@pytest.mark.slow
@pytest.mark.parametrize("case", list(PIGMENT_CASES) + list(FINITE_CASES))
def test_model_error_resolved_at_6e5_photons(setup, case):
    """The binned comparison at 10x the photons (bin SE <= 1.6 %), 4 SE + quadrature as the quick tests: the
    model error it showed (up to 6.9 %, 4 bins beyond 4 SE; module docstring, review O) is gone (review P:
    quadrature split at the critical angle, the lobe's polar shape from the transport, reciprocal rims)."""
    from nmmm.appearance.brdf import ClearCoat, CoatMedium, PaintBRDF
    from nmmm.appearance.flakes import FlakeLayer

    nk, tilt = setup
    n = 600_000
    if case in PIGMENT_CASES:
        ka, ks, g, band, tau = PIGMENT_CASES[case]
        r = trace_coat(45.0, tau, nk, tilt, np.asarray(ka), ks, g, band, n_photons=n, theta_edges_deg=THETA_EDGES,
                       phi_edges_deg=PHI_EDGES, seed=164)
        paint = _pigmented_paint(case)
    else:
        sig, alpha, fe, tau, pig = FINITE_CASES[case]
        ka, ks, g = pig if pig is not None else ((0.0, 0.0, 0.0), 0.0, 0.0)
        ka = np.asarray(ka, float)
        r = trace_coat(45.0, tau, nk, gaussian_tilt(sig), ka, ks, g, n_photons=n, theta_edges_deg=THETA_EDGES,
                       phi_edges_deg=PHI_EDGES, seed=350, surface_roughness=alpha, edge_fraction=fe)
        med = CoatMedium(WAVELENGTHS, ka / H_COAT_NM, ks / H_COAT_NM, g, H_COAT_NM) if pig is not None else None
        paint = PaintBRDF(ClearCoat(N_COAT), RHO, FlakeLayer(aluminium_flakes(), gaussian_tilt(sig), tau,
                                                             surface_roughness=alpha, edge_fraction=fe), medium=med)
    b = paint.bin_average(WAVELENGTHS, _wi(45.0), THETA_EDGES, PHI_EDGES, n_quad=24)
    tol = N_SE * r["bins_se"] + MODEL_TOL_BINS * r["bins"]
    assert np.all(np.abs(b - r["bins"]) < tol), (case, np.round((b - r["bins"]) / r["bins_se"], 1)[..., 1])


# --------------------------------------------------------------------------------------
# flakes that reflect AND transmit (issue 18): interference flakes, R and T of their thin-film Stack


def _flat_flake_layer(R_top, R_bottom, T, tau):
    """Exact reflectance of a layer of flat flakes (optical depth τ, rate 1 per unit τ along any
    direction) over a black base, no coat: two streams down/up, dI↓/dt = −(1 − T) I↓ + R_b I↑,
    −dI↑/dt = −(1 − T) I↑ + R_t I↓ (down-going light meets the top face). With a = 1 − T,
    k = √(a² − R_t R_b): R = R_t sinh(kτ) / (k cosh(kτ) + a sinh(kτ)) (lossless: Rτ / (1 + Rτ));
    the light reflected by exactly one flake: R_t (1 − e^{−2aτ}) / (2a)."""
    a = 1.0 - T
    k = np.sqrt(np.maximum(a * a - R_top * R_bottom, 0.0))
    s = np.where(k * tau > 1e-8, np.sinh(k * tau) / np.where(k > 0, k, 1.0), tau)
    return R_top * s / (np.cosh(k * tau) + a * s), R_top * -np.expm1(-2 * a * tau) / (2 * a)


def test_tracer_transmitting_flakes_white_furnace_and_two_flux():
    """The tracer's flakes that reflect and transmit (:class:`StackFlake`, :func:`_flake_hit`).
    (a) White furnace: a lossless TiO2-like / mica / TiO2-like flake (n 2.5, 100 nm; 1.58,
    400 nm incoherent) under a lossless coat (n = 1.5) over a white base returns all light
    (measured 1.00000 ± 0.00001, 23 transmissions per photon). (b) Flat flakes (σ = 0.5°), no
    coat, black base, an ASYMMETRIC lossy flake (hematite 60 nm on mica 400 nm): the albedo and
    the one-reflection part equal the exact two-stream solution (:func:`_flat_flake_layer`;
    measured within 1.1 SE at 2·10^5 photons, three wavelengths in one run: grey branch
    probability, spectral weights), while the solution with the faces swapped is ≥ 10 SE away
    (down-going light meets the top face, up-going light the reversed stack)."""
    from nmmm.materials import get

    tilt = gaussian_tilt(SIGMA_DEG)
    lossless = ((2.5 + 0j, 100.0), (1.58 + 0j, 400.0, False), (2.5 + 0j, 100.0))
    f = StackFlake(lossless, [550.0], N_COAT)
    assert f.symmetric
    r = trace_coat(45.0, 2.0, f, tilt, np.zeros(1), 0.0, 0.0, rho=1.0, n_photons=10_000, seed=3)
    assert abs(r["albedo"][0] - 1.0) < 1e-3 and r["transmissions"] > 5, (r["albedo"], r["transmissions"])
    layers = ((get("main/Fe2O3/Querry-o"), 60.0), (1.58 + 0j, 400.0, False))
    f = StackFlake(layers, WAVELENGTHS, 1.0 + 1e-9)
    assert not f.symmetric
    th, tau = 30.0, 1.0
    # the reference's R and T straight from Stack (not through StackFlake's face choice and angle table): light
    # going down meets the layers as listed, light going up the reversed stack
    from nmmm.layers import Stack

    def rt(lay):
        r = Stack(lay, ambient=1.0 + 1e-9, substrate=1.0 + 1e-9).rt(WAVELENGTHS, [th])
        return 0.5 * (np.ravel(r.Rs) + np.ravel(r.Rp)), 0.5 * (np.ravel(r.Ts) + np.ravel(r.Tp))

    (Rt, T), (Rb, _) = rt(list(layers)), rt(list(layers)[::-1])
    exact, single = _flat_flake_layer(Rt, Rb, T, tau)
    swapped, _ = _flat_flake_layer(Rb, Rt, T, tau)
    r = trace_coat(th, tau, f, gaussian_tilt(0.5), np.zeros(3), 0.0, 0.0, rho=0.0, n=1.0 + 1e-9, n_photons=200_000,
                   seed=4)
    got, se = r["albedo"] - r["specular"], r["albedo_se"]
    # 4 SE + 0.1 % (the file's convention; measured |z| <= 0.8 and <= 1.0); with the faces swapped inside
    # StackFlake (up-going light meeting the top face) the albedo is 105 / 59 / 6 SE off
    assert np.all(np.abs(got - exact) < N_SE * se + 1e-3 * exact), (got, exact, se)
    assert np.all(np.abs(r["single_flake"] - single) < N_SE * se + 1e-3 * single), (r["single_flake"], single)
    assert np.abs(got - swapped)[0] > 10 * se[0], (got, swapped, se)


TRANSMITTING_WAVELENGTHS = np.arange(380.0, 781.0, 10.0)  # the recipe's grid: the lobe rule sees all its nodes


def _transmitting_paint(case):
    """The shipped pearl's coat (fe2o3_mica_pearl: deposit tilt, τ = 0.72, n = 1.5, primer 0.15, no pigment) with its
    own flakes (hematite 60 nm / mica 400 nm incoherent / hematite 60 nm) or TiO2/mica (120 nm anatase, 400 nm)."""
    from dataclasses import replace

    from nmmm.appearance.flakes import mica_pigment
    from nmmm.demo.appearance import _recipe_coat

    if case == "interference_paint()":  # the package's default pearlescent paint: σ = 10°, τ = 1, dark base 0.03
        from nmmm.appearance.brdf import interference_paint

        return interference_paint()
    paint, _ = _recipe_coat("fe2o3_mica_pearl", TRANSMITTING_WAVELENGTHS).brdf(TRANSMITTING_WAVELENGTHS)
    if case == "TiO2/mica":
        paint = paint.with_(flakes=replace(paint.flakes, optics=mica_pigment(120.0, 400.0)))
    return paint


def _trace_transmitting(paint, n_photons, seed, split_bins=False, theta_i=45.0):
    """The tracer on ``paint``'s coat at θi (45°), one run per wavelength of WAVELENGTHS (the grey branch
    probability is then exact: no spectral-weight variance): dict λ -> trace_coat's dict."""
    fl = paint.flakes
    body = paint.body_reflectance
    rho = float(np.ravel(body[1] if isinstance(body, tuple) else body)[0])  # grey in both paints
    n = float(np.mean(paint.coat.index(TRANSMITTING_WAVELENGTHS)))  # the binder, both sides of the flakes
    out = {}
    for j, lam in enumerate(WAVELENGTHS):
        f = StackFlake(fl.optics.layers, [lam], n)
        out[lam] = trace_coat(theta_i, fl.optical_depth, f, fl.tilt, np.zeros(1), 0.0, 0.0, fl.depth_range, rho=rho,
                              n=n, n_photons=n_photons, theta_edges_deg=THETA_EDGES, phi_edges_deg=PHI_EDGES,
                              seed=seed + j, split_bins=split_bins)
    return out


def _model_on(paint, components=None, n_quad=96, theta_i=45.0):
    """albedo (3,), bins (nθ, nφ, 3) and, per component, the hemispherical albedo (3,) at θi (45°) on WAVELENGTHS
    (n_quad = 96: the deposit's narrow tilt, mean 6.8°, leaves n_quad = 24 1 % low in the specular bin)."""
    w = TRANSMITTING_WAVELENGTHS
    li = np.searchsorted(w, WAVELENGTHS)
    wi = _wi(theta_i)
    a = paint.albedo(w, wi)[li]
    b = paint.bin_average(w, wi, THETA_EDGES, PHI_EDGES, n_quad=n_quad)[..., li]
    te, pe = np.linspace(0.0, 90.0, 19), np.linspace(0.0, 360.0, 25)
    t = np.radians(te)
    proj = 0.5 * (np.sin(t[1:]) ** 2 - np.sin(t[:-1]) ** 2)[:, None] * np.radians(np.diff(pe))[None, :]
    comp = {c: np.einsum("ab,abl->l", proj, paint.bin_average(w, wi, te, pe, components=(c,), n_quad=8)[..., li])
            for c in (components or ())}
    return a, b, comp


@pytest.mark.parametrize("case", ["Fe2O3/mica pearl", "TiO2/mica", "interference_paint()"])
def test_transmitting_flakes_match_mc(case):
    """Interference flakes that reflect and transmit, in the shipped pearl's coat, against the tracer (3·10^5
    photons per wavelength, θi = 45°): the paint's multiple lobe is the transport's, the one-flake and substrate
    terms (extinction per direction: τ a(μ) (1 − T̄(μ, λ)) / μ, ``_Tables.optical_path``) and the albedo within
    4 SE + 0.1 %, every bin within 4 SE + quadrature (MODEL_TOL_BINS). Measured at 4·10^6 (pearl) and 2·10^6
    (TiO2/mica) photons: module docstring, issue 18 (transmitting flakes); interference_paint() at 5·10^5: every
    bin within 2.1 SE, albedo within 0.0005 (its far bins had been 2.4-2.7x the tracer's at 550/650 nm)."""
    paint = _transmitting_paint(case)
    assert paint.prepare(TRANSMITTING_WAVELENGTHS).ms_lobe_shape == "transport"
    r = _trace_transmitting(paint, 300_000, seed={"F": 600, "T": 700, "i": 800}[case[0]])
    a, b, comp = _model_on(paint, ("flakes", "base"))
    for j, lam in enumerate(WAVELENGTHS):
        t = r[lam]
        # 4 SE + 0.1 % of the value (the file's convention; measured |z| <= 1.5 for all nine, the components
        # within 0.61 %). The former 4 SE + 0.003 allowed 38 % on TiO2/mica's one-flake term at 550 nm (0.0101)
        for got, want in ((a[j], t["albedo"][0]), (comp["flakes"][j], t["single_flake"][0]),
                          (comp["base"][j], t["base"][0])):
            assert abs(got - want) < N_SE * t["albedo_se"][0] + 1e-3 * want, (case, lam, got, want, t["albedo_se"])
        B, Bse = t["bins"][..., 0], t["bins_se"][..., 0]
        z = np.round((b[..., j] - B) / Bse, 1)
        assert np.all(np.abs(b[..., j] - B) < N_SE * Bse + MODEL_TOL_BINS * B), (case, lam, z)


@pytest.mark.slow
@pytest.mark.parametrize("case", ["Fe2O3/mica pearl", "TiO2/mica"])
def test_transmitting_flakes_match_mc_at_1e6_photons(case):
    """The comparison behind the lobe rule of ms_azimuth.lobe_tables at 10^6 photons per wavelength (bin SE
    ≤ 1.3 %): every bin within 4 SE + quadrature and the albedo within 4 SE + 0.1 % with the transport's lobe
    (module docstring: the table for both lobes)."""
    paint = _transmitting_paint(case)
    r = _trace_transmitting(paint, 1_000_000, seed=640 if case.startswith("Fe") else 740)
    a, b, _ = _model_on(paint)
    for j, lam in enumerate(WAVELENGTHS):
        t = r[lam]
        tol = N_SE * t["albedo_se"][0] + 1e-3 * t["albedo"][0]
        assert abs(a[j] - t["albedo"][0]) < tol, (case, lam, a[j], t["albedo"])
        B, Bse = t["bins"][..., 0], t["bins_se"][..., 0]
        z = np.round((b[..., j] - B) / Bse, 1)
        assert np.all(np.abs(b[..., j] - B) < N_SE * Bse + MODEL_TOL_BINS * B), (case, lam, z)


@pytest.mark.slow
@pytest.mark.parametrize("theta_i", [0.0, 45.0, 70.0])
def test_transmitting_flakes_multiple_amount(theta_i):
    """The multiple term (hemispherically integrated) at θi = 0°, 45° and 70° within 4 SE + 0.1 % of the tracer's
    for the pearl (10^6 photons per wavelength; the file's convention, SE of the multiple term itself: a 5 % band, as
    first written, sat inside the albedo's SE at 450 nm and could not tell). Was xfail: model / tracer 0.80 / 0.89 /
    0.97 at 450 / 550 / 650 nm (-67 / -35 / -8.6 SE), F_ms taking the exact terms-2–3 albedo from the node
    transport's total (the transport's own one-flake light 0.45 % low, a 20 % error on a multiple term 25× smaller;
    coat_transport: F_ms from the transport's own split, 96 × 96 nodes). Then at 0° 1.015 / 1.029 / 1.033 (7.6 / 13
    / 11 SE at 2·10^6 photons): the deposit's half-normal tilt, p(h) ∝ 1/θ_h per sr, point-sampled on the outgoing
    nodes (columns 9 % over near the normal, the transport not reciprocal there: ms_azimuth._core_kernel), and the
    lobe's shape linear in λ between 9 evenly spaced nodes (coat_transport._lobe_nodes: 17 for this paint). Measured
    here (seeds as below): 0° 1.0028 / 1.0063 / 1.0073 (z 1.0 / 2.1 / 1.7; before both fixes 1.0108 / 1.0289 / 1.0342,
    z 3.8 / 9.4 / 7.9), 45° 1.0018 / 1.0056 / 1.0082 (z 0.6 / 1.7 / 2.1), 70° 1.0033 / 0.9960 / 1.0026 (z 1.1 / -1.2 /
    0.7); 45 s for the three."""
    paint = _transmitting_paint("Fe2O3/mica pearl")
    r = _trace_transmitting(paint, 1_000_000, seed={0.0: 600, 45.0: 640, 70.0: 680}[theta_i], theta_i=theta_i)
    _, _, comp = _model_on(paint, ("multiple",), theta_i=theta_i)
    mc_ms = np.array([r[lam]["multiple"][0] for lam in WAVELENGTHS])
    se = np.array([r[lam]["multiple_se"][0] for lam in WAVELENGTHS])
    assert np.all(np.abs(comp["multiple"] - mc_ms) < N_SE * se + 1e-3 * mc_ms), (comp["multiple"] / mc_ms,
                                                                                  (comp["multiple"] - mc_ms) / se)
