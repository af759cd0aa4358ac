"""Colour differences between CIELAB coordinates, and tolerances.

- :func:`delta_e2000` — the CIEDE2000 colour difference, broadcasting.
- :func:`delta_e` — a colour difference by name (:data:`DELTA_E_METHODS`): ``"CIE 1976"`` (ΔE*ab),
  ``"CIE 1994"`` (ΔE94, graphic arts or ``textiles=True``), ``"CMC"`` (CMC(l:c), ``l``, ``c``),
  ``"CIE 2000"`` (ΔE00 with parametric factors ``kL``, ``kC``, ``kH``), all through colour-science.
- :func:`delta_lch` — the ΔL*, ΔC*ab, ΔH*ab decomposition (CIE 15:2004 §8.2.2).
- :func:`within_tolerance` — pass/fail of a difference against a tolerance.

References
----------
- G. Sharma, W. Wu, E. N. Dalal, Color Res. Appl. 30, 21 (2005) — CIEDE2000,
  https://doi.org/10.1002/col.20070
- CIE 15:2004 Colorimetry, §8.2–8.3; CIE 116-1995 (ΔE94); F. J. J. Clarke, R. McDonald, B. Rigg,
  J. Soc. Dyers Colour. 100, 128 (1984) — CMC(l:c)
- T. Mansencal et al., Colour 0.4.7, Zenodo, https://doi.org/10.5281/zenodo.3757045
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from nmmm.colour._validation import _check_triplets
from nmmm.errors import InvalidInputError

#: Method names of :func:`delta_e` (aliases → canonical) and the keyword parameters each takes.
DELTA_E_METHODS: dict[str, tuple[str, ...]] = {
    "CIE 1976": (),
    "CIE 1994": ("textiles",),
    "CMC": ("l", "c"),
    "CIE 2000": ("kL", "kC", "kH"),
}
_ALIASES = {"cie1976": "CIE 1976", "de76": "CIE 1976", "deab": "CIE 1976", "cie76": "CIE 1976",
            "cie1994": "CIE 1994", "de94": "CIE 1994", "cie94": "CIE 1994",
            "cmc": "CMC", "cmc(l:c)": "CMC", "decmc": "CMC",
            "cie2000": "CIE 2000", "de00": "CIE 2000", "ciede2000": "CIE 2000", "cie00": "CIE 2000"}


def _lab_pair(lab1: ArrayLike, lab2: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    lab1, lab2 = _check_triplets(lab1, "lab1"), _check_triplets(lab2, "lab2")
    for lab, name in ((lab1, "lab1"), (lab2, "lab2")):
        if np.any(lab[..., 0] < -1e-6):
            raise InvalidInputError(f"{name} has L* = {float(lab[..., 0].min()):g} < 0; CIELAB lightness is >= 0 "
                                    "(L* = 0 is black), check the coordinates or their order (L*, a*, b*)")
    return lab1, lab2


def delta_e2000(lab1: ArrayLike, lab2: ArrayLike) -> np.ndarray:
    """CIEDE2000 colour difference (Sharma, Wu & Dalal 2005), broadcasting."""
    import colour

    lab1, lab2 = _lab_pair(lab1, lab2)
    return colour.delta_E(lab1, lab2, method="CIE 2000")


def canonical_delta_e_method(method: str) -> str:
    """The :data:`DELTA_E_METHODS` name of ``method`` (any case; ``dE00``, ``CIEDE2000``, ``dE94``, ``CMC`` …)."""
    if method in DELTA_E_METHODS:
        return method
    key = str(method).strip().lower().replace(" ", "").replace("_", "").replace("*", "")
    if key in _ALIASES:
        return _ALIASES[key]
    raise InvalidInputError(f"unknown colour-difference method {method!r}; use one of "
                            f"{', '.join(DELTA_E_METHODS)} (or dE76, dE94, CMC, dE00)")


def _delta_e2000_k(lab1: np.ndarray, lab2: np.ndarray, kL: float, kC: float, kH: float) -> np.ndarray:
    """CIEDE2000 with any kL:kC:kH (Sharma et al. 2005, eqs. 1–22); colour-science offers 1:1:1 and 2:1:1."""
    L1, a1, b1 = np.moveaxis(lab1, -1, 0)
    L2, a2, b2 = np.moveaxis(lab2, -1, 0)
    Cab = 0.5 * (np.hypot(a1, b1) + np.hypot(a2, b2))
    G = 0.5 * (1 - np.sqrt(Cab**7 / (Cab**7 + 25.0**7)))
    a1p, a2p = (1 + G) * a1, (1 + G) * a2
    C1p, C2p = np.hypot(a1p, b1), np.hypot(a2p, b2)
    h1p = np.where((a1p == 0) & (b1 == 0), 0.0, np.degrees(np.arctan2(b1, a1p)) % 360)
    h2p = np.where((a2p == 0) & (b2 == 0), 0.0, np.degrees(np.arctan2(b2, a2p)) % 360)
    dLp, dCp = L2 - L1, C2p - C1p
    dh = h2p - h1p
    dh = np.where(dh > 180, dh - 360, np.where(dh < -180, dh + 360, dh))
    dh = np.where(C1p * C2p == 0, 0.0, dh)
    dHp = 2 * np.sqrt(C1p * C2p) * np.sin(np.radians(dh / 2))
    Lbp, Cbp = 0.5 * (L1 + L2), 0.5 * (C1p + C2p)
    hs = h1p + h2p
    hbp = np.where(np.abs(h1p - h2p) <= 180, hs / 2, np.where(hs < 360, (hs + 360) / 2, (hs - 360) / 2))
    hbp = np.where(C1p * C2p == 0, hs, hbp)
    T = (1 - 0.17 * np.cos(np.radians(hbp - 30)) + 0.24 * np.cos(np.radians(2 * hbp))
         + 0.32 * np.cos(np.radians(3 * hbp + 6)) - 0.20 * np.cos(np.radians(4 * hbp - 63)))
    dtheta = 30 * np.exp(-(((hbp - 275) / 25) ** 2))
    RC = 2 * np.sqrt(Cbp**7 / (Cbp**7 + 25.0**7))
    SL = 1 + 0.015 * (Lbp - 50) ** 2 / np.sqrt(20 + (Lbp - 50) ** 2)
    SC, SH = 1 + 0.045 * Cbp, 1 + 0.015 * Cbp * T
    RT = -np.sin(np.radians(2 * dtheta)) * RC
    l, c, h = dLp / (kL * SL), dCp / (kC * SC), dHp / (kH * SH)
    return np.sqrt(l**2 + c**2 + h**2 + RT * c * h)


def delta_e(lab1: ArrayLike, lab2: ArrayLike, method: str = "CIE 2000", **k: float | bool) -> np.ndarray:
    """Colour difference of ``lab2`` from ``lab1`` by ``method`` (:data:`DELTA_E_METHODS`), broadcasting.

    Parameters per method: ``"CIE 1994"`` ``textiles`` (False: graphic arts kL = 1, K1 0.045,
    K2 0.015; True: kL = 2, K1 0.048, K2 0.014; the first colour is the reference); ``"CMC"`` ``l``
    (default 2, acceptability; 1 perceptibility), ``c`` (default 1), ``lab1`` the standard;
    ``"CIE 2000"`` ``kL``, ``kC``, ``kH`` (default 1; textiles 2:1:1).
    """
    import colour

    name = canonical_delta_e_method(method)
    unknown = sorted(set(k) - set(DELTA_E_METHODS[name]))
    if unknown:
        allowed = ", ".join(DELTA_E_METHODS[name]) or "none"
        raise InvalidInputError(f"{name} colour difference takes no parameter {', '.join(unknown)}; "
                                f"its parameters: {allowed}")
    for key, v in k.items():
        if key != "textiles" and not (np.isfinite(float(v)) and float(v) > 0):
            raise InvalidInputError(f"{name} parameter {key} = {v!r}: a parametric factor is a number > 0")
    lab1, lab2 = _lab_pair(lab1, lab2)
    if name == "CIE 1976":
        return colour.delta_E(lab1, lab2, method="CIE 1976")
    if name == "CIE 1994":
        return colour.delta_E(lab1, lab2, method="CIE 1994", textiles=bool(k.get("textiles", False)))
    if name == "CMC":
        return colour.delta_E(lab1, lab2, method="CMC", l=float(k.get("l", 2.0)), c=float(k.get("c", 1.0)))
    kL, kC, kH = (float(k.get(n, 1.0)) for n in ("kL", "kC", "kH"))
    if kC == 1 and kH == 1 and kL in (1, 2):
        return colour.delta_E(lab1, lab2, method="CIE 2000", textiles=kL == 2)
    return _delta_e2000_k(*np.broadcast_arrays(lab1, lab2), kL, kC, kH)


def delta_lch(lab_reference: ArrayLike, lab: ArrayLike) -> np.ndarray:
    """(..., 3) ΔL*, ΔC*ab, ΔH*ab of ``lab`` against ``lab_reference`` (CIE 15:2004 §8.2.2).

    ΔH*ab = ±√(ΔE*ab² − ΔL*² − ΔC*ab²), signed as the hue angle turns (counter-clockwise +), so
    ΔL*² + ΔC*² + ΔH*² = ΔE*ab².
    """
    a, b = _lab_pair(lab_reference, lab)
    a, b = np.broadcast_arrays(a, b)
    dL = b[..., 0] - a[..., 0]
    dC = np.hypot(b[..., 1], b[..., 2]) - np.hypot(a[..., 1], a[..., 2])
    dE2 = np.sum((b - a) ** 2, axis=-1)
    dH = np.sqrt(np.clip(dE2 - dL**2 - dC**2, 0, None))
    cross = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    return np.stack([dL, dC, np.where(cross < 0, -dH, dH)], axis=-1)


def within_tolerance(lab_reference: ArrayLike, lab: ArrayLike, tolerance: float, method: str = "CIE 2000",
                     **k: float | bool) -> tuple[np.ndarray, np.ndarray]:
    """(difference, passes) of ``lab`` against ``lab_reference``: passes where difference ≤ ``tolerance``."""
    tol = float(tolerance)
    if not (np.isfinite(tol) and tol > 0):
        raise InvalidInputError(f"tolerance {tolerance!r}: a colour-difference tolerance is a number > 0 "
                                "(e.g. 1.0 for ΔE00)")
    de = np.asarray(delta_e(lab_reference, lab, method, **k))
    return de, de <= tol
