"""Industry illuminant names (F11, TL84, CWF, LED B3) are colour-science's illuminants (issue 17 item 2)."""

import numpy as np
import pytest

from nmmm.colour import spectra_to_lab, white_point
from nmmm.colour.illuminants import canonical_illuminant
from nmmm.errors import InvalidInputError

W = np.arange(380.0, 781.0, 10.0)
R = 0.2 + 0.5 * np.exp(-((W - 600) / 60) ** 2)


@pytest.mark.parametrize("alias, name", [("F11", "FL11"), ("TL84", "FL11"), ("tl84", "FL11"), ("CWF", "FL2"),
                                         ("F2", "FL2"), ("U30", "FL12"), ("LED B3", "LED-B3"), ("led_v1", "LED-V1"),
                                         ("d65", "D65"), ("D65", "D65"), ("A", "A")])
def test_alias_maps_to_the_cie_illuminant(alias, name):
    assert canonical_illuminant(alias) == name
    np.testing.assert_array_equal(spectra_to_lab(W, R, alias), spectra_to_lab(W, R, name))


def test_alias_white_is_colour_sciences():
    import colour

    xyz = colour.sd_to_XYZ(colour.SpectralDistribution(np.ones_like(W), W), colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"],
                           colour.SDS_ILLUMINANTS["FL11"], method="ASTM E308")
    np.testing.assert_allclose(white_point(W, "TL84"), xyz, rtol=1e-9)


def test_unknown_name_says_which_are_close():
    with pytest.raises(InvalidInputError, match="TL84"):
        spectra_to_lab(W, R, "TL85")


def test_recipe_lighting_accepts_aliases():
    from nmmm.recipes.schema import parse_recipe, read_toml, example_path

    raw, _, base = read_toml(example_path("hematite_tint"))
    raw["lighting"] = {"illuminants": ["D65", "TL84", "F2"]}
    assert parse_recipe(raw, base_dir=base).lighting.illuminants == ["D65", "TL84", "F2"]


def test_light_spd_accepts_aliases():
    from nmmm.appearance.render.lights import spd

    np.testing.assert_array_equal(spd("TL84").values, spd("FL11").values)
