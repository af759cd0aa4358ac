"""Shared helpers of the recipe tests: the shipped recipes with fast settings."""

import tomllib
import warnings

import pytest

from nmmm.recipes.schema import example_path


def fast_raw(name: str, step_nm: float = 20.0) -> dict:
    """A shipped example as a raw dict, on a coarser grid (and a small image) for speed."""
    raw = tomllib.loads(example_path(name).read_text())
    raw.setdefault("spectral", {})["step_nm"] = step_nm
    if "image" in raw:
        raw["image"]["pixels"] = [30, 20]
        raw["image"]["renderer"] = "simple"  # the discrete-flake renderer is exercised by a slow test
    if "pigment" in raw:
        raw["pigment"]["size_nodes"] = 8
    return raw


@pytest.fixture(autouse=True)
def _quiet_size_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield
