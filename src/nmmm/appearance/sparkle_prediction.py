"""Sparkle at the pixel footprint, predicted from the flake statistics.

A pixel of a plate image integrates the flakes whose centres lie in its footprint on the
plate (area A, mm²). A flake at normal m sends its mirror reflection of a light into the
external direction f(m); the renderer spreads it over a normalised Gaussian lobe g
(per sr, width σ_g = ``glint_spread_deg``: the source's angular size and the flakes'
roughness, cut at 3σ_g) around f, so flake k adds X_k = K w_k g(∠(f_k, ωo)) to the pixel
radiance, with K the same for all flakes of the pixel (irradiance, coat transmission in
and out, flake reflectance, 1/(A cos θo)) and w_k = a_k exp(−τ_e S ζ_k) its own weight
(area a_k, mean-field attenuation by the flakes above it, ζ_k its optical-depth fraction,
S the path factor of :func:`nmmm.appearance.brdf.flake_list_reflection`; for flakes that
transmit τ_e S is the BRDF's optical depth per direction, τ a(μ)(1 − T̄(μ))/μ in and out); in a pigmented
basecoat (:class:`~nmmm.appearance.brdf.CoatMedium`, optical thickness κ = (μa + μs) H,
flakes in the band z0 … z0 + dz) also exp(−κ S' (z0 + dz ζ_k)), S' = 1/μi' + 1/μo' —
the same per-flake form whose mean is the statistical term's
e^{−κ z0 S'} (1 − e^{−X})/X, X = τ_e S + κ dz S'.

Flake centres form a stationary point process of density n_A (flakes / mm²) and their
normals follow the tilt density p_m per sr (:class:`~nmmm.appearance.flakes.TiltDistribution`),
so the mirror directions have the density per external sr

    p_ω(ωo) = p_m(h') cos θo / (4 n² (ωi'·h') cos θo')

(half-vector Jacobian 1/(4 ωi'·h') inside the binder of index n, refraction Jacobian
cos θo / (n² cos θo')), h' the half vector of the refracted directions ωi', ωo'.
The glinting flakes of a footprint are then a Poisson thinning of its flakes
(compound Poisson: the count of flakes whose lobe reaches ωo is Poisson with mean
λ = n_A A p_ω π (3σ_g)², each with an independent weight and lobe position), whence

- mean radiance ⟨L⟩ = n_A ⟨w⟩ K p_ω — the statistical flake BRDF of
  :class:`~nmmm.appearance.brdf.PaintBRDF` (its τ = n_A ⟨a⟩, its (1 − e^{−τ_e S})/(τ_e S)
  the mean of e^{−τ_e S ζ});
- per-pixel variance Var L = n_A A ⟨(K w g)²⟩ / A² → the relative variance

      Var L / ⟨L⟩² = (⟨w²⟩ / ⟨w⟩²) / N,   N = n_A A p_ω Ω_g,   Ω_g = 1 / ∫ g² dω

  N is the number of glinting flakes per pixel (the flakes whose mirror direction falls in
  the lobe's effective solid angle Ω_g ≈ 4π σ_g²). For a lobe wide enough that p_ω changes
  across it, the moments are integrated over the lobe (polar Gauss quadrature around ωo):
  N = n_A A (∫p_ω g)² / ∫p_ω g², the fourth cumulant n_A A ⟨w⁴⟩ ∫p_ω g⁴, and the glints'
  mean is the statistical BRDF times ``lobe_mean_factor`` = ∫p_ω g / p_ω(ωo). Closer viewing (smaller A) gives fewer,
  individually visible glints (large Var/⟨L⟩²); farther away they merge (N ≫ 1).

Rough flake faces (``FlakeLayer.surface_roughness`` α > 0, the renderer's law): flake k adds
w_k q(t(h') − t(m_k)) J, q the GGX facet density D cos of roughness α_eff (α² + 2 σ_g² J, the
source's lobe moved to the normals), composed as tilt vectors like
:meth:`~nmmm.appearance.flakes.TiltDistribution.roughened`, cut at 8 α_eff; the moments are
∫ p_m q^j over the normals and the glints' mean is the BRDF's roughened facet density times
``lobe_mean_factor`` (≈ 0.985, the cut tail). Most flakes of a pixel then glint, so the
correlation of the flakes' weights with their places in a deposit cell matters: the relative
variance is ⟨w²⟩/⟨w⟩² (1/N + (R − 1)/(n_A A)), R = Var(Σ w)/(n_A A ⟨w²⟩) over footprint-sized
windows of the cell (R = 1 compound Poisson). :func:`simulate_glint_pixels` still draws the
Gaussian lobe (mirror faces).

:func:`glint_footprint_statistics` evaluates these per pixel. :func:`simulate_glint_pixels`
draws pixel values from the same compound-Poisson law (no renderer, no flake positions),
and :func:`predicted_sparkle` applies the definitions of :func:`nmmm.appearance.sparkle.
sparkle_graininess` to such a statistical image (plus the analytic band-pass graininess
:func:`predicted_graininess`): the sparkle and graininess predicted from flake size,
number density, orientation and depth (issue 18 item 5).

References
----------
- W. Jakob, M. Hašan, L.-Q. Yan, J. Lawrence, R. Ramamoorthi, S. Marschner, "Discrete
  stochastic microfacet models", ACM TOG 33(4) (2014) — glint counts in a footprint.
- D. Daley, D. Vere-Jones, An Introduction to the Theory of Point Processes, Springer 2003
  — compound Poisson (Campbell) moments, independent thinning.
- C. S. McCamy, Color Res. Appl. 23 (1998) 362 — micro appearance of metallic paints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.spectra import check_finite

__all__ = ["GlintFootprintStatistics", "glint_footprint_statistics", "lobe_integrals", "simulate_glint_pixels",
           "predicted_graininess", "predicted_sparkle", "variance_standard_error", "pixel_footprint_mm2",
           "plate_light_geometry", "sparkle_from_composition"]

#: the renderer's lobe cut (in units of σ_g)
LOBE_CUT = 3.0


@dataclass(frozen=True)
class GlintFootprintStatistics:
    """Per-pixel statistics of the glints (arrays of the pixels' shape).

    ``glinting_flakes`` N (flakes whose mirror direction falls in the lobe's effective
    solid angle), ``candidates`` λ (mean number of flakes whose cut lobe reaches the view),
    ``relative_variance`` Var L / ⟨L⟩², ``weight_ratio`` ⟨w²⟩/⟨w⟩², ``mirror_density_per_sr``
    p_ω, ``density_per_mm2`` n_A, ``footprint_mm2`` A, and the flake weights' samples
    (``weights``, (N_flakes,) at each pixel's attenuation: (pixels, N_flakes) would be too
    big, so the weights at the mean path factor) for :func:`simulate_glint_pixels`."""

    glinting_flakes: np.ndarray
    candidates: np.ndarray
    relative_variance: np.ndarray
    weight_ratio: np.ndarray
    mirror_density_per_sr: np.ndarray
    density_per_mm2: float
    footprint_mm2: np.ndarray
    lobe_sigma_rad: float
    weights: np.ndarray
    relative_fourth_cumulant: np.ndarray
    #: ⟨L_glints⟩ / (statistical flake BRDF term): ∫ p_ω g dω / p_ω(ωo) (→ 1 for a narrow lobe)
    lobe_mean_factor: np.ndarray | float = 1.0

    def variance_error(self, n_pixels) -> np.ndarray:
        """Predicted standard error of the relative variance estimated from ``n_pixels``
        independent pixels: sqrt((κ4 + 2 σ⁴) / n) / ⟨L⟩² (κ4 = λ⟨X⁴⟩ for compound Poisson)."""
        rv = np.asarray(self.relative_variance, float)
        return np.sqrt((np.asarray(self.relative_fourth_cumulant, float) + 2 * rv * rv) / np.asarray(n_pixels, float))


def _refract_in(v, n):
    t = v[..., :2] / n
    return np.concatenate([t, np.sqrt(np.clip(1 - np.sum(t * t, axis=-1, keepdims=True), 0, 1))], axis=-1)


def _depth_fraction(flakes) -> np.ndarray:
    """ζ_k: the optical depth above flake k over the layer's (the renderer's definition)."""
    if hasattr(flakes, "optical_depth_above") and flakes.optical_depth > 0:
        return np.asarray(flakes.optical_depth_above(), float) / flakes.optical_depth
    top, bottom = flakes.layer_depth_nm
    return np.clip((np.asarray(flakes.depth_nm, float) - top) / max(bottom - top, 1e-9), 0.0, 1.0)


def lobe_integrals(sigma_rad: float, cut: float = LOBE_CUT) -> tuple[float, float, float]:
    """(∫ g dω, ∫ g² dω, ∫ g⁴ dω) of the renderer's cut Gaussian lobe (small-angle, flat):
    ∫ g^j dω = gnorm^j 2π σ² (1 − e^{−j c²/2}) / j."""
    gnorm = 1.0 / (2 * math.pi * sigma_rad ** 2 * (1 - math.exp(-0.5 * cut * cut)))
    g2 = gnorm ** 2 * math.pi * sigma_rad ** 2 * (1 - math.exp(-cut * cut))
    g4 = gnorm ** 4 * 0.5 * math.pi * sigma_rad ** 2 * (1 - math.exp(-2 * cut * cut))
    return 1.0, g2, g4


def _mirror_density(tilt, n, ip, wo):
    """p_ω(ωo) per external sr (module docstring), ip the refracted light direction."""
    op = _refract_in(wo, n)
    h = ip + op
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    ih = np.clip(np.sum(ip * h, axis=-1), 1e-9, 1.0)
    return tilt.pdf(h[..., 2]) * np.clip(wo[..., 2], 0.0, None) / (4 * n * n * ih * np.maximum(op[..., 2], 1e-9))


def _lobe_moments(tilt, n, ip, wo, sigma, n_r: int = 6, n_phi: int = 8, chunk: int = 32768):
    """(∫_disc p_ω dω, ∫ p_ω g dω, ∫ p_ω g² dω, ∫ p_ω g⁴ dω) around each ωo over the cut
    lobe (radius 3σ): Gauss–Legendre in the angle r (weight sin r), uniform in azimuth."""
    shape = wo.shape[:-1]
    wo2 = wo.reshape(-1, 3)
    ip2 = np.broadcast_to(ip, wo.shape).reshape(-1, 3)
    x, wx = np.polynomial.legendre.leggauss(n_r)
    rmax = LOBE_CUT * sigma
    r = 0.5 * (x + 1) * rmax
    wr = 0.5 * rmax * wx * np.sin(r)
    ph = (np.arange(n_phi) + 0.5) * 2 * math.pi / n_phi
    gnorm = 1.0 / (2 * math.pi * sigma ** 2 * (1 - math.exp(-0.5 * LOBE_CUT ** 2)))
    g = gnorm * np.exp(-0.5 * (r / sigma) ** 2)
    W = (wr[:, None] * np.full(n_phi, 2 * math.pi / n_phi)[None, :]).ravel()  # (K,)
    G = np.repeat(g, n_phi)
    cr, sr = np.repeat(np.cos(r), n_phi), np.repeat(np.sin(r), n_phi)
    cp, sp = np.tile(np.cos(ph), n_r), np.tile(np.sin(ph), n_r)
    out = np.zeros((4, wo2.shape[0]))
    for i in range(0, wo2.shape[0], chunk):
        o = wo2[i:i + chunk]
        t1 = np.cross(o, np.array([0.0, 0.0, 1.0]))
        bad = np.linalg.norm(t1, axis=1) < 1e-9
        t1[bad] = (1.0, 0.0, 0.0)
        t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
        t2 = np.cross(o, t1)
        d = (cr[None, :, None] * o[:, None, :] + sr[None, :, None]
             * (cp[None, :, None] * t1[:, None, :] + sp[None, :, None] * t2[:, None, :]))  # (c, K, 3)
        p = _mirror_density(tilt, n, ip2[i:i + chunk, None, :], d)  # (c, K)
        out[0, i:i + chunk] = p @ W
        out[1, i:i + chunk] = p @ (W * G)
        out[2, i:i + chunk] = p @ (W * G * G)
        out[3, i:i + chunk] = p @ (W * G ** 4)
    return tuple(v.reshape(shape) for v in out)


#: the cut of a rough-faced flake's facet lobe in units of its width α_eff (the renderer's)
ROUGH_LOBE_CUT = 8.0


def _facet_lobe_moments(tilt, n, ip, wo, sigma, alpha, n_r: int = 32, n_phi: int = 32, chunk: int = 2048,
                        cut: bool = True):
    """Rough flake faces (GGX α): each flake k adds K_k = q(t(h') − t(m_k)) per sr of facet
    normals at the path's half vector h', q = D cos of roughness α_eff (α_eff² = α² + 2 σ_n²,
    σ_n² = σ_g² J, J = cos θo / (4 n² (ωi'·h') cos θo'): the source's lobe moved to the normals)
    per unit tilt-vector area (small-angle composition, the law of TiltDistribution.roughened),
    cut at |δ| <= ROUGH_LOBE_CUT α_eff(normal view). Returns (∫_cut p, ∫ p K, ∫ p K², ∫ p K⁴)
    over the flake tilt density p (per tilt area, K with the factor θh/sin θh that makes it per
    sr) by a polar Gauss quadrature around t(h') (radius r = α_eff tan ψ, Gauss–Legendre in ψ),
    and J."""
    shape = wo.shape[:-1]
    op = _refract_in(wo, n)
    h = ip + op
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    ih = np.clip(np.sum(ip * h, axis=-1), 1e-9, 1.0)
    J = np.clip(wo[..., 2], 0.0, None) / (4 * n * n * ih * np.maximum(op[..., 2], 1e-9))
    h2, J2 = h.reshape(-1, 3), J.ravel()
    rcut = min(ROUGH_LOBE_CUT * math.sqrt(alpha ** 2 + 2 * sigma ** 2 / (4 * n * n)), math.radians(35.0))
    if not cut:
        rcut = math.radians(89.0)
    x, wx = np.polynomial.legendre.leggauss(n_r)
    ph = (np.arange(n_phi) + 0.5) * 2 * math.pi / n_phi
    cp, sp = np.cos(ph), np.sin(ph)
    out = np.zeros((4, h2.shape[0]))
    for i in range(0, h2.shape[0], chunk):
        hh = h2[i:i + chunk]
        ae = np.sqrt(alpha ** 2 + 2 * sigma ** 2 * J2[i:i + chunk])[:, None]  # (c, 1)
        pm = np.arctan(rcut / ae)
        psi = 0.5 * (x[None, :] + 1) * pm  # (c, n_r)
        r = ae * np.tan(psi)
        wr = 0.5 * pm * wx[None, :] * ae / np.cos(psi) ** 2 * r * (2 * math.pi / n_phi)  # dr · r dφ
        cd = np.cos(r)
        dd = cd * cd * (ae * ae - 1.0) + 1.0
        sh = np.hypot(hh[:, 0], hh[:, 1])
        th = np.arctan2(sh, hh[:, 2])
        fh = np.where(sh > 1e-12, th / np.maximum(sh, 1e-300), 1.0)
        K = ae * ae / (math.pi * dd * dd) * cd * np.where(r > 1e-12, np.sin(r) / np.maximum(r, 1e-300), 1.0)
        K = K * fh[:, None]
        th_x, th_y = (fh * hh[:, 0])[:, None, None], (fh * hh[:, 1])[:, None, None]
        mx = th_x - r[:, :, None] * cp[None, None, :]
        my = th_y - r[:, :, None] * sp[None, None, :]
        tm = np.hypot(mx, my)
        pf = tilt.pdf(np.cos(np.minimum(tm, math.pi / 2))) * np.where(tm > 1e-12, np.sin(tm) / np.maximum(tm, 1e-300), 1.0)
        pf = np.where(tm < math.pi / 2, pf, 0.0)
        ps = pf.sum(axis=2) * wr  # (c, n_r)
        out[0, i:i + chunk] = ps.sum(axis=1)
        out[1, i:i + chunk] = (ps * K).sum(axis=1)
        out[2, i:i + chunk] = (ps * K * K).sum(axis=1)
        out[3, i:i + chunk] = (ps * K ** 4).sum(axis=1)
    return tuple(v.reshape(shape) for v in out) + (J, h)


def _window_sum_excess(flakes, w, areas_mm2, n_windows: int = 4000, seed: int = 0):
    """R(A) = Var(Σ_k w_k over a window of area A) / (n_A A ⟨w²⟩) of the flake cell (periodic),
    square windows at random places: 1 for independently marked Poisson flakes (compound
    Poisson), < 1 for a regular or fixed-count cell, > 1 where bright flakes cluster (a
    deposit: the depth weights e^{−x ζ} are correlated in space). ``areas_mm2`` (M,) -> (M,)."""
    cw, chh = (float(v) * 1e-6 for v in flakes.region_nm)
    pos = np.asarray(flakes.positions_nm, float)[:, :2] * 1e-6
    n_a = pos.shape[0] / (cw * chh)
    rng = np.random.default_rng(seed)
    c = rng.random((n_windows, 2)) * (cw, chh)
    d = pos[None, :, :] - c[:, None, :]
    d[..., 0] -= cw * np.round(d[..., 0] / cw)
    d[..., 1] -= chh * np.round(d[..., 1] / chh)
    out = []
    for A in np.atleast_1d(areas_mm2):
        half = 0.5 * min(math.sqrt(A), cw, chh)
        inside = (np.abs(d[..., 0]) < half) & (np.abs(d[..., 1]) < half)
        sw = inside.astype(float) @ w
        out.append(sw.var() / (n_a * (2 * half) ** 2 * float(np.mean(w * w))))
    return np.array(out)


def glint_footprint_statistics(paint, flakes, wi, wo, footprint_mm2, glint_spread_deg: float = 1.0,
                               wavelength_nm: float = 550.0) -> GlintFootprintStatistics:
    """Predicted glint statistics of pixels whose footprint on the plate is ``footprint_mm2``.

    Parameters
    ----------
    paint : PaintBRDF
        The paint (coat index, flake layer: tilt density, optical depth, extinction).
    flakes : FlakeList
        The flake cell (number density, areas, depths); only its statistics are used.
    wi, wo : (..., 3)
        Unit directions to the light and to the viewer at each pixel's point.
    footprint_mm2 : (...)
        Area of each pixel's footprint on the plate (mm²).
    glint_spread_deg : float
        The renderer's lobe width σ_g (degrees).
    """
    sig = float(check_finite(glint_spread_deg, "glint_spread_deg"))
    if not 0 < sig <= 20:
        raise InvalidInputError(f"glint_spread_deg must lie in (0, 20] degrees, got {glint_spread_deg!r}")
    if paint.flakes is None:
        raise InvalidInputError("paint has no flake layer: a sparkle prediction needs flakes")
    wi = check_finite(wi, "wi").astype(float)
    wo = check_finite(wo, "wo").astype(float)
    A = check_finite(footprint_mm2, "footprint_mm2").astype(float)
    if np.any(A <= 0):
        raise InvalidInputError("footprint_mm2 must be > 0 (the pixel's area on the plate)")
    wi, wo = np.broadcast_arrays(wi, wo)
    tab = paint.prepare(np.array([float(wavelength_nm)]))
    n = float(tab.n)
    tilt = paint.flakes.tilt
    ip = _refract_in(wi, n)
    op = _refract_in(wo, n)
    p_w = _mirror_density(tilt, n, ip, wo)
    cw, chh = flakes.region_nm
    n_a = len(flakes) / (cw * chh * 1e-12)
    s = math.radians(sig)
    # the lobe moments of the mirror density, ∫ p_ω(ω) g^j(∠(ω, ωo)) dω (j = 0 over the cut
    # disc, 1, 2, 4), by a polar Gauss quadrature around ωo: exact for a density that varies
    # across a wide lobe, → p_ω(ωo) ∫ g^j as σ_g → 0
    alpha = float(getattr(paint.flakes, "surface_roughness", 0.0) or 0.0)
    if alpha > 0:
        # rough faces: the moments over the facet lobe in the normals' tilt-vector plane; the
        # glints' mean against the statistical term's facet density (tilt.roughened(α), the
        # BRDF's) at h'
        I0, I1, I2, I4, J, h = _facet_lobe_moments(tilt, n, ip, wo, s, alpha)
        rough = tilt.roughened(alpha)
        p_r = rough.pdf(h[..., 2])
        p_w = p_r * J
        # against the BRDF's facet density: the cut tail (~1.5 %) and roughened()'s own error
        lobe_factor = np.where(p_r > 0, I1 / np.where(p_r > 0, p_r, 1.0), 1.0)
    else:
        I0, I1, I2, I4 = _lobe_moments(tilt, n, ip, wo, s)
        lobe_factor = np.where(p_w > 0, I1 / np.where(p_w > 0, p_w, 1.0), 1.0)
    N = np.where(I2 > 0, n_a * A * I1 * I1 / np.where(I2 > 0, I2, 1.0), 0.0)
    lam = n_a * A * I0
    # weights a_k exp(-τ_e S ζ_k) at each pixel's path factor S (flakes that transmit: the
    # optical depth per direction in place of τ_e S, below)
    a = np.asarray(flakes.areas_nm2, float) * 1e-12
    zeta = _depth_fraction(flakes)
    tau_e = float(np.mean(tab.tau_e))
    mu_g = np.linspace(0.05, 1.0, 96)
    a_g = np.asarray((rough if alpha > 0 else tilt).projected_mean(mu_g), float)
    S = np.interp(ip[..., 2], mu_g, a_g) / ip[..., 2] + np.interp(op[..., 2], mu_g, a_g) / op[..., 2]
    # a pigmented basecoat (κ = (μa + μs) H, flakes in the band z0 … z0 + dz): flake k at
    # z0 + dz ζ_k is dimmed by e^{−κ S' (z0 + dz ζ_k)}, S' = 1/μi' + 1/μo'; e^{−κ S' z0} is
    # common to all flakes of the pixel (in K), κ dz S' joins the exponent of ζ
    kappa = float(np.mean(getattr(tab, "kappa", 0.0)))
    S2 = 1.0 / np.maximum(ip[..., 2], 1e-9) + 1.0 / np.maximum(op[..., 2], 1e-9)
    # moments over the flakes: Σ a e^{-x ζ}, Σ a² e^{-2 x ζ} on a grid of x = τ_e S + κ dz S'
    if tab.has_flakes and not tab.tau_e_const:
        # flakes that transmit: τ_e S is the BRDF's extinction per direction (issue 18),
        # τ a(μ)(1 − T̄(μ))/μ in and out (_Tables.optical_path, at this one wavelength)
        xf = (tab.optical_path(ip[..., 2].ravel()) + tab.optical_path(op[..., 2].ravel()))[:, 0].reshape(S.shape)
    else:
        xf = tau_e * S
    x = xf + kappa * float(getattr(tab, "dz", 1.0)) * S2
    xs = np.linspace(float(x.min()), float(x.max()), 33) if x.size else np.zeros(1)
    m1 = np.array([np.mean(a * np.exp(-v * zeta)) for v in xs])
    m2 = np.array([np.mean((a * np.exp(-v * zeta)) ** 2) for v in xs])
    m4 = np.array([np.mean((a * np.exp(-v * zeta)) ** 4) for v in xs])
    ratio = np.interp(x, xs, m2 / m1 ** 2)
    ratio4 = np.interp(x, xs, m4 / m1 ** 4)
    # the flakes' weights are not independent of their places in a deposit cell (bright,
    # shallow flakes cluster): Var = n_A A ⟨w²⟩ (I2 − I1²) + Var(Σ w) I1², so the relative
    # variance is ⟨w²⟩/⟨w⟩² (1/N + (R − 1)/(n_A A)), R the cell's window-sum excess
    # (R = 1: compound Poisson). It matters where most flakes of a pixel glint (rough faces)
    Ag = np.geomspace(max(float(A.min()), 1e-8), max(float(A.max()), 1e-8), 9)
    Rg = _window_sum_excess(flakes, a * np.exp(-float(np.mean(x)) * zeta), Ag)
    R = np.interp(np.log(A), np.log(Ag), Rg)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(N > 0, ratio / N + ratio * (R - 1.0) / (n_a * A), np.inf)
        k4 = np.where(I1 > 0, ratio4 * I4 / ((n_a * A) ** 3 * I1 ** 4), np.inf)
    weights = a * np.exp(-float(np.mean(x)) * zeta)
    return GlintFootprintStatistics(N, lam, rel, ratio, p_w, float(n_a), A, s, weights, k4, lobe_factor)


def simulate_glint_pixels(mean, stats: GlintFootprintStatistics, rng=None) -> np.ndarray:
    """Pixel values drawn from the compound-Poisson law of ``stats`` with mean ``mean``
    (same shape): Poisson(λ) flakes per pixel, each with a weight drawn from the flake
    cell's weights and a lobe position uniform over the cut disc (g ∝ exp(−r²/2σ²),
    r² uniform on [0, (3σ)²])."""
    rng = np.random.default_rng(rng)
    mean = np.asarray(mean, float)
    lam = np.broadcast_to(stats.candidates, mean.shape)
    k = rng.poisson(lam)
    tot = int(k.sum())
    w = rng.choice(stats.weights, size=tot)
    c2 = LOBE_CUT ** 2
    g = np.exp(-0.5 * c2 * rng.random(tot))
    mean_g = (1 - math.exp(-0.5 * c2)) / (0.5 * c2)
    pix = np.repeat(np.arange(k.size), k.ravel())
    sums = np.bincount(pix, weights=w * g, minlength=k.size).reshape(mean.shape)
    unit = lam * float(np.mean(stats.weights)) * mean_g
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(unit > 0, mean * sums / unit, 0.0)


def variance_standard_error(x) -> tuple[float, float]:
    """Sample variance of ``x`` and its standard error sqrt((m4 − s⁴)/n) (any distribution:
    the fourth central moment m4 carries the compound-Poisson tail)."""
    x = np.asarray(x, float).ravel()
    if x.size < 4:
        raise InvalidInputError("need at least 4 values to estimate a variance and its error")
    d = x - x.mean()
    s2 = float(np.mean(d * d)) * x.size / (x.size - 1)
    m4 = float(np.mean(d ** 4))
    return s2, math.sqrt(max(m4 - s2 * s2, 0.0) / x.size)


def _band_kernel_norm2(pixel_size_um, acuity_um, background_um, size=None):
    """Σ k² of the graininess band-pass (acuity − background Gaussians) of
    :func:`~nmmm.appearance.sparkle.sparkle_graininess`, for independent pixels."""
    from scipy import ndimage

    sb = background_um / pixel_size_um / 2.0
    m = int(size or (2 * int(4 * sb + 1) + 1))
    d = np.zeros((m, m))
    d[m // 2, m // 2] = 1.0
    k = (ndimage.gaussian_filter(d, acuity_um / pixel_size_um / 2.0, mode="constant")
         - ndimage.gaussian_filter(d, sb, mode="constant"))
    return float(np.sum(k * k))


def predicted_graininess(smooth, glint_mean, stats: GlintFootprintStatistics, pixel_size_um: float,
                         acuity_um: float = 50.0, background_um: float = 500.0) -> float:
    """Graininess G (definition of :func:`~nmmm.appearance.sparkle.sparkle_graininess`)
    predicted for an image whose pixels have mean ``smooth + glint_mean`` and independent
    glint noise of variance ``relative_variance · glint_mean²``:
    G² = (⟨Var⟩ Σ k² + Var(k ∗ mean)) / ⟨mean⟩², k the band-pass kernel."""
    from scipy import ndimage

    mu = np.asarray(smooth, float) + np.asarray(glint_mean, float)
    var = np.asarray(stats.relative_variance, float) * np.asarray(glint_mean, float) ** 2
    ps = float(pixel_size_um)
    band = (ndimage.gaussian_filter(mu, acuity_um / ps / 2.0, mode="reflect")
            - ndimage.gaussian_filter(mu, background_um / ps / 2.0, mode="reflect"))
    g2 = (float(np.mean(var)) * _band_kernel_norm2(ps, acuity_um, background_um) + float(band.var())) / float(mu.mean()) ** 2
    return math.sqrt(g2)


def predicted_sparkle(smooth, glint_mean, stats: GlintFootprintStatistics, pixel_size_um: float, rng=0,
                      **kwargs):
    """:class:`~nmmm.appearance.sparkle.SparkleMetrics` of a statistical image — ``smooth``
    plus glints drawn by :func:`simulate_glint_pixels` — with the definitions of
    :func:`~nmmm.appearance.sparkle.sparkle_graininess` (``kwargs`` go there)."""
    from nmmm.appearance.sparkle import sparkle_graininess

    img = np.asarray(smooth, float) + simulate_glint_pixels(glint_mean, stats, rng)
    return sparkle_graininess(img, pixel_size_um, **kwargs)


def pixel_footprint_mm2(camera) -> tuple[np.ndarray, np.ndarray]:
    """Footprint areas (H, W) in mm² of a pinhole camera's pixels on the plate z = 0 (the
    quadrilateral of its four corner rays, by its diagonals' cross product) and the pixel
    centres' points (H, W, 3) on the plate."""
    W, H = camera.resolution
    c = np.asarray(camera.position_mm, float)

    def hit(rows, cols):
        d = camera.pixel_directions(rows, cols)
        with np.errstate(divide="ignore", invalid="ignore"):
            return c - d * (c[2] / d[..., 2])[..., None]

    P = hit(np.arange(H, dtype=float), np.arange(W, dtype=float))
    Pc = hit(np.arange(H + 1) - 0.5, np.arange(W + 1) - 0.5)
    a = Pc[1:, 1:] - Pc[:-1, :-1]
    b = Pc[:-1, 1:] - Pc[1:, :-1]
    return 0.5 * np.abs(a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]), P


def plate_light_geometry(camera, light) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(A, P, wi, wo, E)`` of a pinhole camera's pixels on the plate z = 0 and one light: the
    footprints A (H, W) mm² and points P (H, W, 3) of :func:`pixel_footprint_mm2`, the unit
    directions wi to the light and wo to the camera (H, W, 3), and E (H, W) = cos θi / r² (r in m)
    for a point light (``position_mm``) or cos θi for a directional one (``direction``) — times the
    light's spectral intensity (irradiance) it is the plate's irradiance."""
    A, P = pixel_footprint_mm2(camera)
    wo = np.asarray(camera.position_mm, float) - P
    wo /= np.linalg.norm(wo, axis=-1, keepdims=True)
    if hasattr(light, "position_mm"):
        v = np.asarray(light.position_mm, float) - P
        r = np.linalg.norm(v, axis=-1)
        wi = v / r[..., None]
        E = wi[..., 2] / (r * 1e-3) ** 2
    else:
        wi = np.broadcast_to(np.asarray(light.direction, float), wo.shape)
        E = wi[..., 2]
    return A, P, wi, wo, E


def sparkle_from_composition(paint, flakes, illumination_deg=(15.0, 45.0, 75.0), pixel_size_um: float = 40.0,
                             size_px: int = 160, glint_spread_deg: float = 1.0, wavelength_nm: float = 550.0,
                             n_images: int = 8, rng=0, **kwargs) -> dict:
    """Sparkle and graininess predicted from the composition for a camera along the normal
    and a directional light at each ``illumination_deg`` (multi-angle sparkle instruments
    light at 15°, 45°, 75° and image at 0°), without rendering.

    The image is ``size_px`` square pixels of ``pixel_size_um``: its mean is the paint's BRDF
    (smooth part + the statistical flake term through the lobe), its glints the compound-Poisson
    law of :func:`glint_footprint_statistics`; the metric is
    :func:`~nmmm.appearance.sparkle.sparkle_graininess` (``kwargs`` go there) averaged over
    ``n_images`` statistical images. Returns ``{angle: {metric: mean, metric + "_sd": spread}}``
    with the glinting flakes per pixel and the analytic graininess ``graininess_analytic``.
    """
    ps = float(check_finite(pixel_size_um, "pixel_size_um"))
    if not ps > 0:
        raise InvalidInputError(f"pixel_size_um must be > 0, got {pixel_size_um!r}")
    m = int(size_px)
    if m < 8:
        raise InvalidInputError(f"size_px must be >= 8 pixels, got {size_px!r}")
    rng = np.random.default_rng(rng)
    w = np.array([float(wavelength_nm)])
    A = np.full((m, m), (ps * 1e-3) ** 2)
    wo = np.broadcast_to(np.array([0.0, 0.0, 1.0]), (m, m, 3))
    out = {}
    for ang in np.atleast_1d(np.asarray(illumination_deg, float)):
        if not 0 <= ang < 90:
            raise InvalidInputError(f"illumination_deg must lie in [0, 90), got {ang!r}")
        t = math.radians(ang)
        wi = np.array([0.0, math.sin(t), math.cos(t)])
        smooth = float(paint.evaluate(w, wi, wo[0, 0], components=("specular", "base", "multiple"))[0]) * wi[2]
        stat = float(paint.evaluate(w, wi, wo[0, 0], components=("flakes",))[0]) * wi[2]
        st = glint_footprint_statistics(paint, flakes, np.broadcast_to(wi, (m, m, 3)), wo, A, glint_spread_deg,
                                        wavelength_nm)
        gmean = np.full((m, m), stat) * np.asarray(st.lobe_mean_factor)
        sm = np.full((m, m), smooth)
        mets = [predicted_sparkle(sm, gmean, st, ps, rng=rng, **kwargs).as_dict() for _ in range(int(n_images))]
        row = {}
        for k in ("density_per_mm2", "area_fraction", "mean_contrast", "p90_contrast", "sparkle_intensity",
                  "graininess"):
            v = np.array([d[k] for d in mets], float)
            row[k] = float(v.mean())
            row[k + "_sd"] = float(v.std(ddof=1)) if v.size > 1 else 0.0
        row["glinting_flakes_per_pixel"] = float(np.mean(st.glinting_flakes))
        row["graininess_analytic"] = predicted_graininess(sm, gmean, st, ps)
        out[float(ang)] = row
    return out
