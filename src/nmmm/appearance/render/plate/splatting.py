"""Splatting of the glint records onto the image (Numba): records sorted by pixel, one pixel
group per task, each record's spectrum the coat transmission in and out, the flake
reflectance at its local angle, the mean-field attenuation by the flakes above it, the
extinction by the pigments of the coat above it (a pigmented basecoat,
:class:`~nmmm.appearance.brdf.CoatMedium`) and the light's spectrum (``_glint_splat``).
"""

from __future__ import annotations

import math

from nmmm.errors import InvalidInputError

try:  # pragma: no cover - numba is a dependency, but keep a NumPy path
    import numba as _nb
except ImportError:  # pragma: no cover
    _nb = None


def _needs_numba(*args):  # pragma: no cover - only without numba
    raise InvalidInputError("discrete flakes (glints) need numba")


if _nb is not None:
    @_nb.njit(parallel=True, cache=True, fastmath=True)
    def _glint_splat(img, gstart, rec_pix, rec_w, rec_th, rec_li, Tc, Rf, step, tau_e, const_tau, espec, kappa,
                     ext):
        """Add the glint spectra to the image; records sorted by pixel, one pixel group
        per task (no write conflicts, deterministic order). ``const_tau``: τ_e is the same
        at every wavelength and there is no pigment (κ = 0); else each wavelength gets
        exp(−τ_e(λ) S ζ − κ(λ) S' (z0 + dz ζ)) (``rec_th[:, 3]`` = S ζ, ``rec_th[:, 4]`` =
        S' (z0 + dz ζ)), the flake term of :mod:`nmmm.appearance.brdf.effect_tables` per flake.
        Flakes that transmit (``rec_th`` of 9 columns): τ_e S ζ becomes the extinction per
        direction of the BRDF, ζ (ε(θi')/μi' + ε(θo')/μo'), ε = ``ext`` (NT, L) = τ a(μ) (1 − T̄(μ, λ))
        (``_Tables.ext_tab``, interpolated as in the BRDF's kernels; ``rec_th[:, 5:9]`` = θi', θo',
        ζ/μi', ζ/μo')."""
        L = img.shape[1]
        nt = Tc.shape[0]
        ng = gstart.size - 1
        transmit = rec_th.shape[1] > 5
        for gi in _nb.prange(ng):
            for r in range(gstart[gi], gstart[gi + 1]):
                p = rec_pix[r]
                x0 = rec_th[r, 0] / step
                x1 = rec_th[r, 1] / step
                x2 = rec_th[r, 2] / step
                a0 = min(int(x0), nt - 2)
                a1 = min(int(x1), nt - 2)
                a2 = min(int(x2), nt - 2)
                f0 = min(x0 - a0, 1.0)
                f1 = min(x1 - a1, 1.0)
                f2 = min(x2 - a2, 1.0)
                wgt = rec_w[r]
                sz = rec_th[r, 3]
                sk = rec_th[r, 4]
                li = rec_li[r]
                if const_tau:
                    wgt *= math.exp(-tau_e[0] * sz)
                    for l in range(L):
                        ti = Tc[a0, l] * (1 - f0) + Tc[a0 + 1, l] * f0
                        to = Tc[a1, l] * (1 - f1) + Tc[a1 + 1, l] * f1
                        rf = Rf[a2, l] * (1 - f2) + Rf[a2 + 1, l] * f2
                        img[p, l] += wgt * ti * to * rf * espec[li, l]
                elif transmit:
                    x3 = rec_th[r, 5] / step
                    x4 = rec_th[r, 6] / step
                    a3 = min(int(x3), nt - 2)
                    a4 = min(int(x4), nt - 2)
                    f3 = min(x3 - a3, 1.0)
                    f4 = min(x4 - a4, 1.0)
                    zi = rec_th[r, 7]
                    zo = rec_th[r, 8]
                    for l in range(L):
                        ti = Tc[a0, l] * (1 - f0) + Tc[a0 + 1, l] * f0
                        to = Tc[a1, l] * (1 - f1) + Tc[a1 + 1, l] * f1
                        rf = Rf[a2, l] * (1 - f2) + Rf[a2 + 1, l] * f2
                        xf = ((ext[a3, l] * (1 - f3) + ext[a3 + 1, l] * f3) * zi
                              + (ext[a4, l] * (1 - f4) + ext[a4 + 1, l] * f4) * zo)
                        img[p, l] += wgt * ti * to * rf * math.exp(-xf - kappa[l] * sk) * espec[li, l]
                else:
                    for l in range(L):
                        ti = Tc[a0, l] * (1 - f0) + Tc[a0 + 1, l] * f0
                        to = Tc[a1, l] * (1 - f1) + Tc[a1 + 1, l] * f1
                        rf = Rf[a2, l] * (1 - f2) + Rf[a2 + 1, l] * f2
                        img[p, l] += wgt * ti * to * rf * math.exp(-tau_e[l] * sz - kappa[l] * sk) * espec[li, l]
else:  # pragma: no cover
    _glint_splat = _needs_numba
