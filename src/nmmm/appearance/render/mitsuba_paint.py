"""nmmm's paint BRDF as a Mitsuba 3 BSDF plugin (``nmmm_paint``), evaluated spectrally.

Mitsuba 3 is an optional extra: ``pip install 'nmmm[mitsuba]'``; its ``llvm_ad_spectral``
variant JIT-compiles through the system libLLVM. **Dr.Jit ≥ 1.0 needs libLLVM ≥ 17 on
x86-64** (libLLVM 15/16 abort with "Cannot select: fmaximum"): on Debian 12,
``apt-get install libllvm19`` (or point ``DRJIT_LIBLLVM_PATH`` at a recent libLLVM).

The plugin tabulates any nmmm BRDF (a :class:`~nmmm.appearance.brdf.PaintBRDF`, smooth
terms: coat lobe, statistical flakes, diffuse base, multiple scattering) once in
Rusinkiewicz coordinates (θ_h on a square-root grid, θ_d, φ_d folded to [0°, 90°] by
isotropy and reciprocity) on the rendering wavelength grid, and compresses the spectra on
a few basis spectra (SVD, ``rank`` ≤ 8 — the relative residual is reported):

    f(θ_h, θ_d, φ_d, λ) ≈ Σ_k c_k(θ_h, θ_d, φ_d) B_k(λ)

The coefficients live in a trilinear ``Texture3f`` and the basis spectra in a
``Texture1f`` over wavelength, so each of Mitsuba's sampled wavelengths gets its own value
(a true spectral BSDF, not RGB). A smooth clear coat's mirror reflection is a Dirac lobe
weighted by the Fresnel reflectance F(θ, λ) (a 2-D texture). Sampling: the Dirac with
probability ≈ F̄(θi), otherwise a cosine-weighted hemisphere (unbiased for the glossy
flake lobe, though noisier than a lobe-matched sampler).

In Mitsuba's **polarized** spectral variants (``*_spectral_polarized``) the BSDF returns Mueller
matrices: the smooth coat's Dirac is the reflection matrix of
:func:`nmmm.appearance.brdf.mueller.coat_reflection_mueller` (nmmm's r_s, r_p, tabulated over θ and
λ as ratios to F: (Rs−Rp)/(Rs+Rp), 2Re(rp rs*)/(Rs+Rp), 2Im(rp rs*)/(Rs+Rp)), rotated from the plane
of incidence to Mitsuba's Stokes bases as its ``conductor`` plugin does; the tabulated glossy and
diffuse terms are returned as **depolarizers** (the diffuse body and the MS lobe depolarize; the
rough coat's and the flakes' own polarization is modelled by nmmm's plate renderer,
:mod:`nmmm.appearance.render.plate.stokes`, not by this plugin).

Public objects
--------------
- :func:`require_mitsuba` — import Mitsuba, choose the variant, with clear errors.
- :class:`MitsubaUnavailableError`
- :func:`register_nmmm_plugins` — register ``nmmm_paint`` (once per variant).
- :func:`paint_table` — the tabulated, spectrally compressed BRDF (NumPy; testable alone).
- :func:`paint_bsdf` — a Mitsuba scene-dictionary entry ``{"type": "nmmm_paint", ...}``.
- :func:`rusinkiewicz_coordinates` — (θ_h, θ_d, φ_d) of direction pairs (NumPy).

References
----------
- W. Jakob, S. Speierer, N. Roussel, M. Nimier-David, D. Vicini, T. Zeltner, B. Nicolet,
  M. Crespo, V. Leroy, Z. Zhang, "Mitsuba 3 renderer" (2022), https://mitsuba-renderer.org —
  Python plugins (``mi.register_bsdf``), spectral variants.
- S. Rusinkiewicz, "A new change of variables for efficient BRDF representation", EGWR 1998.
- W. Matusik, H. Pfister, M. Brand, L. McMillan, ACM TOG 22(3) (2003) 759 — tabulated
  isotropic BRDFs (θ_h on a square-root grid).
"""

from __future__ import annotations

import glob
import os
import re
import uuid

import numpy as np

from nmmm.errors import InvalidInputError, NmmmError

__all__ = [
    "MitsubaUnavailableError",
    "require_mitsuba",
    "register_nmmm_plugins",
    "paint_table",
    "paint_bsdf",
    "rusinkiewicz_coordinates",
    "SUPPORTED_VARIANTS",
    "INSTALL_HINT",
]

SUPPORTED_VARIANTS = ("llvm_ad_spectral", "scalar_spectral", "cuda_ad_spectral", "llvm_ad_spectral_polarized",
                      "scalar_spectral_polarized", "cuda_ad_spectral_polarized")
INSTALL_HINT = ("pip install 'nmmm[mitsuba]'; and for the LLVM variants a system libLLVM >= 17, "
                "e.g. apt-get install libllvm19 (Dr.Jit >= 1.0 cannot use libLLVM 15/16: 'Cannot select fmaximum')")
_MIN_LLVM = 17
_TABLES: dict = {}
_REGISTERED: set = set()


class MitsubaUnavailableError(NmmmError, ImportError):
    """Mitsuba 3 (or the libLLVM its LLVM variants need) is missing or unusable."""


def _llvm_versions() -> list[tuple[int, str]]:
    path = os.environ.get("DRJIT_LIBLLVM_PATH")
    cands = [path] if path else []
    for d in ("/usr/lib/x86_64-linux-gnu", "/usr/lib64", "/usr/lib", "/usr/local/lib", "/opt/homebrew/opt/llvm/lib",
              "/usr/lib/aarch64-linux-gnu"):
        cands += glob.glob(os.path.join(d, "libLLVM*.so*")) + glob.glob(os.path.join(d, "libLLVM*.dylib"))
        cands += glob.glob(os.path.join(d, "llvm-*", "lib", "libLLVM*.so*"))
    out = []
    for c in cands:
        m = re.search(r"LLVM[-.]?(?:so\.)?(\d+)", os.path.basename(c)) or re.search(r"llvm-(\d+)", c)
        if m:
            out.append((int(m.group(1)), c))
    return out


def require_mitsuba(variant: str = "llvm_ad_spectral"):
    """Import Mitsuba 3, set ``variant`` (a spectral one) and return the module.

    Raises :class:`MitsubaUnavailableError` saying what to install when Mitsuba or a
    suitable libLLVM is missing, :class:`InvalidInputError` for an unsupported variant.
    """
    if variant not in SUPPORTED_VARIANTS:
        raise InvalidInputError(
            f"unsupported Mitsuba variant {variant!r}: nmmm's paint BSDF is spectral; use one of {SUPPORTED_VARIANTS}"
        )
    try:
        import mitsuba as mi
    except ImportError as exc:
        raise MitsubaUnavailableError(f"Mitsuba 3 is not installed ({exc}): pip install 'nmmm[mitsuba]' "
                                      f"(its LLVM variant also needs libLLVM >= {_MIN_LLVM}: apt-get install libllvm19)"
                                      ) from exc
    if variant.startswith("llvm"):
        found = _llvm_versions()
        if not found or max(v for v, _ in found) < _MIN_LLVM:
            have = ", ".join(sorted({f"{v}" for v, _ in found})) or "none"
            raise MitsubaUnavailableError(
                f"Mitsuba's {variant} variant needs libLLVM >= {_MIN_LLVM} (found: {have}): apt-get install libllvm19 "
                f"(or point DRJIT_LIBLLVM_PATH at a libLLVM >= {_MIN_LLVM}; Dr.Jit >= 1.0 fails on 15/16 with "
                "'Cannot select fmaximum'), or use the slow variant 'scalar_spectral'"
            )
    if variant not in mi.variants():
        raise MitsubaUnavailableError(f"this Mitsuba build lacks the {variant!r} variant (has {mi.variants()}); "
                                      f"{INSTALL_HINT}")
    try:
        mi.set_variant(variant)
    except Exception as exc:  # noqa: BLE001 - Dr.Jit raises plain exceptions when libLLVM is missing
        raise MitsubaUnavailableError(f"cannot start Mitsuba variant {variant!r}: {exc}; {INSTALL_HINT}") from exc
    return mi


# --------------------------------------------------------------------------------------
# tabulation (NumPy)


def rusinkiewicz_coordinates(wi, wo):
    """(θ_h, θ_d, φ_d) in radians of unit direction pairs (..., 3), φ_d folded to
    [0, π/2] (isotropic, reciprocal BRDFs)."""
    wi = np.asarray(wi, float)
    wo = np.asarray(wo, float)
    h = wi + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    th = np.arccos(np.clip(h[..., 2], -1, 1))
    ph = np.arctan2(h[..., 1], h[..., 0])
    c, s = np.cos(ph), np.sin(ph)
    x = wi[..., 0] * c + wi[..., 1] * s
    y = -wi[..., 0] * s + wi[..., 1] * c
    z = wi[..., 2]
    ct, st = np.cos(th), np.sin(th)
    dx = x * ct - z * st
    dz = x * st + z * ct
    td = np.arccos(np.clip(dz, -1, 1))
    pd = np.abs(np.arctan2(y, dx))
    pd = np.where(pd > np.pi / 2, np.pi - pd, pd)
    return th, td, pd


def _directions(th, td, pd):
    """Inverse of :func:`rusinkiewicz_coordinates` with φ_h = 0 -> (wi, wo)."""
    d = np.stack([np.sin(td) * np.cos(pd), np.sin(td) * np.sin(pd), np.cos(td)], axis=-1)
    ct, st = np.cos(th)[..., None], np.sin(th)[..., None]

    def rot_y(v):  # rotate by +θ_h about y
        return np.stack([v[..., 0] * ct[..., 0] + v[..., 2] * st[..., 0], v[..., 1],
                         -v[..., 0] * st[..., 0] + v[..., 2] * ct[..., 0]], axis=-1)

    wi = rot_y(d)
    dm = d * np.array([-1.0, -1.0, 1.0])
    wo = rot_y(dm)
    return wi, wo


def paint_table(brdf, wavelength_nm=None, n_theta_h: int = 48, n_theta_d: int = 48, n_phi_d: int = 12,
                rank: int = 8) -> dict:
    """Tabulate ``brdf`` (without the Dirac) on a (φ_d, θ_d, θ_h) grid and compress its
    spectra on ``rank`` basis spectra. Returns a dict of NumPy arrays: ``coeff``
    (n_phi_d, n_theta_d, n_theta_h, rank), ``basis`` (L, rank), ``wavelength_nm``,
    ``fresnel`` (L, 91) (Dirac weight over θ 0..90°, zeros for a rough coat),
    ``fresnel_mean`` (91,), ``residual`` (relative Frobenius residual of the compression)."""
    from nmmm.appearance.render.lights import default_wavelengths

    w = default_wavelengths() if wavelength_nm is None else np.asarray(wavelength_nm, float).ravel()
    if min(n_theta_h, n_theta_d, n_phi_d) < 2:
        raise InvalidInputError("table sizes must be >= 2")
    s = np.linspace(0, 1, n_theta_h)
    th = s * s * (np.pi / 2)
    td = np.linspace(0, np.pi / 2, n_theta_d)
    pd = np.linspace(0, np.pi / 2, n_phi_d)
    P, D, H = np.meshgrid(pd, td, th, indexing="ij")
    wi, wo = _directions(H, D, P)
    ok = (wi[..., 2] > 1e-4) & (wo[..., 2] > 1e-4)
    L = w.size
    vals = np.zeros(P.shape + (L,))
    comps = ("specular", "flakes", "base", "multiple")
    try:
        f = brdf.evaluate(w, wi[ok], wo[ok], components=comps)
    except TypeError:
        f = brdf.evaluate(w, wi[ok], wo[ok])
    vals[ok] = f
    M = vals.reshape(-1, L)
    U, S, Vt = np.linalg.svd(M, full_matrices=False)
    k = int(min(rank, L))
    basis = Vt[:k].T  # (L, k)
    coeff = M @ basis
    resid = float(np.linalg.norm(M - coeff @ basis.T) / max(np.linalg.norm(M), 1e-30))
    thd = np.radians(np.linspace(0, 90, 91))
    mu = np.cos(thd)[:, None] * np.ones((1, 3))
    mu[:, 0] = np.sin(thd)
    mu[:, 1] = 0.0
    pol = np.zeros((L, 91, 3))
    if hasattr(brdf, "specular_reflectance"):
        F = np.asarray(brdf.specular_reflectance(w, np.clip(mu, 0, 1)), float)  # (91, L)
        if np.any(F > 0) and hasattr(brdf, "coat"):
            from nmmm.appearance.brdf.mueller import coat_reflection_mueller

            M = coat_reflection_mueller(brdf.coat, w, np.clip(mu[:, 2], 0, 1))  # (91, L, 4, 4)
            a = np.maximum(M[..., 0, 0], 1e-30)
            pol = np.moveaxis(np.stack([M[..., 1, 0] / a, M[..., 2, 2] / a, M[..., 3, 2] / a], -1), 0, 1)
    else:
        F = np.zeros((91, L))
    return {
        "wavelength_nm": w,
        "coeff": coeff.reshape(P.shape + (k,)).astype(np.float32),
        "basis": basis.astype(np.float32),
        "fresnel": np.ascontiguousarray(F.T, dtype=np.float32),
        "fresnel_mean": F.mean(axis=1).astype(np.float32),
        "fresnel_polarization": np.ascontiguousarray(pol, dtype=np.float32),
        "residual": resid,
        "name": getattr(brdf, "name", "paint"),
    }


