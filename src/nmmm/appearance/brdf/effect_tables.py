"""Tables and kernel of a :class:`~nmmm.appearance.brdf.PaintBRDF` whose basecoat is a
pigmented medium (:class:`~nmmm.appearance.brdf.CoatMedium`) holding the flakes.

The terms are those of the package docstring with the pigments' extinction added on every
path (κ = (μa + μs) H the coat's vertical optical thickness, flakes uniform in the band
z0 … z0 + dz, internal cosines μi', μo', S' = 1/μi' + 1/μo'):

- flakes: τ p(h') R / (4 μi' μo') · exp(−κ z0 S') (1 − e^−X)/X, X = τ_e S + κ dz S'; with
  rough flake faces p is the facet-normal distribution (``TiltDistribution.roughened``), and
  R is reduced by (1 − f_e), the fraction f_e scattered diffusely by the flake rims
  (``FlakeLayer.edge_fraction``), whose light joins the multiple-scattering lobe;
- substrate: ρ / (π (1 − ρ r_t)) · exp(−τ_e S − κ S'), r_t with the same attenuation;
- everything else — light scattered by the pigments (once or more), pigment–flake and
  pigment–substrate interreflections — is the multiple-scattering lobe, its amount F_ms from
  :func:`~nmmm.appearance.brdf.coat_transport.coat_transport` and its azimuthal modes fused
  in the kernel. The lossless reference (white furnace) keeps the pigments' scattering and
  drops their absorption.

This is radiative transfer in the coat, not a Lambertian base under the flakes; with no
pigment (μs = μa = 0) it reduces to the model without a medium.
"""

from __future__ import annotations

import numpy as np

from nmmm.appearance.brdf.clear_coat import ggx_distribution, smith_g1_ggx
from nmmm.appearance.brdf.coat_transport import coat_transport
from nmmm.appearance.brdf.flake_lobe import flake_single_scattering_albedo
from nmmm.appearance.brdf.interpolation import _NA, _deg, _hemi_mean, _lerp1, _lerp_table, _refine_deficit
from nmmm.appearance.brdf.fused_kernel import evaluate_effect
from nmmm.appearance.brdf.ms_azimuth import lobe_factor
from nmmm.appearance.brdf.tables import _Tables
from nmmm.appearance.flakes import refract_in

_NS2 = 2048


def _s2_lerp(Q, S2, step):
    """Q (NS2, L) at S' (P,) -> (P, L)."""
    x = np.clip((S2 - 2.0) / step, 0.0, Q.shape[0] - 1.000001)
    i = x.astype(np.intp)
    f = (x - i)[:, None]
    return Q[i] * (1.0 - f) + Q[i + 1] * f


