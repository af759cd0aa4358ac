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


@pytest.fixture(scope="session")
def grey_metallic_run(tmp_path_factory):
    """grey_metallic (40 nm grid, 30 x 20 px stereo pair) written as a recipe file and run once
    by `run_recipe` for the whole session: ``(recipe_path, result, out_dir)``. Tests read it,
    never modify it."""
    from nmmm.recipes.run import _dump_toml, run_recipe

    d = tmp_path_factory.mktemp("grey_metallic")
    recipe = d / "grey.toml"
    recipe.write_text(_dump_toml(fast_raw("grey_metallic", step_nm=40.0)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = run_recipe(str(recipe), d / "out", progress=False)
    return recipe, res, d / "out"


@pytest.fixture(autouse=True)
def _quiet_size_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield
