"""Dispersion models as :class:`~nmmm.materials.material.Material` objects.

- :class:`Constant` — non-dispersive n + ik (or ε); defined in :mod:`nmmm.materials.material`
  (which turns numbers into it) and re-exported here.
- :class:`Cauchy` — n = A + B/λ² + C/λ⁴ (λ in µm), optional Urbach absorption tail.
- :class:`Sellmeier` — n² = A + Σ Bᵢ λ²/(λ² − Cᵢ) (λ, √Cᵢ in µm).
- :class:`Drude` — free carriers, ε = ε∞ − ωp²/(E² + iΓE).
- :class:`Lorentz` — sum of oscillators, ε = ε∞ + Σ Aⱼ/(E0ⱼ² − E² − iΓⱼE).
- :class:`DrudeLorentz` — Drude plus Lorentz oscillators.
- :class:`TaucLorentz` — amorphous semiconductors and dielectrics (Jellison–Modine).
- :func:`canonical_parameters` — parameters written with explicit units (``B_um2``, ``C_um4``,
  ``B_nm2``, ``C_nm4`` for Cauchy; ``C_um2``, ``C_nm2`` for Sellmeier; see
  :data:`EXPLICIT_UNIT_KEYS`) -> the model's own keyword arguments, converted.

Units. Cauchy's and Sellmeier's coefficients follow their literature, with λ in µm: Cauchy
``B`` in µm², ``C`` in µm⁴; Sellmeier ``C`` in µm² — the exceptions to nmmm's "nm everywhere".
A recipe or model file may say so in the key (``B_um2 = 0.0042``) or give nm-based values
(``B_nm2 = 4200``, the same coefficient: 1 µm² = 10⁶ nm²); :func:`canonical_parameters`
converts them, and refuses a coefficient given twice.

Photon energies E, ωp, Γ, E0, Eg are in eV (E = 1239.84 eV·nm / λ). With the time
dependence exp(−iωt) every absorbing term has Im ε ≥ 0. Every model evaluates over
``range_nm`` (default: all positive wavelengths, since a model is a formula; set it to
the range the parameters were fitted on to be warned outside it).

References
----------
- A. L. Cauchy, Mémoire sur la dispersion de la lumière (1836); Urbach tail:
  F. Urbach, Phys. Rev. 92, 1324 (1953); form as in J. A. Woollam, WVASE manual.
- W. Sellmeier, Ann. Phys. 219, 272 (1871); I. H. Malitson, JOSA 55, 1205 (1965).
- M. Dressel & G. Grüner, Electrodynamics of Solids (CUP 2002), ch. 5 (Drude, Lorentz).
- H. Fujiwara, Spectroscopic Ellipsometry (Wiley 2007), §5.3 (Lorentz, Drude, Tauc–Lorentz).
- G. E. Jellison Jr. & F. A. Modine, Appl. Phys. Lett. 69, 371 (1996); erratum 69, 2137 (1996).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.materials.material import HC_EV_NM, Constant, Material


def _require(cond: bool, message: str):
    if not cond:
        raise InvalidInputError(message)


def _finite(*values, what="parameters"):
    arr = np.asarray(values, dtype=complex)
    _require(bool(np.all(np.isfinite(arr))), f"{what} must be finite, got {values}")


@dataclass(frozen=True, repr=False, kw_only=True)
class _Model(Material):
    name: str = "model"
    reference: str = ""
    range_nm: tuple[float, float] = (0.0, np.inf)

    def __post_init__(self):
        lo, hi = self.range_nm
        _require(0 <= lo < hi, f"{self.name}: range_nm must be (lo, hi) with 0 <= lo < hi, got {self.range_nm}")


@dataclass(frozen=True, repr=False, kw_only=True)
class Cauchy(_Model):
    """Cauchy dispersion n(λ) = A + B/λ² + C/λ⁴ with λ in µm (B in µm², C in µm⁴), and an
    optional Urbach absorption tail k(E) = k_amplitude·exp(k_exponent·(E − band_edge_ev))
    (E in eV), the "Cauchy + Urbach" model of ellipsometry software. Cauchy is an empirical
    description of transparent regions: it is not Kramers–Kronig consistent.
    """

    A: float
    B: float = 0.0
    C: float = 0.0
    k_amplitude: float = 0.0
    k_exponent: float = 0.0
    band_edge_ev: float = 3.5
    name: str = "Cauchy"
    reference: str = "A. L. Cauchy (1836); Urbach tail: F. Urbach, Phys. Rev. 92, 1324 (1953)"

    def __post_init__(self):
        super().__post_init__()
        _finite(self.A, self.B, self.C, self.k_amplitude, self.k_exponent, self.band_edge_ev)
        _require(self.A > 0, f"{self.name}: Cauchy A must be > 0, got {self.A}")
        _require(self.k_amplitude >= 0, f"{self.name}: k_amplitude must be >= 0 (k >= 0), got {self.k_amplitude}")

    def _nk(self, w_nm):
        l2 = (w_nm / 1000.0) ** 2
        n = self.A + self.B / l2 + self.C / (l2 * l2)
        k = self.k_amplitude * np.exp(self.k_exponent * (HC_EV_NM / w_nm - self.band_edge_ev))
        return n + 1j * k


@dataclass(frozen=True, repr=False, kw_only=True)
class Sellmeier(_Model):
    """Sellmeier n² = A + Σ Bᵢ λ²/(λ² − Cᵢ), λ in µm, Cᵢ in µm² (resonance wavelengths √Cᵢ).

    Fused silica (Malitson 1965): A = 1, B = (0.6961663, 0.4079426, 0.8974794),
    C = (0.0684043², 0.1162414², 9.896161²).
    """

    B: tuple[float, ...]
    C: tuple[float, ...]
    A: float = 1.0
    name: str = "Sellmeier"
    reference: str = "W. Sellmeier, Ann. Phys. 219, 272 (1871)"

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "B", tuple(float(b) for b in np.atleast_1d(self.B)))
        object.__setattr__(self, "C", tuple(float(c) for c in np.atleast_1d(self.C)))
        _require(len(self.B) == len(self.C) and len(self.B) > 0, f"{self.name}: B and C need the same, non-zero length")
        _finite(self.A, *self.B, *self.C)
        _require(all(c >= 0 for c in self.C), f"{self.name}: resonance terms C (µm²) must be >= 0, got {self.C}")
        _require(self.A > 0, f"{self.name}: A must be > 0")

    def _nk(self, w_nm):
        l2 = (w_nm / 1000.0) ** 2
        n2 = self.A + sum(b * l2 / (l2 - c) for b, c in zip(self.B, self.C))
        n2 = np.asarray(n2, dtype=float)
        if np.any(n2 <= 0):
            raise InvalidInputError(f"{self.name}: n² <= 0 at some wavelengths (too close to a resonance)")
        return np.sqrt(n2) + 0j


def _energy_ev(w_nm):
    return HC_EV_NM / np.asarray(w_nm, dtype=float)


def _oscillators(osc, name) -> tuple[tuple[float, float, float], ...]:
    osc = tuple(tuple(float(v) for v in o) for o in osc)
    for o in osc:
        _require(len(o) == 3, f"{name}: each oscillator is (amplitude_ev2, center_ev, broadening_ev), got {o}")
        _finite(*o)
        a, e0, g = o
        _require(a >= 0, f"{name}: oscillator amplitude must be >= 0 (Im eps >= 0), got {a}")
        _require(e0 > 0, f"{name}: oscillator centre energy must be > 0 eV, got {e0}")
        _require(g >= 0, f"{name}: broadening must be >= 0 eV, got {g}")
    return osc


@dataclass(frozen=True, repr=False, kw_only=True)
class Lorentz(_Model):
    """Sum of Lorentz oscillators, ε(E) = ε∞ + Σ Aⱼ / (E0ⱼ² − E² − iΓⱼE).

    ``oscillators`` is a sequence of ``(A [eV²], E0 [eV], Γ [eV])``. Exactly causal
    (Kramers–Kronig consistent) for any parameters (Fujiwara 2007, eq. 5.20).
    """

    oscillators: tuple = ()
    eps_inf: float = 1.0
    name: str = "Lorentz"
    reference: str = "H. Fujiwara, Spectroscopic Ellipsometry (Wiley 2007), eq. 5.20"

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "oscillators", _oscillators(self.oscillators, self.name))
        _finite(self.eps_inf)

    def _lorentz_terms(self, E):
        out = np.zeros(E.shape, dtype=complex)
        for a, e0, g in self.oscillators:
            out += a / (e0 * e0 - E * E - 1j * g * E)
        return out

    def _eps(self, w_nm):
        E = _energy_ev(w_nm)
        return self.eps_inf + self._lorentz_terms(E)


def _check_drude(m):
    _finite(m.plasma_ev, m.gamma_ev, m.eps_inf)
    _require(m.plasma_ev >= 0, f"{m.name}: plasma energy must be >= 0 eV")
    _require(m.gamma_ev > 0, f"{m.name}: damping gamma_ev must be > 0 eV (Im eps > 0)")


@dataclass(frozen=True, repr=False, kw_only=True)
class Drude(_Model):
    """Free-carrier (Drude) model ε(E) = ε∞ − ωp² / (E² + iΓE), ωp and Γ in eV
    (Dressel & Grüner 2002, eq. 5.1.14 in energy units)."""

    plasma_ev: float
    gamma_ev: float
    eps_inf: float = 1.0
    name: str = "Drude"
    reference: str = "M. Dressel & G. Grüner, Electrodynamics of Solids (CUP 2002), ch. 5"

    def __post_init__(self):
        super().__post_init__()
        _check_drude(self)

    def _drude_term(self, E):
        return -self.plasma_ev**2 / (E * E + 1j * self.gamma_ev * E)

    def _eps(self, w_nm):
        return self.eps_inf + self._drude_term(_energy_ev(w_nm))


@dataclass(frozen=True, repr=False, kw_only=True)
class DrudeLorentz(_Model):
    """Drude free carriers plus Lorentz oscillators (Rakić et al., Appl. Opt. 37, 5271 (1998)
    for metals): ε = ε∞ − ωp²/(E² + iΓE) + Σ Aⱼ/(E0ⱼ² − E² − iΓⱼE)."""

    plasma_ev: float
    gamma_ev: float
    oscillators: tuple = ()
    eps_inf: float = 1.0
    name: str = "Drude-Lorentz"
    reference: str = "A. D. Rakić et al., Appl. Opt. 37, 5271 (1998)"

    def __post_init__(self):
        super().__post_init__()
        _check_drude(self)
        object.__setattr__(self, "oscillators", _oscillators(self.oscillators, self.name))

    def _eps(self, w_nm):
        E = _energy_ev(w_nm)
        return self.eps_inf + Drude._drude_term(self, E) + Lorentz._lorentz_terms(self, E)


@dataclass(frozen=True, repr=False, kw_only=True)
class TaucLorentz(_Model):
    """Tauc–Lorentz model of Jellison & Modine (1996) for amorphous materials:

    ε2(E) = A·E0·C·(E − Eg)² / [((E² − E0²)² + C²E²)·E] for E > Eg, 0 otherwise;
    ε1 from its closed-form Kramers–Kronig transform plus ε1(∞) (their eq. and erratum).
    A, E0, C, Eg in eV.
    """

    A: float
    E0: float
    C: float
    Eg: float
    eps_inf: float = 1.0
    name: str = "Tauc-Lorentz"
    reference: str = "G. E. Jellison Jr., F. A. Modine, Appl. Phys. Lett. 69, 371 (1996); erratum 69, 2137"

    def __post_init__(self):
        super().__post_init__()
        _finite(self.A, self.E0, self.C, self.Eg, self.eps_inf)
        _require(self.A > 0, f"{self.name}: amplitude A must be > 0 eV")
        _require(self.Eg >= 0, f"{self.name}: band gap Eg must be >= 0 eV")
        _require(self.C > 0, f"{self.name}: broadening C must be > 0 eV")
        _require(2 * self.E0 > self.C, f"{self.name}: need C < 2·E0 (alpha = sqrt(4E0² − C²) real)")
        _require(self.E0 > self.Eg, f"{self.name}: need E0 > Eg")

    def eps2(self, E):
        A, E0, C, Eg = self.A, self.E0, self.C, self.Eg
        E = np.asarray(E, dtype=float)
        val = A * E0 * C * (E - Eg) ** 2 / (((E * E - E0 * E0) ** 2 + C * C * E * E) * E)
        return np.where(E > Eg, val, 0.0)

    def eps1(self, E):
        A, E0, C, Eg = self.A, self.E0, self.C, self.Eg
        E = np.asarray(E, dtype=float)
        a_ln = (Eg**2 - E0**2) * E**2 + Eg**2 * C**2 - E0**2 * (E0**2 + 3 * Eg**2)
        a_atan = (E**2 - E0**2) * (E0**2 + Eg**2) + Eg**2 * C**2
        alpha = np.sqrt(4 * E0**2 - C**2)
        gamma = np.sqrt(E0**2 - C**2 / 2)
        zeta4 = (E**2 - gamma**2) ** 2 + alpha**2 * C**2 / 4
        pi = np.pi
        with np.errstate(divide="ignore", invalid="ignore"):
            t1 = A * C * a_ln / (2 * pi * zeta4 * alpha * E0) * np.log(
                (E0**2 + Eg**2 + alpha * Eg) / (E0**2 + Eg**2 - alpha * Eg))
            t2 = -A * a_atan / (pi * zeta4 * E0) * (
                pi - np.arctan((2 * Eg + alpha) / C) + np.arctan((alpha - 2 * Eg) / C))
            t3 = 2 * A * E0 / (pi * zeta4 * alpha) * Eg * (E**2 - gamma**2) * (
                pi + 2 * np.arctan(2 * (gamma**2 - Eg**2) / (alpha * C)))
            t4 = -A * E0 * C * (E**2 + Eg**2) / (pi * zeta4 * E) * np.log(np.abs(E - Eg) / (E + Eg))
            t5 = 2 * A * E0 * C * Eg / (pi * zeta4) * np.log(
                np.abs(E - Eg) * (E + Eg) / np.sqrt((E0**2 - Eg**2) ** 2 + Eg**2 * C**2))
            out = self.eps_inf + t1 + t2 + t3 + t4 + t5
        # E == Eg: the two logarithms cancel analytically; take the limit from nearby energies
        at_gap = np.isclose(E, Eg)
        if np.any(at_gap):
            out = np.where(at_gap, 0.5 * (self.eps1(E * (1 + 1e-7)) + self.eps1(E * (1 - 1e-7))), out)
        return out

    def _eps(self, w_nm):
        E = _energy_ev(w_nm)
        return self.eps1(E) + 1j * self.eps2(E)


#: registry of dispersion models by name, for recipes and fitting
MODELS = {
    "constant": Constant,
    "cauchy": Cauchy,
    "sellmeier": Sellmeier,
    "drude": Drude,
    "lorentz": Lorentz,
    "drude_lorentz": DrudeLorentz,
    "tauc_lorentz": TaucLorentz,
}

#: explicit-unit spellings of dispersion coefficients: model -> {key: (model keyword, factor to its unit)}
EXPLICIT_UNIT_KEYS = {
    "cauchy": {"B_um2": ("B", 1.0), "C_um4": ("C", 1.0), "B_nm2": ("B", 1e-6), "C_nm4": ("C", 1e-12)},
    "sellmeier": {"C_um2": ("C", 1.0), "C_nm2": ("C", 1e-6)},
}


def canonical_parameters(model: str, params: dict) -> dict:
    """``params`` with explicit-unit keys (:data:`EXPLICIT_UNIT_KEYS`) replaced by the model's
    keyword arguments in its own units; list values (Sellmeier) are converted element-wise.

    >>> canonical_parameters("cauchy", {"A": 1.5, "B_nm2": 4200.0, "C_um4": 0.0001})
    {'A': 1.5, 'B': 0.0042, 'C': 0.0001}
    """
    aliases = EXPLICIT_UNIT_KEYS.get(str(model).lower().replace("-", "_"), {})
    out = {}
    for key, value in params.items():
        if key not in aliases:
            if key in out:
                raise InvalidInputError(f"{model}: {key} is given twice (once with its unit in the name); keep one")
            out[key] = value
            continue
        target, factor = aliases[key]
        if target in out or target in params:
            given = [k for k in params if k == target or aliases.get(k, ("",))[0] == target]
            raise InvalidInputError(f"{model}: the coefficient {target} is given twice ({', '.join(given)}); keep one "
                                    f"(units: {', '.join(f'{k}' for k, (t, _) in aliases.items() if t == target)})")
        if isinstance(value, (list, tuple)):
            out[target] = type(value)(float(v) * factor for v in value)
        else:
            out[target] = float(value) * factor
    return out
