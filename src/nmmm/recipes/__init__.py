"""nmmm.recipes — one TOML description of a material from its compounds to its images,
the commands that run it, and the reports a person reads (``nmmm demo`` is :mod:`nmmm.demo`, on the
floor above).

- :mod:`~nmmm.recipes.schema` — :class:`Recipe` (pydantic), :func:`load_recipe` (errors are
  :class:`nmmm.errors.RecipeError` naming the key path), :func:`example_recipes`.
- :mod:`~nmmm.recipes.run` — :func:`compute` (physics only) and :func:`run_recipe` (CSV,
  NetCDF, plots, images, HTML report) -> :class:`RunResult`  (``nmmm run``).
- :mod:`~nmmm.recipes.compare` — :func:`compare_recipes`: ΔE2000 under chosen illuminants,
  spectra overlaid, images side by side  (``nmmm compare``).
- :mod:`~nmmm.recipes.sweep` — :func:`nmmm.recipes.sweep.sweep` on Dask, one Parquet file per point,
  resumable  (``nmmm sweep``).
- :mod:`~nmmm.recipes.report` — self-contained HTML reports.
- :mod:`~nmmm.recipes.pairs` — :func:`make_experiment_pairs`: computed image vs photograph ->
  ``pairs.toml`` for the 2AFC experiment (``nmmm run RECIPE --pair-with PHOTO``).

Shipped recipes (``nmmm run NAME`` accepts their names): gold_ruby_glass, hematite_paint,
hematite_paint_ethylcellulose, grey_metallic, interference_pigment, hematite_coating_fft.
"""

from nmmm.recipes.schema import Recipe, example_path, example_recipes, load_recipe, parse_recipe


def __getattr__(name):  # heavy modules on demand (keeps `import nmmm.recipes` light)
    import importlib

    lazy = {
        "compute": "nmmm.recipes.run", "run_recipe": "nmmm.recipes.run", "RunResult": "nmmm.recipes.run",
        "compare_recipes": "nmmm.recipes.compare", "load_results": "nmmm.recipes.sweep",
        "write_report": "nmmm.recipes.report",
        "make_experiment_pairs": "nmmm.recipes.pairs",
    }
    if name in lazy:
        return getattr(importlib.import_module(lazy[name]), name)
    if name == "run_demo":  # moved up a floor: recipes may not import the demo
        raise AttributeError("nmmm.recipes.run_demo moved to nmmm.demo.run_demo ('from nmmm.demo import run_demo'); "
                             "the demo is its own package above recipes")
    raise AttributeError(f"module 'nmmm.recipes' has no attribute {name!r}")


__all__ = ["Recipe", "load_recipe", "parse_recipe", "example_recipes", "example_path", "compute", "run_recipe",
           "RunResult", "compare_recipes", "load_results", "write_report", "make_experiment_pairs"]
