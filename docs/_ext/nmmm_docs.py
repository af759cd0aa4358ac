"""Sphinx extension of the nmmm documentation (built offline, warnings as errors).

- ``.. nmmm-recipe-reference::`` — the recipe reference generated at build time from the pydantic
  models of :mod:`nmmm.recipes.schema` (every key: type, unit, default, constraint, an example
  value from the shipped recipes), so it follows the schema as it changes.
- ``.. nmmm-api:: PACKAGE`` — every name of ``PACKAGE.__all__`` through autodoc, in order.
- ``autodoc-process-docstring`` hook: a docstring (after napoleon) that is not clean
  reStructuredText is shown verbatim as a literal block instead of breaking the build; the
  number of such docstrings is printed at the end of the build.
- The gallery: at ``builder-inited`` every ``examples/*.py`` becomes ``gallery/<name>.rst``
  (title and text from its docstring, its figures, its source); the examples listed in
  ``nmmm_gallery_run`` are run then (their figures are the ones just made), the others show the
  figures stored under ``docs/gallery_figures/<name>/`` (made by the same script, saying so).
"""

from __future__ import annotations

import ast
import io
import re
import shutil
import subprocess
import sys
import time
import tomllib
import types
import typing
from pathlib import Path

from docutils import nodes
from docutils.parsers.rst import Directive, directives
from docutils.statemachine import StringList

ROOT = Path(__file__).resolve().parents[2]
_VERBATIM: list[str] = []


# --------------------------------------------------------------------------------------
# docstrings that are not clean reST are shown verbatim

_ROLE = re.compile(r":(?:[a-z]+:)*[a-z]+:`([^`]*)`")


def _clean_rst(text: str) -> bool:
    import docutils.core

    if re.search(r"^:(?:param|type)\s[^\n]*?:[a-z]+:`", text, re.M):  # a role inside a field name
        return False
    probe = _ROLE.sub(lambda m: "``" + m.group(1).replace("`", "'") + "``", text)
    stream = io.StringIO()
    try:
        doc = docutils.core.publish_doctree(probe, settings_overrides={
            "report_level": 2, "halt_level": 5, "warning_stream": stream, "file_insertion_enabled": False,
            "raw_enabled": False})
    except Exception:  # noqa: BLE001 - anything docutils cannot take is shown verbatim
        return False
    return not stream.getvalue() and not any(m["level"] >= 2 for m in doc.findall(nodes.system_message))


def _process_docstring(app, what, name, obj, options, lines):
    if not lines or _clean_rst("\n".join(lines)):
        return
    _VERBATIM.append(name)
    body = ["    " + ln if ln.strip() else "" for ln in lines]
    lines[:] = ["(docstring shown verbatim)", "", "::", ""] + body + [""]


def _report_verbatim(app, exc):
    if exc is None and _VERBATIM:
        print(f"nmmm_docs: {len(_VERBATIM)} docstrings shown verbatim (not clean reST), e.g. {_VERBATIM[:5]}")


# --------------------------------------------------------------------------------------
# recipe reference from the pydantic schema


def _type_text(ann) -> str:
    origin = typing.get_origin(ann)
    if origin is typing.Annotated:
        return _type_text(typing.get_args(ann)[0])
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(ann) if a is not type(None)]
        text = " or ".join(_type_text(a) for a in args)
        return text + (" (optional)" if len(args) < len(typing.get_args(ann)) else "")
    if origin is typing.Literal:
        return "one of " + ", ".join(f'"{a}"' if isinstance(a, str) else repr(a) for a in typing.get_args(ann))
    if origin in (list, tuple):
        args = typing.get_args(ann)
        return f"list of {_type_text(args[0])}" if args else "list"
    if origin is dict:
        args = typing.get_args(ann)
        return f"table of {_type_text(args[1])}" if args else "table"
    names = {float: "number", int: "integer", str: "string", bool: "boolean", typing.Any: "any"}
    if ann in names:
        return names[ann]
    return getattr(ann, "__name__", str(ann))


def _constraints(field) -> str:
    out = []
    for m in field.metadata:
        for attr, sym in (("ge", "≥"), ("gt", ">"), ("le", "≤"), ("lt", "<"), ("min_length", "min length"),
                          ("max_length", "max length")):
            v = getattr(m, attr, None)
            if v is not None:
                out.append(f"{sym} {v}")
        f = getattr(m, "func", None)
        if f is not None and f.__doc__ is None:
            out.append({"_fraction": "in [0, 1]", "_positive": "> 0", "_non_negative": "≥ 0",
                        "_angle": "in (−90, 90)", "_aspecular": "in (−90, 180), not 0"}.get(f.__name__, f.__name__))
    ann = field.annotation
    for a in typing.get_args(ann) or ():
        for m in getattr(a, "__metadata__", ()):
            f = getattr(m, "func", None)
            if f is not None:
                out.append({"_fraction": "each in [0, 1]", "_positive": "each > 0", "_non_negative": "each ≥ 0",
                            "_angle": "each in (−90, 90)", "_aspecular": "each in (−90, 180), not 0"}.get(
                    f.__name__, f.__name__))
    return "; ".join(dict.fromkeys(out))


def _models_in(ann):
    from pydantic import BaseModel

    found = []
    stack = [ann]
    while stack:
        a = stack.pop()
        if isinstance(a, type) and issubclass(a, BaseModel):
            found.append(a)
        stack.extend(typing.get_args(a))
    return found


def _examples() -> dict[str, object]:
    from nmmm.recipes.schema import example_path, example_recipes

    seen: dict[str, object] = {}

    def walk(prefix, v):
        if isinstance(v, dict):
            for k, x in v.items():
                walk(f"{prefix}.{k}" if prefix else k, x)
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            for x in v:
                walk(prefix + "[]", x)
        else:
            seen.setdefault(prefix, v)

    for name in example_recipes():
        walk("", tomllib.loads(example_path(name).read_text()))
    return seen


def _generic(path: str) -> str:
    """``compounds.hematite.model`` -> ``compounds.NAME.model`` for lookup."""
    return path


def recipe_reference_rst() -> list[str]:
    from pydantic_core import PydanticUndefined

    from nmmm.recipes.labelled import units_of_key
    from nmmm.recipes.schema import Recipe

    examples = _examples()
    ex_generic = {}
    for k, v in examples.items():
        parts = k.split(".")
        if parts[0] == "compounds" and len(parts) > 2:
            parts[1] = "NAME"
        ex_generic.setdefault(".".join(parts), v)
    out: list[str] = []
    todo = [("", Recipe, "The whole recipe (top level).")]
    done = set()
    while todo:
        prefix, model, where = todo.pop(0)
        if (prefix, model) in done:
            continue
        done.add((prefix, model))
        title = f"``[{prefix}]``" if prefix else "Top level"
        doc = " ".join((model.__doc__ or "").split()) or where
        out += [title, "~" * len(title), "", doc.replace("*", r"\*"), "",
                ".. list-table::", "   :header-rows: 1", "   :widths: 22 18 8 14 20 18", "",
                "   * - key", "     - type", "     - unit", "     - default", "     - constraint", "     - example"]
        for name, field in model.model_fields.items():
            key = f"{prefix}.{name}" if prefix else name
            ann = field.annotation
            sub = _models_in(ann)
            default = field.default
            if default is PydanticUndefined:
                dtext = "required" if field.default_factory is None else "(table)"
                if field.default_factory is not None:
                    try:
                        dv = field.default_factory()
                        dtext = "(defaults)" if hasattr(dv, "model_fields") else repr(dv)
                    except TypeError:
                        pass
            else:
                dtext = repr(default)
            unit = units_of_key(name) or ""
            ex = ex_generic.get(key.replace("[]", ""), ex_generic.get(key, ""))
            if isinstance(ex, (dict, list)) and len(repr(ex)) > 60:
                ex = repr(ex)[:57] + "..."
            cells = [f"``{key}``", _type_text(ann), unit, dtext, _constraints(field), "" if ex == "" else repr(ex)]
            out.append("   * - " + _cell(cells[0]))
            out += ["     - " + _cell(c) for c in cells[1:]]
            origin = typing.get_origin(ann)
            for m in sub:
                is_dict = origin is dict or any(typing.get_origin(a) is dict for a in typing.get_args(ann))
                is_list = origin is list or any(typing.get_origin(a) is list for a in typing.get_args(ann))
                child = f"{key}.NAME" if is_dict else f"{key}[]" if is_list else key
                todo.append((child, m, f"Entries of ``{key}``."))
        out.append("")
    return out + _dispersion_units_rst()


