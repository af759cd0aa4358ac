"""Shared fixtures of the ellipsometry tests: pyElli (the independent reference) helpers."""

import numpy as np
import pytest

elli = pytest.importorskip("elli")


@pytest.fixture(scope="session")
def silicon():
    from nmmm.materials import get

    return get("main/Si/Green-2008")


@pytest.fixture(scope="session")
def elli_table():
    """f(material, wavelength_nm): a pyElli isotropic material tabulating an nmmm Material's n + ik."""

    def make(material, wavelength_nm):
        return elli.IsotropicMaterial(elli.Table(lbda=np.asarray(wavelength_nm, float),
                                                 n=material.nk(wavelength_nm)))

    return make


@pytest.fixture(scope="session")
def ddelta():
    """f(a, b): Δ differences wrapped into (−180°, 180°]."""
    return lambda a, b: (np.asarray(a) - np.asarray(b) + 180.0) % 360.0 - 180.0
