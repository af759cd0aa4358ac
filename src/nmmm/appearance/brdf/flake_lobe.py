"""The flakes' single-scattering lobe (term 2 of :class:`~nmmm.appearance.brdf.PaintBRDF`):
its directional albedo, by quadrature over the flake normals whose mirror ray leaves the coat.

The pointwise lobe (evaluated per direction pair in :mod:`~nmmm.appearance.brdf.tables` and
:mod:`~nmmm.appearance.brdf.fused_kernel`) is

    f_flake = T_i T_o / n² · τ p(h') R_flake(i'·h') / (4 μi' μo') · (1 − exp(−τ_e S)) / (τ_e S),

S = a(i')/μi' + a(o')/μo' (see the package docstring); for flakes that transmit τ_e S is
τ a(μi')(1 − T̄(μi'))/μi' + τ a(μo')(1 − T̄(μo'))/μo', T̄(μ) their transmission averaged over
the normals a ray along μ meets (``_Tables.optical_path``). In a pigmented coat medium
(:class:`~nmmm.appearance.brdf.CoatMedium`, optical thickness κ, flakes uniform in the band
z0 … z0 + dz of the coat) the last factor becomes the depth average
exp(−κ z0 S') (1 − exp(−X)) / X, X = τ_e S + κ dz S', S' = 1/μi' + 1/μo'.

References
----------
- S. Ershov, K. Kolchin, K. Myszkowski, Computer Graphics Forum 20(3) (2001) 227 —
  flakes as oriented mirrors in a paint layer.
- S. Chandrasekhar, *Radiative Transfer* (1960) — single scattering from a slab.
"""

from __future__ import annotations

import numpy as np

from nmmm.appearance.brdf.interpolation import _deg, _lerp1, _lerp_table, _phi_mean
from nmmm.appearance.flakes import refract_in, refract_out


def flake_single_scattering_albedo(tab, mua, n_theta: int = 24, n_phi: int = 32):
    """External single-scattering flake albedo / T_i, actual and lossless, (NA, L).

    Quadrature over flake normals m (tilt θ_m, azimuth φ_m), restricted for each φ_m
    to the tilts whose mirror ray leaves the coat (θ_m < θ_b(φ_m), found by bisection),
    so that the integrand is smooth (the escape boundary is not cut by the nodes).
    """
    L = tab.L
    if not tab.has_flakes:
        z = np.zeros((mua.size, L))
        return z, z
    n = tab.n
    mu_c = np.sqrt(1 - 1 / (n * n))
    xg, wg = np.polynomial.legendre.leggauss(n_theta)
    ph = (np.arange(n_phi) + 0.5) * np.pi / n_phi  # symmetric in φ: [0, π), weights ×2
    cph, sph = np.cos(ph), np.sin(ph)
    tsup = np.radians(tab.tilt.support_deg)
    out = np.zeros((mua.size, L))
    out0 = np.zeros((mua.size, L))

    def opz(theta, ip):  # o'_z for normals at (theta (…, n_phi), ph)
        st, ct = np.sin(theta), np.cos(theta)
        c = st * cph * ip[0] + ct * ip[2]
        return 2 * c * ct - ip[2], c

    for k, mu in enumerate(mua):
        if mu <= 1e-6:
            continue
        wi = np.array([np.sqrt(1 - mu * mu), 0.0, mu])
        ip = refract_in(wi, n)
        # escape boundary per azimuth: first θ where o'_z <= μ_c (or c <= 0)
        tt = np.linspace(0, tsup, 257)[:, None] * np.ones((1, n_phi))
        oz, c = opz(tt, ip)
        bad = (oz <= mu_c) | (c <= 0)
        first = np.where(bad.any(axis=0), bad.argmax(axis=0), tt.shape[0] - 1)
        hi = tt[first, np.arange(n_phi)]
        lo = tt[np.maximum(first - 1, 0), np.arange(n_phi)]
        hasb = bad.any(axis=0)
        for _ in range(30):
            mid = 0.5 * (lo + hi)
            ozm, cm = opz(mid, ip)
            b = (ozm <= mu_c) | (cm <= 0)
            hi = np.where(b & hasb, mid, hi)
            lo = np.where(b & hasb, lo, mid)
        tb = np.where(hasb, 0.5 * (lo + hi), tsup)  # (n_phi,)
        th = 0.5 * (xg[:, None] + 1) * tb[None, :]  # (n_theta, n_phi)
        wth = 0.5 * wg[:, None] * tb[None, :]
        st, ct = np.sin(th), np.cos(th)
        m = np.stack([st * cph, st * sph, ct], axis=-1).reshape(-1, 3)
        wq = (wth * st * np.interp(np.degrees(th), tab.tilt.tilt_deg, tab.tilt.density)
              * (2 * np.pi / n_phi)).reshape(-1)
        ck = m @ ip
        op = 2 * ck[:, None] * m - ip
        wok, esc = refract_out(op, n)
        ok = esc & (ck > 0) & (wq > 0)
        if not np.any(ok):
            continue
        ck, opk, wok, wk = ck[ok], op[ok], wok[ok], wq[ok]
        To = _lerp_table(tab.Tc, _deg(wok[:, 2]), tab.step)
        kap = getattr(tab, "kappa", None)
        # the flake layer's optical depth in and out (flakes that transmit: per direction and λ); opaque
        # flakes τ_e S as before issue 18, so that their tables stay bit for bit ((a + b) τ_e, not a τ_e + b τ_e)
        if tab.tau_e_const:
            S = (_lerp1(tab.a_tab, _deg(ip[2]), tab.step) / ip[2]
                 + _lerp1(tab.a_tab, _deg(opk[:, 2]), tab.step) / opk[:, 2])
            X = np.outer(S, tab.tau_e)
        else:
            X = tab.optical_path(np.array([ip[2]])) + tab.optical_path(opk[:, 2])  # (K, L)
        if kap is None:  # no pigmented medium: the same attenuation for both
            phi = tab.tau * _phi_mean(X)  # (K, L)
            phi0 = phi
        else:  # flakes uniform in the band z0..z0+dz of a coat of optical thickness κ
            S2 = 1.0 / ip[2] + 1.0 / opk[:, 2]
            phi, phi0 = (tab.tau * np.exp(-np.outer(S2, kv) * tab.z0)
                         * _phi_mean(X + np.outer(S2, kv) * tab.dz)
                         for kv in (tab.kappa, tab.kappa0))
        g = (wk * ck / ip[2])[:, None] * To
        out[k] = np.sum(g * phi * _lerp_table(tab.Rf, _deg(ck), tab.step), axis=0)
        out0[k] = np.sum(g * phi0 * _lerp_table(tab.Rf0, _deg(ck), tab.step), axis=0)
    return out, out0
