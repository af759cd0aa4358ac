"""CIEDE2000 as a residual vector, and the special metamerism index for a change of illuminant.

- :func:`delta_e2000_residuals` — a 3-vector per pair whose Euclidean norm *is* ΔE00
  (Sharma, Wu & Dalal 2005), for least-squares matching:
  ``(ΔL'/kL SL, ΔC'/kC SC + ½RT ΔH'/kH SH, √(1 − RT²/4) ΔH'/kH SH)`` — the square of its norm
  expands to ΔE00² = (ΔL'/SL)² + (ΔC'/SC)² + (ΔH'/SH)² + RT (ΔC'/SC)(ΔH'/SH), and |RT| ≤ 2.
- :func:`metamerism_index` — the CIE special metamerism index for a change in illuminant
  (CIE 15:2004 §9.2.2; ISO 18314-4:2015): the colour difference of a pair under a test
  illuminant after the pair's difference under the reference illuminant is removed by the
  *additive* correction in CIELAB (Lab*_test(sample) − [Lab*_ref(sample) − Lab*_ref(standard)]),
  with ΔE00 as the difference formula (stated, as CIE 15 asks). A pair matched exactly under the
  reference gives the plain ΔE00 under the test illuminant; an isomeric pair gives 0.

References
----------
- G. Sharma, W. Wu, E. N. Dalal, "The CIEDE2000 color-difference formula: implementation notes,
  supplementary test data, and mathematical observations", Color Res. Appl. 30, 21 (2005).
  doi:10.1002/col.20070
- CIE 15:2004 Colorimetry, 3rd ed., §9.2 (special metamerism indices).
- ISO 18314-4:2015 Analytical colorimetry — Part 4: Metamerism index for pairs of samples for change of
  illuminant.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["delta_e2000_residuals", "metamerism_index", "delta_lch"]


def delta_e2000_residuals(lab_reference: ArrayLike, lab: ArrayLike, kL: float = 1.0, kC: float = 1.0,
                          kH: float = 1.0) -> np.ndarray:
    """(..., 3) residuals whose norm is CIEDE2000 (module docstring), Sharma et al. 2005 eqs. 1–22."""
    a = np.asarray(lab_reference, float)
    b = np.asarray(lab, float)
    L1, a1, b1 = a[..., 0], a[..., 1], a[..., 2]
    L2, a2, b2 = b[..., 0], b[..., 1], b[..., 2]
    Cbar = (np.hypot(a1, b1) + np.hypot(a2, b2)) / 2
    G = 0.5 * (1 - np.sqrt(Cbar**7 / (Cbar**7 + 25.0**7)))
    a1p, a2p = (1 + G) * a1, (1 + G) * a2
    C1p, C2p = np.hypot(a1p, b1), np.hypot(a2p, b2)
    h1p = np.degrees(np.arctan2(b1, a1p)) % 360
    h2p = np.degrees(np.arctan2(b2, a2p)) % 360
    dLp = L2 - L1
    dCp = C2p - C1p
    dh = h2p - h1p
    dh = np.where(dh > 180, dh - 360, np.where(dh < -180, dh + 360, dh))
    dh = np.where(C1p * C2p == 0, 0.0, dh)
    dHp = 2 * np.sqrt(C1p * C2p) * np.sin(np.radians(dh) / 2)
    Lbp = (L1 + L2) / 2
    Cbp = (C1p + C2p) / 2
    hsum = h1p + h2p
    hbp = np.where(np.abs(h1p - h2p) > 180, np.where(hsum < 360, hsum + 360, hsum - 360) / 2, hsum / 2)
    hbp = np.where(C1p * C2p == 0, hsum, hbp)
    T = (1 - 0.17 * np.cos(np.radians(hbp - 30)) + 0.24 * np.cos(np.radians(2 * hbp))
         + 0.32 * np.cos(np.radians(3 * hbp + 6)) - 0.20 * np.cos(np.radians(4 * hbp - 63)))
    dtheta = 30 * np.exp(-(((hbp - 275) / 25) ** 2))
    RC = 2 * np.sqrt(Cbp**7 / (Cbp**7 + 25.0**7))
    SL = 1 + 0.015 * (Lbp - 50) ** 2 / np.sqrt(20 + (Lbp - 50) ** 2)
    SC = 1 + 0.045 * Cbp
    SH = 1 + 0.015 * Cbp * T
    RT = -np.sin(np.radians(2 * dtheta)) * RC
    l, c, h = dLp / (kL * SL), dCp / (kC * SC), dHp / (kH * SH)
    return np.stack([l, c + 0.5 * RT * h, np.sqrt(np.clip(1 - RT**2 / 4, 0, None)) * h], axis=-1)


def delta_lch(lab_reference: ArrayLike, lab: ArrayLike) -> np.ndarray:
    """(..., 3) ΔL*, ΔC*ab, ΔH*ab of ``lab`` against ``lab_reference`` (CIE 15:2004 §8.2.2)."""
    a = np.asarray(lab_reference, float)
    b = np.asarray(lab, float)
    dL = b[..., 0] - a[..., 0]
    dC = np.hypot(b[..., 1], b[..., 2]) - np.hypot(a[..., 1], a[..., 2])
    dE2 = np.sum((b - a) ** 2, axis=-1)
    dH = np.sqrt(np.clip(dE2 - dL**2 - dC**2, 0, None))
    cross = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]  # sign of the hue change
    return np.stack([dL, dC, np.where(cross < 0, -dH, dH)], axis=-1)


def metamerism_index(wavelength_nm: ArrayLike, standard: ArrayLike, sample: ArrayLike, test_illuminant: str = "A",
                     reference_illuminant: str = "D65", observer: str = "2") -> np.ndarray:
    """CIE special metamerism index (change in illuminant), ΔE00, additive CIELAB correction
    (module docstring). Broadcasts over leading axes of ``sample``."""
    from nmmm.colour import delta_e2000, spectra_to_lab

    w = np.asarray(wavelength_nm, float)
    std, smp = np.asarray(standard, float), np.asarray(sample, float)
    lab_std_r = spectra_to_lab(w, std, reference_illuminant, observer)
    lab_smp_r = spectra_to_lab(w, smp, reference_illuminant, observer)
    lab_std_t = spectra_to_lab(w, std, test_illuminant, observer)
    lab_smp_t = spectra_to_lab(w, smp, test_illuminant, observer)
    corrected = lab_smp_t - (lab_smp_r - lab_std_r)
    if np.any(corrected[..., 0] < 0):  # said, then clipped (CIELAB has no L* < 0)
        import warnings

        worst = float(np.min(corrected[..., 0]))
        warnings.warn(f"metamerism index: the additive correction takes the sample's L* under {test_illuminant} to "
                      f"{worst:.2f} < 0 (clipped to 0) — the pair differs too much under {reference_illuminant} (the "
                      "correction assumes a near match there, ISO 18314-4), so this is not a metamerism index; match the "
                      "pair first", stacklevel=2)
        corrected[..., 0] = np.clip(corrected[..., 0], 0, None)
    return np.asarray(delta_e2000(np.broadcast_to(lab_std_t, corrected.shape), corrected))