def paint_bsdf(brdf, **table_kwargs) -> dict:
    """A Mitsuba scene-dictionary entry for ``brdf``: ``{"type": "nmmm_paint", "table": key}``
    (the table is kept in this module's registry under ``key``)."""
    tab = paint_table(brdf, **table_kwargs)
    key = uuid.uuid4().hex[:12]
    _TABLES[key] = tab
    return {"type": "nmmm_paint", "table": key}


# --------------------------------------------------------------------------------------
# the plugin


def register_nmmm_plugins(mi=None):
    """Register the ``nmmm_paint`` BSDF with the current Mitsuba variant (idempotent)."""
    if mi is None:
        mi = require_mitsuba()
    variant = mi.variant()
    if variant in _REGISTERED:
        return
    import drjit as dr

    class NmmmPaintBSDF(mi.BSDF):
        """nmmm paint BRDF, tabulated + spectral basis (see module docstring)."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            key = props.get("table", None) if hasattr(props, "get") else props["table"]
            if key not in _TABLES:
                raise InvalidInputError(f"nmmm_paint: unknown table key {key!r}; build the entry with paint_bsdf(brdf)")
            t = _TABLES[key]
            self.name = t["name"]
            w = t["wavelength_nm"]
            self.l0 = float(w[0])
            self.l1 = float(w[-1])
            self.nl = int(w.size)
            c = t["coeff"]
            self.k = int(c.shape[-1])
            self.shape = c.shape[:3]
            self.coeff = mi.Texture3f(mi.TensorXf(np.ascontiguousarray(c)))
            self.basis = mi.Texture1f(mi.TensorXf(np.ascontiguousarray(t["basis"][:, :])))
            self.has_delta = bool(np.any(t["fresnel"] > 0))
            self.fres = mi.Texture2f(mi.TensorXf(np.ascontiguousarray(t["fresnel"][:, :, None])))
            self.fmean = mi.Texture1f(mi.TensorXf(np.ascontiguousarray(t["fresnel_mean"][:, None])))
            pol = t.get("fresnel_polarization", np.zeros(t["fresnel"].shape + (3,), np.float32))
            self.fpol = mi.Texture2f(mi.TensorXf(np.ascontiguousarray(pol)))
            glossy = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            delta = mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide
            self.m_components = [glossy, delta] if self.has_delta else [glossy]
            self.m_flags = (glossy | delta) if self.has_delta else glossy

        # -- helpers ------------------------------------------------------------------
        def _u(self, x, n):
            return (x * (n - 1) + 0.5) / n

        def _ulam(self, lam):
            return self._u(dr.clip((lam - self.l0) / (self.l1 - self.l0), 0.0, 1.0), self.nl)

        def _spectral(self, coeffs, wavelengths):
            vals = []
            for j in range(4):
                b = self.basis.eval(mi.Point1f(self._ulam(wavelengths[j])))
                acc = mi.Float(0.0)
                for q in range(self.k):
                    acc += coeffs[q] * b[q]
                vals.append(dr.maximum(acc, 0.0))
            return mi.UnpolarizedSpectrum(vals[0], vals[1], vals[2], vals[3])

        def _f(self, si, wo):
            wi = si.wi
            h = dr.normalize(wi + wo)
            th = dr.safe_acos(h.z)
            ph = dr.atan2(h.y, h.x)
            c, s = dr.cos(ph), dr.sin(ph)
            x = wi.x * c + wi.y * s
            y = -wi.x * s + wi.y * c
            ct, st = dr.cos(th), dr.sin(th)
            dx = x * ct - wi.z * st
            dz = x * st + wi.z * ct
            td = dr.safe_acos(dz)
            pd = dr.abs(dr.atan2(y, dx))
            pd = dr.select(pd > dr.pi / 2, dr.pi - pd, pd)
            nph, ntd, nth = self.shape
            u = mi.Point3f(self._u(dr.safe_sqrt(th / (dr.pi / 2)), nth), self._u(td / (dr.pi / 2), ntd),
                           self._u(pd / (dr.pi / 2), nph))
            return self._spectral(self.coeff.eval(u), si.wavelengths)

        def _p_delta(self, cos_i):
            if not self.has_delta:
                return mi.Float(0.0)
            th = dr.safe_acos(cos_i) / (dr.pi / 2)
            return dr.clip(self.fmean.eval(mi.Point1f(self._u(th, 91)))[0], 0.02, 0.98)

        def _fresnel(self, cos_i, wavelengths):
            th = self._u(dr.safe_acos(cos_i) / (dr.pi / 2), 91)
            vals = [self.fres.eval(mi.Point2f(th, self._ulam(wavelengths[j])))[0] for j in range(4)]
            return mi.UnpolarizedSpectrum(vals[0], vals[1], vals[2], vals[3])

        def _dirac_mueller(self, ctx, si, wo, cos_i):
            """The coat's mirror reflection as a Mueller matrix in Mitsuba's Stokes bases."""
            F = self._fresnel(cos_i, si.wavelengths)
            th = self._u(dr.safe_acos(cos_i) / (dr.pi / 2), 91)
            r = [self.fpol.eval(mi.Point2f(th, self._ulam(si.wavelengths[j]))) for j in range(4)]
            b, c, s = (mi.UnpolarizedSpectrum(r[0][q], r[1][q], r[2][q], r[3][q]) * F for q in range(3))
            z = mi.UnpolarizedSpectrum(0.0)
            M = mi.Spectrum(F, b, z, z, b, F, z, z, z, z, c, -s, z, z, s, c)
            radiance = ctx.mode == mi.TransportMode.Radiance
            wo_hat, wi_hat = (wo, si.wi) if radiance else (si.wi, wo)
            n = mi.Vector3f(0, 0, 1)
            s_in, s_out = dr.cross(n, -wo_hat), dr.cross(n, wi_hat)
            collinear = dr.all(dr.abs(s_in) < 1e-7)
            s_in = dr.select(collinear, mi.Vector3f(1, 0, 0), dr.normalize(s_in))
            s_out = dr.select(collinear, mi.Vector3f(1, 0, 0), dr.normalize(s_out))
            return mi.mueller.rotate_mueller_basis(M, -wo_hat, s_in, mi.mueller.stokes_basis(-wo_hat),
                                                   wi_hat, s_out, mi.mueller.stokes_basis(wi_hat))

        # -- BSDF interface ---------------------------------------------------------------
        def sample(self, ctx, si, sample1, sample2, active=True):
            cos_i = mi.Frame3f.cos_theta(si.wi)
            active = active & (cos_i > 0)
            p_d = self._p_delta(cos_i)
            pick_delta = sample1 < p_d
            bs = mi.BSDFSample3f()
            wo_d = mi.reflect(si.wi)
            wo_c = mi.warp.square_to_cosine_hemisphere(sample2)
            bs.wo = dr.select(pick_delta, wo_d, wo_c)
            pdf_c = mi.warp.square_to_cosine_hemisphere_pdf(wo_c) * (1 - p_d)
            bs.pdf = dr.select(pick_delta, p_d, pdf_c)
            bs.eta = 1.0
            bs.sampled_component = dr.select(pick_delta, mi.UInt32(1), mi.UInt32(0))
            bs.sampled_type = dr.select(pick_delta, mi.UInt32(+mi.BSDFFlags.DeltaReflection),
                                        mi.UInt32(+mi.BSDFFlags.GlossyReflection))
            f = self._f(si, wo_c) * mi.Frame3f.cos_theta(wo_c) / dr.maximum(pdf_c, 1e-12)
            if mi.is_polarized:
                f = mi.depolarizer(f)
                fd = self._dirac_mueller(ctx, si, wo_d, cos_i) / dr.maximum(p_d, 1e-12)
            else:
                fd = self._fresnel(cos_i, si.wavelengths) / dr.maximum(p_d, 1e-12)
            value = dr.select(pick_delta, fd, f)
            ok = active & (bs.pdf > 0) & (mi.Frame3f.cos_theta(bs.wo) > 0)
            return bs, dr.select(ok, value, 0.0)

        def eval(self, ctx, si, wo, active=True):
            ok = active & (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)
            value = self._f(si, wo) * mi.Frame3f.cos_theta(wo)
            if mi.is_polarized:
                value = mi.depolarizer(value)
            return dr.select(ok, value, 0.0)

        def pdf(self, ctx, si, wo, active=True):
            cos_i = mi.Frame3f.cos_theta(si.wi)
            ok = active & (cos_i > 0) & (mi.Frame3f.cos_theta(wo) > 0)
            p = mi.warp.square_to_cosine_hemisphere_pdf(wo) * (1 - self._p_delta(cos_i))
            return dr.select(ok, p, 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def traverse(self, callback):
            pass

        def parameters_changed(self, keys):
            pass

        def to_string(self):
            return f"NmmmPaintBSDF[{self.name}, rank {self.k}, table {self.shape}]"

    mi.register_bsdf("nmmm_paint", lambda props: NmmmPaintBSDF(props))
    _REGISTERED.add(variant)
