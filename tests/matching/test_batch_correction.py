"""Batch correction with the model's sensitivity at the batch point (issue 17 item 4)."""

import numpy as np
import pytest

from nmmm.matching import RecipeModel
from nmmm.matching.batch_correction import correct_batch
from nmmm.recipes.schema import example_path, read_toml, set_key


@pytest.fixture(scope="module")
def model():
    raw, _, _ = read_toml(example_path("hematite_tint"))
    return RecipeModel(set_key(raw, "film.thickness_nm", 8000.0),
                       ["pigments.0.fraction=0.005:0.08", "pigments.1.fraction=0.02:0.25"])


def test_underdosed_batch_gets_the_missing_hematite(model):
    x0 = np.array([0.021, 0.15])
    target = model.reflectance(x0, "ad") + 0.003  # the standard, read on an instrument 0.003 high
    made = x0 - np.array([0.003, 0.0])  # the batch: 3/1000 of hematite short, read on the same instrument
    measured = model.reflectance(made, "ad") + 0.003
    c = correct_batch(model, x0, measured, target)
    assert c.de00_before > 1.0
    assert c.de00_after < 0.05
    # first-order: the sensitivity at the recipe point (0.021) is lower than at the batch's true 0.018,
    # so one step over-adds a little (the industry corrects again after the next measurement)
    assert c.additions["pigments.0.fraction"] == pytest.approx(0.003, rel=0.3)
    assert c.additions["pigments.1.fraction"] == pytest.approx(0.0, abs=3e-3)
    # the real batch with the proposed additions, measured through the same offset
    after = model.reflectance(made + np.array(list(c.additions.values())), "ad") + 0.003
    from nmmm.colour import delta_e2000, spectra_to_lab

    w = model.wavelength_nm
    de_after = float(delta_e2000(spectra_to_lab(w, target), spectra_to_lab(w, after)))
    assert de_after < 0.5 * c.de00_before


def test_overdosed_batch_needs_a_signed_correction(model):
    x0 = np.array([0.021, 0.15])
    target = model.reflectance(x0, "ad")
    measured = model.reflectance(x0 + np.array([0.003, 0.0]), "ad")
    add_only = correct_batch(model, x0, measured, target)
    assert add_only.additions["pigments.1.fraction"] > 0  # more white offsets too much red
    signed = correct_batch(model, x0, measured, target, additions_only=False)
    assert signed.de00_after < 0.05
