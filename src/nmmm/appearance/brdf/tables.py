"""Per-wavelength-grid tables of a :class:`~nmmm.appearance.brdf.PaintBRDF`: coat Fresnel
and transmission, flake reflectance and projected area, the albedos E1 (single scattering)
and E10 (lossless), the multiple-scattering lobe; and the NumPy evaluation of the four terms
from them (the Numba path is :mod:`~nmmm.appearance.brdf.fused_kernel`).
"""

from __future__ import annotations

import numpy as np

from nmmm.appearance.brdf.clear_coat import ggx_distribution, smith_g1_ggx
from nmmm.appearance.brdf.flake_lobe import flake_single_scattering_albedo
from nmmm.appearance.brdf.fused_kernel import _kernel
from nmmm.appearance.brdf.interpolation import _NA, _NT, _deg, _hemi_mean, _lerp1, _lerp_table, _phi_mean, _refine_deficit
from nmmm.appearance.brdf.ms_azimuth import azimuth_modes
from nmmm.appearance.brdf.multiple_scattering import multiple_scattering_factor
from nmmm.appearance.brdf.spectral_inputs import _spectral_values
from nmmm.appearance.flakes import fresnel_unpolarized, refract_in


class _Tables:
    """Per-wavelength-grid tables of a PaintBRDF (angles on uniform grids)."""

    def __init__(self, paint, w: np.ndarray):
        self.w = w
        self.L = w.size
        coat = paint.coat
        n_l = coat.index(w)
        self.n = float(np.mean(n_l))  # geometry index
        self.n2 = self.n * self.n
        self.alpha = coat.roughness
        self.step = 90.0 / (_NT - 1)
        th = np.linspace(0.0, 90.0, _NT)
        mu = np.cos(np.radians(th))
        # coat Fresnel (external incidence), (NT, L)
        self.Fs = fresnel_unpolarized(mu[:, None], 1.0, n_l[None, :])
        self.Fs[-1] = 1.0
        # specular albedo E_s and coat transmission T = 1 - E_s
        if self.alpha > 0:  # on a 1-degree grid, interpolated (smooth in θ)
            th_c = np.linspace(0.0, 90.0, _NA)
            es_c = self._ggx_albedo(np.cos(np.radians(th_c)))
            self.Es = np.stack([np.interp(th, th_c, es_c[:, j]) for j in range(self.L)], axis=-1)
        else:
            self.Es = self.Fs.copy()
        self.Tc = np.clip(1.0 - self.Es, 0.0, 1.0)
        self.rho = _spectral_values(paint.body_reflectance, w, "body_reflectance")
        # flakes
        fl = paint.flakes
        self.has_flakes = fl is not None and fl.optical_depth > 0
        if self.has_flakes:
            self.tau = fl.optical_depth
            self.tilt = fl.tilt
            c_loc = np.clip(mu, 1e-6, 1.0)
            R, T = fl.optics.rt(c_loc, w, self.n)
            self.Rf = np.asarray(R, float)  # (NT, L) over the local angle in the binder
            Tf = np.asarray(T, float)
            # lossless reference: absorption turned into reflection
            self.Rf0 = np.clip(1.0 - Tf, 0.0, 1.0)
            tbar = _hemi_mean(Tf, mu)  # cosine-weighted mean flake transmittance
            self.tau_e = self.tau * np.clip(1.0 - tbar, 0.0, 1.0)  # (L,)
            self.a_tab = np.asarray(self.tilt.projected_mean(mu), float)  # over internal angle
            self.T_dir = self._directional_transmission(Tf, mu)  # (NT, L)
            # opaque flakes: one extinction at every wavelength and angle (the kernels' fast path)
            self.tau_e_const = not bool(np.any(self.T_dir > 0))
            # τ a(μ) (1 − T̄(μ, λ)): the flake layer's extinction along μ is this / μ (NT, L)
            self.ext_tab = np.ascontiguousarray(self.tau * self.a_tab[:, None] * (1.0 - self.T_dir))
        else:
            self.tau = 0.0
            self.tau_e = np.zeros(self.L)
            self.tau_e_const = True
            self.ext_tab = np.zeros((2, self.L))
        self._albedo_tables()

    # ------------------------------------------------------------------------------
    def _directional_transmission(self, Tf, mu, n_theta: int = 32, n_phi: int = 24):
        """T̄(μ, λ) = ∫ p(m) |u·m| T(|u·m|) dω_m / a(μ): the flakes' transmission averaged over
        the normals a ray along internal cosine μ meets (weighted by their projected area), (NT, L).
        The exact extinction per unit τ along u is a(μ) (1 − T̄(μ)) / μ: transmitted light keeps
        its direction, so it is not scattered. Zero for opaque flakes."""
        if not np.any(Tf > 0):
            return np.zeros_like(Tf)
        m, wq = self.tilt.quadrature(n_theta, n_phi, half=True)
        s = np.sqrt(np.clip(1.0 - mu * mu, 0.0, 1.0))
        c = np.abs(np.outer(s, m[:, 0]) + np.outer(mu, m[:, 2]))  # (NT, K)
        cw = c * wq[None, :]
        out = np.empty_like(Tf)
        for j in range(mu.size):  # one direction at a time: (K, L) tables
            tq = _lerp_table(Tf, _deg(c[j]), self.step)
            out[j] = cw[j] @ tq / max(cw[j].sum(), 1e-300)
        return np.clip(out, 0.0, 1.0)

    def extinction_ratio(self, theta_deg):
        """(1 − T̄(θ, λ)) at internal polar angles (k,) -> (k, L): the flake layer's extinction per
        unit τ along θ relative to opaque flakes' a(μ)/μ (transmitted light is not scattered)."""
        return 1.0 - _lerp_table(self.T_dir, np.asarray(theta_deg, float), self.step)

    def _ext_exp(self):
        """exp(−τ a(μ) (1 − T̄(μ, λ)) / μ) on the angle nodes of ``ext_tab`` (NT, L): the flake layer's
        transmission along each internal direction, interpolated by both kernels (``fused_kernel`` and
        the effect kernel) and both NumPy paths for flakes that transmit instead of an exp per pair and
        wavelength (no SVML: a libm call each, 81·10^6 for 10^6 pairs). Linear interpolation of the
        exponential (nodes 0.5° apart; internal θ ≤ 41.8° at n = 1.5): the pearl's coat with a red
        pigment within 1.9e-6 relative of the exponential of the interpolated path. A (2, L) table of
        zeros for opaque flakes (the kernels do not read it)."""
        e = getattr(self, "_ext_exp_tab", None)
        if e is None:
            if self.has_flakes and not self.tau_e_const:
                mu = np.cos(np.radians(np.arange(self.ext_tab.shape[0]) * self.step))
                with np.errstate(divide="ignore", over="ignore"):
                    e = np.exp(-self.ext_tab / np.maximum(mu, 1e-300)[:, None])
            else:
                e = np.zeros((2, self.L))
            self._ext_exp_tab = e = np.ascontiguousarray(e, float)
        return e

    def _ggx_albedo(self, mu_nodes, n_u=64, n_phi=64):
        a = self.alpha
        x, wx = np.polynomial.legendre.leggauss(n_u)
        u = 0.5 * (x + 1)
        wu = 0.5 * wx
        t2 = a * a * u / (1 - u)
        ch = 1 / np.sqrt(1 + t2)
        sh = np.sqrt(1 - ch * ch)
        ph = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
        H = np.stack(np.broadcast_arrays(sh[:, None] * np.cos(ph), sh[:, None] * np.sin(ph), ch[:, None]), -1).reshape(-1, 3)
        W = np.broadcast_to(wu[:, None] / n_phi, (n_u, n_phi)).reshape(-1)
        out = np.empty((mu_nodes.size, self.L))
        for k, m in enumerate(mu_nodes):
            m = max(m, 1e-4)
            wi = np.array([np.sqrt(1 - m * m), 0.0, m])
            ih = H @ wi
            oz = 2 * ih * H[:, 2] - m
            ok = (ih > 0) & (oz > 0)
            g = smith_g1_ggx(m, a) * smith_g1_ggx(np.where(ok, oz, 1.0), a)
            F = _lerp_table(self.Fs, _deg(ih), self.step)
            wt = np.where(ok, W * g * ih / (m * H[:, 2]), 0.0)
            out[k] = wt @ F
        return out

    def _t(self, mu):
        """Transmission through the flake layer along internal cosines μ (P,) -> (P, L):
        exp(−τ a(μ) (1 − T̄(μ, λ)) / μ) (flakes that transmit: :meth:`_directional_transmission`)."""
        return np.exp(-self.optical_path(mu))

    def optical_path(self, mu):
        """τ a(μ) (1 − T̄(μ, λ)) / μ, the flake layer's optical depth along internal cosines μ (P,) ->
        (P, L); τ a(μ)/μ for opaque flakes."""
        mu = np.maximum(np.asarray(mu, float), 1e-12)
        if not self.has_flakes:
            return np.zeros((mu.size, self.L))
        if self.tau_e_const:
            return np.outer(_lerp1(self.a_tab, _deg(mu), self.step) / mu, self.tau_e)
        return _lerp_table(self.ext_tab, _deg(mu), self.step) / mu[:, None]

    def _albedo_tables(self):
        """E1 (single-scattering albedo), E10 (same, lossless), multiple-scattering lobe."""
        n, L = self.n, self.L
        self.astep = 90.0 / (_NA - 1)
        tha = np.linspace(0.0, 90.0, _NA)
        mua = np.cos(np.radians(tha))
        # external cosine grid for hemispherical integrals (Gauss–Legendre in μ)
        xg, wg = np.polynomial.legendre.leggauss(128)
        mu_e = 0.5 * (xg + 1)
        w_e = 0.5 * wg
        th_e = _deg(mu_e)
        T_e = _lerp_table(self.Tc, th_e, self.step)  # (G, L)
        Es_e = _lerp_table(self.Es, th_e, self.step)
        self.Es_bar = 2 * (w_e * mu_e) @ Es_e  # (L,)
        # internal cosines corresponding to mu_e (Snell), and those beyond the critical angle
        mu_i_e = np.sqrt(1 - (1 - mu_e ** 2) / (n * n))
        mu_c = np.sqrt(1 - 1 / (n * n))
        xi = 0.5 * (xg + 1) * mu_c
        wi_ = 0.5 * wg * mu_c
        if self.has_flakes:
            t_e = self._t(mu_i_e)
            t_tir = self._t(xi)
        else:
            t_e = np.ones((mu_e.size, L))
            t_tir = np.ones((xi.size, L))
        # r_t = 2∫_0^μc t² μ' dμ' + (2/n²)∫ t² E_s μ dμ
        self.r_t = 2 * (wi_ * xi) @ (t_tir ** 2) + 2 / (n * n) * (w_e * mu_e) @ (t_e ** 2 * Es_e)
        esc = 2 / (n * n) * (w_e * mu_e) @ (T_e * t_e)  # ∫ T_o t_o cos dω_o / (π n²) ... times π
        # per-incidence pieces
        Ti = _lerp_table(self.Tc, tha, self.step)  # (NA, L)
        Esi = _lerp_table(self.Es, tha, self.step)
        mu_ii = np.sqrt(1 - (1 - mua ** 2) / (n * n))
        if self.has_flakes:
            t_i = self._t(mu_ii)
        else:
            t_i = np.ones((_NA, L))
        rho = self.rho
        with np.errstate(divide="ignore", invalid="ignore"):
            base = Ti * t_i * (rho / (1 - rho * self.r_t)) * esc
            base0 = Ti * t_i * (1.0 / (1 - self.r_t)) * esc
        base0 = np.where(np.isfinite(base0), base0, Ti)  # r_t = 1 only for a fully trapping coat
        fl, fl0 = flake_single_scattering_albedo(self, mua)
        self.E1 = Esi + Ti * fl + base
        self.E10 = Esi + Ti * fl0 + base0
        self.E1[-1] = Esi[-1]
        self.E10[-1] = Esi[-1]
        # multiple-scattering compensation (Kulla & Conty 2017)
        self.Dms = np.clip(1.0 - self.E10, 0.0, 1.0)
        self.Dms_fine = _refine_deficit(self.Dms, Ti, self.astep, self.Tc, self.step)  # what the kernels read
        E0_bar = 2 * (w_e * mu_e) @ _lerp_table(self.E10, th_e, self.astep)
        sub = 2 * (w_e * mu_e) @ (_lerp_table(self.E1 - self._es_at(tha), th_e, self.astep))
        sub0 = 2 * (w_e * mu_e) @ (_lerp_table(self.E10 - self._es_at(tha), th_e, self.astep))
        with np.errstate(divide="ignore", invalid="ignore"):
            fbar = np.where(sub0 > 1e-12, np.clip(sub / sub0, 0, 1), 0.0)
            Fms = fbar ** 2 * E0_bar / (1 - fbar * (1 - E0_bar))
            self.Fms = np.where(np.isfinite(Fms), Fms, 0.0)
        if self.has_flakes:
            # trapped light in a flake layer escapes far less easily than Kulla–Conty's
            # "escape per cycle = Ē⁰" assumes: use the interreflection model instead
            self.Fms = multiple_scattering_factor(self, sub, sub0)
        with np.errstate(divide="ignore", invalid="ignore"):
            self.Kms = np.where(1 - E0_bar > 1e-9, self.Fms / (np.pi * (1 - E0_bar)), 0.0)
        self.E0_bar = E0_bar
        # the lobe's polar shape c_0 and azimuthal modes from the flake layer's transport, and its
        # directional albedo relative to (1 − E⁰) F_ms (ms_azimuth.lobe_tables)
        self.ms_albedo_factor = np.ones_like(self.Dms)
        self._ms_modes_spectral, self._ms_nodes = np.zeros((1, 1, 1, 0)), np.zeros(1, np.int64)
        self.ms_lobe_shape = "separable"  # or "transport" (lobe_tables)
        if self.has_flakes and np.any(self.Kms > 0):
            azimuth_modes(self)

    def _es_at(self, tha):
        return _lerp_table(self.Es, tha, self.step)

    def albedo_nodes(self):
        """Directional albedo (all terms) and its lossless counterpart on the 0.5° nodes -> two (NT, L)
        arrays, cached: the single terms E = R + T g and the multiple lobe's amount refined through the
        coat as the kernels read it (:func:`~nmmm.appearance.brdf.interpolation._refine_deficit`), the
        lobe's directional factor interpolated from the albedo nodes. Linear between the nodes."""
        cached = getattr(self, "_albedo_nodes", None)
        if cached is None:
            tha = np.linspace(0.0, 90.0, self.E1.shape[0])
            Ti, Ri = _lerp_table(self.Tc, tha, self.step), _lerp_table(self.Es, tha, self.step)
            e1 = _refine_deficit(self.E1, Ti, self.astep, self.Tc, self.step, Ri, self.Es)
            e10 = _refine_deficit(self.E10, Ti, self.astep, self.Tc, self.step, Ri, self.Es)
            th = np.arange(self.Tc.shape[0]) * self.step
            fac = _lerp_table(self.ms_albedo_factor, th, self.astep)
            cached = self._albedo_nodes = (e1 + self.Dms_fine * fac * self.Fms, e10 + self.Dms_fine)
        return cached

    def evaluate_fast(self, wi, wo, comps, out):
        """The fused Numba kernel (same equations as :meth:`evaluate`), writing ``out``."""
        Rf = self.Rf if self.has_flakes else np.zeros((2, self.L))  # read with weight 0
        a_tab = self.a_tab if self.has_flakes else np.zeros(2)
        den = self.tilt.density if self.has_flakes else np.zeros(2)
        dstep = (self.tilt.tilt_deg[1] - self.tilt.tilt_deg[0]) if self.has_flakes else 1.0
        with np.errstate(divide="ignore", invalid="ignore"):
            kb = np.where(self.rho > 0, self.rho / (np.pi * (1 - self.rho * self.r_t)), 0.0)
        do_base = "base" in comps and bool(np.any(self.rho > 0))
        do_ms = "multiple" in comps and bool(np.any(self.Kms > 0))
        if not do_base:  # the kernel's wavelength loop reads every table with a 0/1 weight
            kb = np.zeros(self.L)
        _kernel(np.ascontiguousarray(wi), np.ascontiguousarray(wo), out, self.Fs, self.Tc, Rf, a_tab, den,
                self.step, dstep, self.n, self.alpha, self.tau if self.has_flakes else 0.0,
                np.ascontiguousarray(self.tau_e, float), self.ext_tab, self._ext_exp(), kb, self.Dms_fine,
                np.asarray(self.Kms, float),
                "specular" in comps, "flakes" in comps and self.has_flakes, do_base, do_ms,
                bool(self.tau_e_const))

    def _eX(self, ip, op):
        """The flake layer's transmission in and out, exp(−X) for flakes that transmit, from the table
        :meth:`_ext_exp` interpolated at the internal directions ip, op (P, 3) -> (P, L), as the kernels."""
        et = self._ext_exp()
        return _lerp_table(et, _deg(ip[:, 2]), self.step) * _lerp_table(et, _deg(op[:, 2]), self.step)

    def evaluate(self, wi, wo, comps):
        P = wi.shape[0]
        L = self.L
        mi, mo = wi[:, 2], wo[:, 2]
        valid = (mi > 0) & (mo > 0)
        f = np.zeros((P, L))
        if not np.any(valid):
            return f
        if not np.all(valid):
            f[valid] = self.evaluate(wi[valid], wo[valid], comps)
            return f
        thi, tho = _deg(mi), _deg(mo)
        if "specular" in comps and self.alpha > 0:
            h = wi + wo
            h /= np.linalg.norm(h, axis=-1, keepdims=True)
            cd = np.sum(wi * h, axis=-1)
            D = ggx_distribution(h[:, 2], self.alpha)
            G = smith_g1_ggx(mi, self.alpha) * smith_g1_ggx(mo, self.alpha)
            F = _lerp_table(self.Fs, _deg(cd), self.step)
            f += (D * G / (4 * mi * mo))[:, None] * F
        need_sub = bool({"flakes", "base"} & comps) and (self.has_flakes or np.any(self.rho > 0))
        if need_sub:
            TT = _lerp_table(self.Tc, thi, self.step)
            TT *= _lerp_table(self.Tc, tho, self.step)
            TT /= self.n2
            ip = refract_in(wi, self.n)
            op = refract_in(wo, self.n)
            sub = np.zeros((P, L))
            if self.has_flakes:
                ai = _lerp1(self.a_tab, _deg(ip[:, 2]), self.step) / ip[:, 2]
                ao = _lerp1(self.a_tab, _deg(op[:, 2]), self.step) / op[:, 2]
            if self.has_flakes and "flakes" in comps:
                h = ip + op
                h /= np.linalg.norm(h, axis=-1, keepdims=True)
                cd = np.sum(ip * h, axis=-1)
                p = self.tilt.pdf(h[:, 2])
                g = self.tau * p / (4 * ip[:, 2] * op[:, 2])
                S = ai + ao
                if self.tau_e_const:
                    g = g * _phi_mean(S * self.tau_e[0])
                    sub += g[:, None] * _lerp_table(self.Rf, _deg(cd), self.step)
                else:  # flakes that transmit: e^−X from the table of the transmission in and out, as the kernel
                    X = self.optical_path(ip[:, 2]) + self.optical_path(op[:, 2])
                    with np.errstate(divide="ignore", invalid="ignore"):
                        ph = np.where(X < 1e-6, 1.0 - 0.5 * X, (1.0 - self._eX(ip, op)) / X)
                    sub += g[:, None] * ph * _lerp_table(self.Rf, _deg(cd), self.step)
            if "base" in comps and np.any(self.rho > 0):
                kb = self.rho / (np.pi * (1 - self.rho * self.r_t))
                if self.has_flakes:
                    if self.tau_e_const:
                        sub += np.exp(-(ai + ao) * self.tau_e[0])[:, None] * kb
                    else:
                        sub += self._eX(ip, op) * kb
                else:
                    sub += kb
            f += TT * sub
        if "multiple" in comps and np.any(self.Kms > 0):
            f += _lerp_table(self.Dms_fine, thi, self.step) * _lerp_table(self.Dms_fine, tho, self.step) * self.Kms
        return f
