"""Finding materials (issue 23 item 4): search by formula, name, synonym and phase, each hit with its
range, whether it covers 380-780 nm, and its source; the cited binder table evaluates the published
formulas (written out here from the papers, independently of the database code)."""

import numpy as np
import pytest
from click.testing import CliRunner

from nmmm.errors import InvalidInputError, MaterialNotFoundError
from nmmm.materials import BINDERS, binder, search, search_entries
from nmmm.materials.cli import materials


def test_hematite_is_fe2o3_with_ranges_and_source():
    hits = search_entries("hematite")
    assert [h.key for h in hits] == ["main/Fe2O3/Querry-e", "main/Fe2O3/Querry-o"]
    for h in hits:
        assert h.covers_visible and h.range_nm[0] == pytest.approx(210, rel=1e-6) and "Querry" in h.source
    assert [h.key for h in search_entries("Haematite")] == [h.key for h in hits]


@pytest.mark.parametrize("text,expected,absent", [
    ("rutile", {"main/TiO2/Devore-o", "main/TiO2/Devore-e", "main/TiO2/Bond-o", "main/TiO2/Bond-e"},
     {"main/TiO2/Jolivet-anatase", "main/TiO2/Bodurov"}),
    ("anatase", {"main/TiO2/Jolivet-anatase", "main/TiO2/Bodurov"}, {"main/TiO2/Devore-o"}),
    ("PMMA", {"organic/poly_methyl_methacrylate/Sultanova", "3d/plastics/pmma"}, set()),
    ("iron oxide", {"main/Fe2O3/Querry-o", "main/Fe3O4/Querry"}, set()),
    ("epoxy", {"other/Microchem_SU8_2000/specs"}, set()),
    ("Fe2O3", {"main/Fe2O3/Querry-o", "main/Fe2O3/Querry-e"}, {"glass/soda-lime/Vogt-10ppm"}),
])
def test_synonyms_phases_formulas(text, expected, absent):
    keys = set(search(text))
    assert expected <= keys and not (absent & keys)


def test_coverage_flag_is_the_range():
    for h in search_entries("rutile"):
        assert h.covers_visible == (h.range_nm[0] <= 380 and h.range_nm[1] >= 780)
    assert not any(h.covers_visible for h in search_entries("rutile"))  # Devore, Bond start at 430-450 nm
    with pytest.raises(InvalidInputError):
        search_entries("  ")


def test_cli_search_hematite_lists_fe2o3_with_ranges():
    r = CliRunner().invoke(materials, ["search", "hematite"])
    assert r.exit_code == 0, r.output
    lines = r.output.splitlines()
    assert [ln.split("\t")[0] for ln in lines] == ["main/Fe2O3/Querry-e", "main/Fe2O3/Querry-o"]
    assert all("210–" in ln and "covers 380–780 nm" in ln and "Querry" in ln for ln in lines)
    r = CliRunner().invoke(materials, ["search", "alkyd"])
    assert r.exit_code == 0 and "binder alkyd" in r.output and "not published" in r.output


def test_binders_are_the_published_formulas():
    w = np.linspace(440.0, 780.0, 35)
    um = w / 1000.0
    # Sultanova et al. (2009), PMMA: n^2 - 1 = 1.1819 l^2 / (l^2 - 0.011313)
    np.testing.assert_allclose(binder("acrylic").n(w), np.sqrt(1 + 1.1819 * um**2 / (um**2 - 0.011313)), rtol=1e-6)
    # MicroChem SU-8 2000 data sheet: n = 1.566 + 0.00796 / l^2 + 0.00014 / l^4
    np.testing.assert_allclose(binder("epoxy").n(w), 1.566 + 0.00796 / um**2 + 0.00014 / um**4, rtol=1e-6)
    assert np.all(binder("epoxy").k(w) == 0)
    assert float(binder("ethylcellulose").n(589.3)) == 1.479  # Polymer Handbook n_D, non-dispersive
    assert binder("PMMA") is binder("acrylic")


def test_unpublished_binders_say_so():
    assert set(BINDERS) == {"epoxy", "acrylic", "alkyd", "polyurethane", "nitrocellulose", "ethylcellulose"}
    for name in ("alkyd", "polyurethane", "nitrocellulose"):
        assert BINDERS[name].status == "not published" and BINDERS[name].range_nm is None
        with pytest.raises(MaterialNotFoundError, match="no published dispersion model"):
            binder(name)
    with pytest.raises(MaterialNotFoundError, match="unknown binder"):
        binder("shellac")
    for b in BINDERS.values():
        assert b.reference and b.notes
