"""Sphinx configuration of the nmmm documentation: offline (no intersphinx, no web fonts or
MathJax), warnings as errors (``sphinx-build -W --keep-going``), napoleon for the NumPy-style
docstrings, and the project extension ``_ext/nmmm_docs.py`` (recipe reference generated from the
schema, API of every public name, gallery from ``examples/``)."""

import sys
from importlib.metadata import version as _version
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent / "_ext"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))  # document this checkout's nmmm

project = "nmmm"
author = "nmmm developers"
copyright = "nmmm developers, BSD-3-Clause"
release = _version("nmmm")  # one source: pyproject.toml's [project] version
version = release

extensions = ["sphinx.ext.autodoc", "sphinx.ext.napoleon", "sphinx.ext.viewcode", "nmmm_docs"]
# napoleon, not numpydoc: it ships with Sphinx (no extra dependency offline) and renders the NumPy
# sections (Parameters, Returns, Notes, References, Examples) without failing on the many short
# docstrings that have no sections at all; numpydoc would warn on each of those under -W.
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_rtype = False
autodoc_typehints = "signature"
autodoc_member_order = "bysource"
autodoc_default_options = {"show-inheritance": False}
autodoc_mock_imports = ["mitsuba", "drjit"]

exclude_patterns = ["_build", "gallery/_work", "gallery_figures"]
templates_path = []
html_theme = "alabaster"
html_static_path = ["_static"]
html_css_files = ["nmmm.css"]  # the gallery description box wraps (docs/_static/nmmm.css)
html_title = f"nmmm {release}"
html_theme_options = {"description": "Predictive colour and appearance of paints, from nano to macro",
                      "fixed_sidebar": False, "font_family": "sans-serif", "head_font_family": "sans-serif"}
html_sidebars = {"**": ["about.html", "navigation.html", "searchbox.html"]}

# examples run while the pages are built (each a few seconds on 2 cores); the others show stored figures
nmmm_gallery_run = ["ema_gold_ruby", "ema_multilevel", "microstructure_hematite", "ellipsometry_hematite"]