_POWER = {"2": "²", "4": "⁴"}


def _dispersion_units_rst() -> list[str]:
    """The explicit-unit keys of dispersion coefficients (:data:`nmmm.materials.models.EXPLICIT_UNIT_KEYS`)
    as a table: a compound's ``params`` (and an ellipsometry ``model.toml`` layer) may give them."""
    from nmmm.materials.models import EXPLICIT_UNIT_KEYS

    title = "Units of dispersion-model coefficients"
    out = [title, "~" * len(title), "",
           "Wavelengths are in nm everywhere, but the published Cauchy and Sellmeier coefficients are in "
           "µm units: the plain keys ``B``, ``C`` of ``compounds.NAME.params`` are read in those µm units. "
           "Say the unit in the key instead (the shipped recipes do), or give nm units; the value is "
           "converted to the model's own unit. A coefficient given twice (``B`` and ``B_um2``) is an error.", "",
           ".. list-table::", "   :header-rows: 1", "", "   * - model", "     - key", "     - coefficient",
           "     - unit", "     - factor to the model's unit"]
    for model, keys in EXPLICIT_UNIT_KEYS.items():
        for key, (coef, factor) in keys.items():
            base, unit = key.split("_", 1)
            unit_text = unit[:2].replace("um", "µm") + _POWER.get(unit[2:], unit[2:])
            out += [f"   * - {model}", f"     - ``{key}``", f"     - ``{coef}``", f"     - {unit_text}",
                    f"     - {factor:g}"]
    return out + [""]


def _cell(text) -> str:
    text = str(text).replace("\n", " ")
    if text.startswith("``"):
        return text
    return text.replace("*", r"\*").replace("`", "'").replace("|", r"\|") or " "


class RecipeReference(Directive):
    def run(self):
        from sphinx.util.nodes import nested_parse_with_titles

        node = nodes.section()
        node.document = self.state.document
        nested_parse_with_titles(self.state, StringList(recipe_reference_rst(), source="nmmm.recipes.schema"), node)
        return node.children


# --------------------------------------------------------------------------------------
# API of a package


class PackageAPI(Directive):
    required_arguments = 1

    def run(self):
        import importlib

        pkg = self.arguments[0]
        mod = importlib.import_module(pkg)
        lines = []
        for name in getattr(mod, "__all__", []):
            obj = getattr(mod, name)
            if isinstance(obj, types.ModuleType):
                continue
            home = getattr(obj, "__module__", "") or ""
            top = pkg.split(".")[:2]
            if home.startswith("nmmm.") and home.split(".")[:2] != top and (callable(obj) or isinstance(obj, type)):
                # re-exported from another package: documented there once (one [source] link, one target)
                owner = ".".join(home.split(".")[:2])
                lines += [f"``{name}`` — re-exported from ``{owner}``: :py:obj:`{owner}.{name}`", ""]
                continue
            if isinstance(obj, type):
                lines += [f".. autoclass:: {pkg}.{name}", "   :members:", "   :no-inherited-members:", ""]
            elif callable(obj):
                lines += [f".. autofunction:: {pkg}.{name}", ""]
            else:
                lines += [f".. autodata:: {pkg}.{name}", "   :no-value:", ""]
        node = nodes.container()
        self.state.nested_parse(StringList(lines, source=pkg), 0, node)
        return node.children


# --------------------------------------------------------------------------------------
# gallery


def _example_doc(path: Path) -> tuple[str, str]:
    """The title (the docstring's first paragraph, on one line) and the description: prose paragraphs
    joined into single lines, so that the description box wraps them to its width; indented lines
    (commands) kept as they are."""
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or path.stem
    paragraphs = [p for p in doc.split("\n\n") if p.strip()]
    title = " ".join(ln.strip() for ln in paragraphs[0].splitlines())
    out = []
    for par in paragraphs[1:]:
        lines = par.splitlines()
        if all(ln.startswith(" ") for ln in lines if ln.strip()):
            out.append("\n".join(lines))
        else:
            out.append(" ".join(ln.strip() for ln in lines).replace("``", ""))  # plain text: no reST marks
    return title.strip().rstrip("."), "\n\n".join(out)