class _EffectTables(_Tables):
    """Tables of a paint with a coat medium (same attributes as :class:`_Tables`, plus κ)."""

    fuses_ms_azimuth = True

    def __init__(self, paint, w):
        med = paint.medium
        if med is None:
            z = np.zeros(w.size)
            self.kap_a, self.kap_s, self.g_pig = z, z, z
        else:
            self.kap_a, self.kap_s, self.g_pig = med.on_grid(w)
        self.kappa = self.kap_a + self.kap_s
        self.kappa0 = self.kap_s.copy()
        fl = paint.flakes
        z0, z1 = fl.depth_range if fl is not None else (0.0, 1.0)
        self.z0, self.dz = float(z0), float(z1 - z0)
        self.edge = fl.edge_fraction if fl is not None else 0.0
        if fl is not None and fl.surface_roughness > 0:  # rough faces: the facet-normal distribution
            from dataclasses import replace

            paint = paint.with_(flakes=replace(fl, tilt=fl.tilt.roughened(fl.surface_roughness), surface_roughness=0.0))
        super().__init__(paint, w)

    def _trans(self, mu, kappa):
        """exp(−τ_e a(μ)/μ − κ/μ) through the whole coat along internal cosines (P,) -> (P, L)."""
        mu = np.maximum(mu, 1e-12)
        x = np.outer(1.0 / mu, kappa)
        if self.has_flakes:
            x = x + self.optical_path(mu)
        return np.exp(-x)

    def _albedo_tables(self):
        n, L = self.n, self.L
        if self.has_flakes and self.edge > 0:
            # the rim scatters a fraction `edge` diffusely with the flake's mean reflectance
            # (relative to the lossless one); the mirror keeps the rest
            mu = np.cos(np.radians(np.linspace(0.0, 90.0, self.Rf.shape[0])))
            r0 = _hemi_mean(self.Rf0, mu)
            self.edge_albedo = np.where(r0 > 0, _hemi_mean(self.Rf, mu) / np.where(r0 > 0, r0, 1.0), 0.0)
            self.Rf = self.Rf * (1.0 - self.edge)
            self.Rf0 = self.Rf0 * (1.0 - self.edge)
        self.astep = 90.0 / (_NA - 1)
        tha = np.linspace(0.0, 90.0, _NA)
        mua = np.cos(np.radians(tha))
        xg, wg = np.polynomial.legendre.leggauss(128)
        mu_e, w_e = 0.5 * (xg + 1), 0.5 * wg
        th_e = _deg(mu_e)
        T_e = _lerp_table(self.Tc, th_e, self.step)
        Es_e = _lerp_table(self.Es, th_e, self.step)
        self.Es_bar = 2 * (w_e * mu_e) @ Es_e
        mu_i_e = np.sqrt(1 - (1 - mu_e ** 2) / (n * n))
        mu_c = np.sqrt(1 - 1 / (n * n))
        xi, wi_ = 0.5 * (xg + 1) * mu_c, 0.5 * wg * mu_c
        Ti = _lerp_table(self.Tc, tha, self.step)
        Esi = _lerp_table(self.Es, tha, self.step)
        mu_ii = np.sqrt(1 - (1 - mua ** 2) / (n * n))
        fl, fl0 = flake_single_scattering_albedo(self, mua)
        bases = []
        for kap, rho in ((self.kappa, self.rho), (self.kappa0, np.ones(L))):
            t_e, t_tir, t_i = self._trans(mu_i_e, kap), self._trans(xi, kap), self._trans(mu_ii, kap)
            r_t = 2 * (wi_ * xi) @ (t_tir ** 2) + 2 / (n * n) * (w_e * mu_e) @ (t_e ** 2 * Es_e)
            esc = 2 / (n * n) * (w_e * mu_e) @ (T_e * t_e)
            with np.errstate(divide="ignore", invalid="ignore"):
                b = Ti * t_i * (rho / (1 - rho * r_t)) * esc
            bases.append((np.where(np.isfinite(b), b, Ti), r_t))
        (base, self.r_t), (base0, _) = bases
        self.E1 = Esi + Ti * fl + base
        self.E10 = Esi + Ti * fl0 + base0
        self.E1[-1] = Esi[-1]
        self.E10[-1] = Esi[-1]
        self.Dms = np.clip(1.0 - self.E10, 0.0, 1.0)
        self.Dms_fine = _refine_deficit(self.Dms, Ti, self.astep, self.Tc, self.step)  # what the kernels read
        E0_bar = 2 * (w_e * mu_e) @ _lerp_table(self.E10, th_e, self.astep)
        self.E0_bar = E0_bar
        self.Fms = coat_transport(self)  # also the lobe's shape tables (c_0 and the modes)
        # attenuation by the pigments, exp(−c S'), tabulated over S' = 1/μi' + 1/μo' (2 … 2/μc',
        # internal directions lie in the escape cone): 2048 nodes, relative error ≤ (c Δ)²/8 ≈ 1e-5 c²
        mu_min = np.sqrt(max(1 - 1 / (n * n), 1e-6))
        self._s2_step = (2.0 / mu_min - 2.0) * 1.001 / (_NS2 - 1)
        s2 = 2.0 + self._s2_step * np.arange(_NS2)
        kap = np.asarray(self.kappa, float)
        self._Qd, self._Qz, self._Qb = (np.ascontiguousarray(np.exp(-np.outer(s2, kap * f)))
                                        for f in (self.dz, self.z0, 1.0 - self.dz))
        with np.errstate(divide="ignore", invalid="ignore"):
            self.Kms = np.where(1 - E0_bar > 1e-9, self.Fms / (np.pi * (1 - E0_bar)), 0.0)
        self.E0_bar = E0_bar

    # -- evaluation ------------------------------------------------------------------
    def evaluate_fast(self, wi, wo, comps, out):
        """The fused Numba kernel (:func:`~nmmm.appearance.brdf.fused_kernel.evaluate_effect`), writing ``out``."""
        evaluate_effect(self, wi, wo, comps, out)

    def evaluate(self, wi, wo, comps):
        P, L = wi.shape[0], self.L
        mi, mo = wi[:, 2], wo[:, 2]
        valid = (mi > 0) & (mo > 0)
        f = np.zeros((P, L))
        if not np.all(valid):
            if np.any(valid):
                f[valid] = self.evaluate(wi[valid], wo[valid], comps)
            return f
        thi, tho = _deg(mi), _deg(mo)
        if "specular" in comps and self.alpha > 0:
            h = wi + wo
            h /= np.linalg.norm(h, axis=-1, keepdims=True)
            D = ggx_distribution(h[:, 2], self.alpha)
            G = smith_g1_ggx(mi, self.alpha) * smith_g1_ggx(mo, self.alpha)
            f += (D * G / (4 * mi * mo))[:, None] * _lerp_table(self.Fs, _deg(np.sum(wi * h, axis=-1)), self.step)
        TT = _lerp_table(self.Tc, thi, self.step) * _lerp_table(self.Tc, tho, self.step) / self.n2
        ip, op = refract_in(wi, self.n), refract_in(wo, self.n)
        S2 = 1 / ip[:, 2] + 1 / op[:, 2]
        if self.has_flakes:
            S = (_lerp1(self.a_tab, _deg(ip[:, 2]), self.step) / ip[:, 2]
                 + _lerp1(self.a_tab, _deg(op[:, 2]), self.step) / op[:, 2])
        else:
            S = np.zeros(P)
        if self.has_flakes and not self.tau_e_const:  # flakes that transmit: per direction and λ
            Xf = self.optical_path(ip[:, 2]) + self.optical_path(op[:, 2])
        else:  # opaque flakes: τ_e S, bit for bit as before issue 18
            Xf = np.outer(S, self.tau_e)
        X = Xf + np.outer(S2, self.kappa) * self.dz
        if self.has_flakes and not self.tau_e_const:  # the flake layer's transmission in and out, as the kernel
            et = self._ext_exp()
            eX = (_lerp_table(et, _deg(ip[:, 2]), self.step) * _lerp_table(et, _deg(op[:, 2]), self.step)
                  * _s2_lerp(self._Qd, S2, self._s2_step))
        else:
            eX = np.exp(-Xf) * _s2_lerp(self._Qd, S2, self._s2_step)  # e^−X, as the kernel
        if self.has_flakes and "flakes" in comps:
            h = ip + op
            h /= np.linalg.norm(h, axis=-1, keepdims=True)
            g = self.tau * self.tilt.pdf(h[:, 2]) / (4 * ip[:, 2] * op[:, 2])
            att = (1.0 - eX) / (X + 1e-300)
            if self.z0 > 0:
                att = att * _s2_lerp(self._Qz, S2, self._s2_step)
            f += TT * g[:, None] * att * _lerp_table(self.Rf, _deg(np.sum(ip * h, axis=-1)), self.step)
        if "base" in comps and np.any(self.rho > 0):
            kb = self.rho / (np.pi * (1 - self.rho * self.r_t))
            eb = eX * _s2_lerp(self._Qb, S2, self._s2_step) if self.dz < 1 else eX
            f += TT * eb * kb
        if "multiple" in comps and np.any(self.Kms > 0):
            f += (_lerp_table(self.Dms_fine, thi, self.step) * _lerp_table(self.Dms_fine, tho, self.step) * self.Kms
                  * (1 + self._azimuth_factor(wi, wo)))
        return f

    def _azimuth_factor(self, wi, wo):
        """s(λ) = c_0 + 2 Σ c_m cos(m φ) (≥ −1): (P, L)."""
        return lobe_factor(self, wi, wo)

