"""The sections of ``nmmm demo``, registered in one place.

- :data:`RECIPE_SECTIONS` — the shipped recipes run (``"substitution"`` is the ``nmmm compare`` view of
  :data:`SUBSTITUTION`; the hematite recipe adds the 5/7/10 % and grain-size series, serial sweeps over
  :data:`HEMATITE_FRACTIONS` and :data:`HEMATITE_DIAGONALS_NM`).
- :data:`HOOKS` — ``(title, "module:function")`` of the worked examples, one module of :mod:`nmmm.demo`
  per seed example and per scale's tour. A hook is ``hook(output_dir) -> {"title", "figures", "tables",
  "text"}``; one that draws progress bars takes ``progress: bool = True`` and gets the demo's flag.

Adding a section is adding a module with its hook and a line here.
"""

from __future__ import annotations

__all__ = ["RECIPE_SECTIONS", "SUBSTITUTION", "HEMATITE_FRACTIONS", "HEMATITE_DIAGONALS_NM", "HOOKS"]

RECIPE_SECTIONS = ("gold_ruby_glass", "hematite_paint", "substitution", "grey_metallic", "interference_pigment",
                   "hematite_coating_fft")
#: the substitution view of the demo: (recipe A, recipe B) compared by ``nmmm compare``
SUBSTITUTION = ("hematite_paint", "hematite_paint_ethylcellulose")
HEMATITE_FRACTIONS = (0.05, 0.07, 0.10)
HEMATITE_DIAGONALS_NM = (100.0, 150.0, 250.0, 400.0, 600.0, 1000.0)

HOOKS = (
    ("Compounds of the seed paper (nmmm.materials)", "nmmm.demo.materials:demo"),
    ("Gold-ruby glass in depth (nmmm.ema)", "nmmm.demo.gold_ruby:gold_ruby_demo"),
    ("Hematite paint in depth (nmmm.layers)", "nmmm.demo.hematite:hematite_demo"),
    ("Interference pigments in depth (nmmm.layers)", "nmmm.demo.interference:demo"),
    ("Real paint systems: tints, whites, coats (nmmm.layers)", "nmmm.demo.paint_systems:demo"),
    ("Colour matching: a hidden mixture matched back to a recipe (nmmm.matching)", "nmmm.demo.matching:demo"),
    ("Calibration: a colourant calibrated from a measured ladder, physical and empirical (nmmm.matching)",
     "nmmm.demo.matching:calibration_demo"),
    ("Physical fidelity: hematite colour sensitivity, gold size series", "nmmm.demo.sensitivity:demo"),
    ("Microstructures (nmmm.microstructure)", "nmmm.demo.microstructure:demo"),
    ("FFT homogenization (nmmm.homogenize)", "nmmm.demo.homogenization:demo"),
    ("Ellipsometry (nmmm.ellipsometry)", "nmmm.demo.ellipsometry:demo"),
    ("BRDFs and multi-angle colour (nmmm.appearance)", "nmmm.demo.appearance:demo"),
    ("Rendering (nmmm.appearance.render)", "nmmm.demo.rendering:demo"),
    ("2AFC validation (nmmm.experiment)", "nmmm.demo.experiment:demo"),
)
