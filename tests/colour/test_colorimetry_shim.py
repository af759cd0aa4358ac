"""nmmm.appearance.colorimetry, the old home of colour, warns and hands back nmmm.colour's objects."""

import importlib
import subprocess
import sys

import pytest

import nmmm.appearance
import nmmm.colour


def test_old_module_warns_and_reexports_the_same_objects():
    sys.modules.pop("nmmm.appearance.colorimetry", None)
    with pytest.warns(DeprecationWarning, match="nmmm.colour"):
        old = importlib.import_module("nmmm.appearance.colorimetry")
    assert sorted(old.__all__) == sorted(nmmm.colour.__all__)
    for name in nmmm.colour.__all__:
        assert getattr(old, name) is getattr(nmmm.colour, name), name


def test_appearance_reexports_colour_without_warning():
    for name in ("delta_e2000", "spectra_to_lab", "spectra_to_srgb", "spectra_to_xyz", "weighting_factors",
                 "white_point", "xyz_to_lab", "xyz_to_srgb"):
        assert getattr(nmmm.appearance, name) is getattr(nmmm.colour, name), name
    # a fresh interpreter, so that the import really runs: it must not touch the deprecated module
    code = "import sys, nmmm.appearance; assert 'nmmm.appearance.colorimetry' not in sys.modules"
    subprocess.run([sys.executable, "-W", "error::DeprecationWarning:nmmm", "-c", code], check=True)
