"""Causality of effective media: n and k of a mixture change together (Kramers–Kronig).

- :func:`kk_check_mixture` — the Kramers–Kronig consistency report
  (:func:`nmmm.materials.kramers_kronig.kk_consistency`) of an effective medium, of its host,
  and of a *counterfactual* medium that takes the mixture's absorption k but keeps the host's
  index n — what a model that "adds colour without changing the index" would assume.
- :func:`kk_index_change` — the sharper test: the change of n caused by the inclusions,
  Δn = n_mix − n_host, against the Kramers–Kronig transform of the change of k, Δk. Both
  materials' own truncation errors cancel in the difference (the transform is linear).

Notes
-----
Maxwell Garnett and Bruggeman are rational functions of the phase permittivities whose
poles lie in the lower half of the complex frequency plane when the phases' do (they are
Herglotz/Stieltjes functions, Bergman 1978; Milton 1981), so a mixture of causal materials is
causal: its n and k obey the Kramers–Kronig relations. The seed's gold-ruby glass makes the
point visible: the plasmon absorption band near 530 nm comes with a dispersive swing of n
around it. The counterfactual medium fails the check by about the size of that swing.

References
----------
- H. A. Kramers (1927); R. de L. Kronig (1926); F. Wooten, Optical Properties of Solids (1972), §6.4.
- D. J. Bergman, "The dielectric constant of a composite material — a problem in classical
  physics", Phys. Rep. 43, 377 (1978).
- G. W. Milton, J. Appl. Phys. 52, 5286 (1981).
"""

from __future__ import annotations

import numpy as np

from dataclasses import dataclass

from nmmm.materials.material import HC_EV_NM, DerivedMaterial, Material, nk_to_eps


def kk_check_mixture(mixture: Material, host: Material, wavelength_nm=None, n_points: int = 1500) -> dict:
    """Kramers–Kronig reports of ``mixture``, ``host`` and the counterfactual "host n + mixture k".

    Returns ``{"mixture": KKReport, "host": KKReport, "decoupled": KKReport,
    "decoupled_material": Material}``; see :class:`nmmm.materials.kramers_kronig.KKReport`
    (``.max_abs``, ``.rms``, ``.consistent(tolerance)``).
    """
    from nmmm.materials.kramers_kronig import kk_consistency

    def eps_decoupled(w):
        return nk_to_eps(host.nk(w).real + 1j * mixture.nk(w).imag)

    decoupled = DerivedMaterial(
        name=f"{host.name} n with {mixture.name} k (non-causal counterfactual)",
        eps_function=eps_decoupled, components=(mixture, host),
        reference="counterfactual: absorption added without changing the index")
    kw = dict(wavelength_nm=wavelength_nm, n_points=n_points)
    return {
        "mixture": kk_consistency(mixture, **kw),
        "host": kk_consistency(host, **kw),
        "decoupled": kk_consistency(decoupled, **kw),
        "decoupled_material": decoupled,
    }


@dataclass(frozen=True)
class KKChange:
    """Result of :func:`kk_index_change` on the wavelengths of ``band_nm``.

    ``delta_n_kk`` is the KK transform of Δk plus a fitted background c0 + c2·E² (absorption
    changes outside the data range). ``swing`` is the peak-to-peak of Δn, ``residual_max``
    the largest |Δn − Δn_KK|; ``relative_error`` their ratio. A model that changed k without
    n would have Δn = 0, hence a relative error of about 1.
    """

    wavelength_nm: np.ndarray
    delta_n: np.ndarray
    delta_k: np.ndarray
    delta_n_kk: np.ndarray
    swing: float
    residual_max: float

    @property
    def relative_error(self) -> float:
        return self.residual_max / self.swing if self.swing > 0 else 0.0


def kk_index_change(mixture: Material, host: Material, band_nm=(380.0, 780.0), n_points: int = 3000) -> KKChange:
    """Compare the index change Δn caused by inclusions with the KK transform of Δk.

    The transform (:func:`nmmm.materials.kramers_kronig.n_from_k`, exact for piecewise-linear
    data) runs over the mixture's whole wavelength range on ``n_points`` energies; the
    comparison is reported on ``band_nm``.
    """
    from nmmm.materials.kramers_kronig import n_from_k

    lo, hi = mixture.range_nm
    hi = hi if np.isfinite(hi) else 20000.0
    E = np.linspace(HC_EV_NM / hi, HC_EV_NM / max(lo, 1.0), n_points)
    w = HC_EV_NM / E
    dnk = mixture.nk(w) - host.nk(w)
    dn, dk = dnk.real, dnk.imag
    dn_kk = n_from_k(dk, w, n_inf=0.0)
    band = (w >= band_nm[0]) & (w <= band_nm[1])
    basis = np.stack([np.ones(band.sum()), E[band] ** 2], -1)
    coef, *_ = np.linalg.lstsq(basis, (dn - dn_kk)[band], rcond=None)
    dn_kk_b = dn_kk[band] + basis @ coef
    order = np.argsort(w[band])
    res = np.abs(dn[band] - dn_kk_b)
    return KKChange(w[band][order], dn[band][order], dk[band][order], dn_kk_b[order],
                    float(np.ptp(dn[band])), float(res.max()))


__all__ = ["KKChange", "kk_check_mixture", "kk_index_change"]