def build_gallery(app):
    src = Path(app.srcdir)
    gal = src / "gallery"
    gal.mkdir(exist_ok=True)
    run = set(app.config.nmmm_gallery_run)
    stored = src / "gallery_figures"
    entries = []
    for ex in sorted((ROOT / "examples").glob("*.py")):
        name = ex.stem
        if name.startswith("_") or name == "make_example_data":
            continue
        title, text = _example_doc(ex)
        figdir = gal / "_figures" / name
        if figdir.exists():
            shutil.rmtree(figdir)
        figdir.mkdir(parents=True)
        how = ""
        if name in run:
            work = gal / "_work" / name
            shutil.rmtree(work, ignore_errors=True)
            work.mkdir(parents=True)
            t0 = time.perf_counter()
            proc = subprocess.run([sys.executable, str(ex), str(work / "out")], cwd=work, capture_output=True,
                                  text=True, timeout=app.config.nmmm_gallery_timeout_s,
                                  env={**__import__("os").environ, "MPLBACKEND": "Agg", "PYTHONPATH": str(ROOT / "src")})
            if proc.returncode != 0:
                raise RuntimeError(f"gallery: examples/{ex.name} failed:\n{proc.stderr[-2000:]}")
            for png in sorted(work.rglob("*.png"))[:app.config.nmmm_gallery_max_figures]:
                shutil.copy(png, figdir / png.name)
            how = f"Run while these pages were built ({time.perf_counter() - t0:.1f} s); the figures below are its output."
        else:
            for png in sorted((stored / name).glob("*.png")) if (stored / name).exists() else []:
                shutil.copy(png, figdir / png.name)
            how = ("Not run while these pages were built (it takes too long for the documentation build); the "
                   "figures below are stored ones made by the same script (``docs/gallery_figures/"
                   f"{name}/``, regenerated by ``python docs/make_gallery_figures.py``).")
        figs = sorted(figdir.glob("*.png"))
        head = title.replace("*", r"\*")
        # the docstring as plain text in a box that wraps (docs/_static/nmmm.css), not a python listing
        lines = [f".. _gallery-{name}:", "", head, "=" * len(head), "", ".. code-block:: text",
                 "   :class: nmmm-description", ""]
        lines += ["   " + ln if ln.strip() else "" for ln in text.splitlines()] + [""]
        lines += [how, ""]
        if not figs:
            lines += ["This example writes no figure (its output is text or data files).", ""]
        for f in figs:
            lines += [f".. figure:: _figures/{name}/{f.name}", "   :width: 90%", "", f"   ``{f.name}``", ""]
        lines += ["Source", "------", "", f".. literalinclude:: ../../examples/{ex.name}", "   :language: python", ""]
        (gal / f"{name}.rst").write_text("\n".join(lines), encoding="utf-8")
        entries.append((name, head, figs[0] if figs else None))
    idx = ["Gallery", "=======", "", "The scripts of ``examples/``, one page each: what they show, their figures and "
           "their source. Run any of them with ``python examples/NAME.py [output_dir]``.", "",
           ".. toctree::", "   :maxdepth: 1", ""] + [f"   {n}" for n, _, _ in entries] + [""]
    for n, head, fig in entries:
        if fig is not None:
            idx += [f".. figure:: _figures/{n}/{fig.name}", "   :width: 45%", f"   :target: {n}.html", "",
                    f"   :ref:`gallery-{n}`", ""]
    (gal / "index.rst").write_text("\n".join(idx), encoding="utf-8")


def setup(app):
    app.add_config_value("nmmm_gallery_run", [], "env")
    app.add_config_value("nmmm_gallery_timeout_s", 120, "env")
    app.add_config_value("nmmm_gallery_max_figures", 6, "env")
    app.add_directive("nmmm-recipe-reference", RecipeReference)
    app.add_directive("nmmm-api", PackageAPI)
    app.connect("autodoc-process-docstring", _process_docstring, priority=900)
    app.connect("builder-inited", build_gallery)
    app.connect("build-finished", _report_verbatim)
    return {"parallel_read_safe": True, "version": "1"}
