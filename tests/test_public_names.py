"""Every public name of every nmmm package resolves, always to the same object, of the documented kind.

Issue 14 item 6: a package that exported a function lazily (PEP 562 ``__getattr__``) or eagerly from a
submodule *of the same name* handed out the submodule once that submodule had been imported anywhere
(importing ``pkg.name`` binds the attribute ``name`` of ``pkg`` to the module). So, for every package
found under ``src/nmmm`` (new packages are covered when they appear), in a fresh subprocess:

- every name in ``__all__`` resolves twice as ``from pkg import name`` and twice as ``getattr(pkg, name)``,
  then again after importing every submodule of the package, to the very same object each time;
- that object is a module only if the package docstring documents it as ``:mod:``; a name documented as
  ``:func:`` is a callable that is not a module, ``:class:`` / ``:exc:`` a class;
- no submodule of the package has the name of an entry of its ``__all__``.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from functools import cache
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGES = sorted(".".join(p.parent.relative_to(SRC).parts) for p in (SRC / "nmmm").rglob("__init__.py"))

_RESOLVE = r'''
import importlib, json, pkgutil, sys

pkg_name = sys.argv[1]
pkg = importlib.import_module(pkg_name)
doc = pkg.__doc__ or ""
names = getattr(pkg, "__all__", None)
report = {"has_all": names is not None, "doc": doc, "problems": [], "kinds": {}, "submodules": [],
          "import_errors": {}}
names = list(names or [])
first = {}

def note(name, how, obj):
    if name not in first:
        first[name] = obj
    elif obj is not first[name]:
        report["problems"].append(f"{name}: {how} gave {obj!r}, not the {first[name]!r} it gave before")

def resolve_all(stage):
    for name in names:
        for attempt in (1, 2):
            try:
                ns = {}
                exec(f"from {pkg_name} import {name}", ns)
                note(name, f"'from {pkg_name} import {name}' ({stage}, #{attempt})", ns[name])
            except Exception as exc:
                report["problems"].append(f"{name}: 'from {pkg_name} import {name}' ({stage}) raised {exc!r}")
            try:
                note(name, f"getattr({pkg_name}, {name!r}) ({stage}, #{attempt})", getattr(pkg, name))
            except Exception as exc:
                report["problems"].append(f"{name}: getattr({pkg_name}, {name!r}) ({stage}) raised {exc!r}")

resolve_all("fresh interpreter")
report["submodules"] = sorted(m.name for m in pkgutil.iter_modules(pkg.__path__))
for info in pkgutil.walk_packages(pkg.__path__, pkg_name + ".", onerror=lambda n: None):
    try:
        importlib.import_module(info.name)
    except Exception as exc:  # reported: test_install names the missing dependency
        report["import_errors"][info.name] = repr(exc)
resolve_all("after importing every submodule")

for name, obj in first.items():
    report["kinds"][name] = {"module": isinstance(obj, type(sys)), "class": isinstance(obj, type),
                             "callable": callable(obj), "type": type(obj).__name__}
print("@@REPORT@@" + json.dumps(report))
'''

#: Sphinx roles of the package docstrings -> the kind of object they promise
_ROLE = re.compile(r":(mod|func|meth|class|exc|data|attr|obj):`~?([\w.]+)`")


@cache
def _report(package: str) -> dict:
    proc = subprocess.run([sys.executable, "-c", _RESOLVE, package], capture_output=True, text=True, timeout=600)
    marker = [line for line in proc.stdout.splitlines() if line.startswith("@@REPORT@@")]
    assert proc.returncode == 0 and marker, f"importing {package} failed (exit {proc.returncode}):\n{proc.stderr[-4000:]}"
    return json.loads(marker[-1][len("@@REPORT@@"):])


def documented_kinds(package: str, doc: str, names: set[str]) -> dict[str, set[str]]:
    """name -> the roles the docstring gives it, for roles naming ``name`` or ``package.name``."""
    kinds: dict[str, set[str]] = {}
    for role, target in _ROLE.findall(doc):
        name = target.removeprefix(package + ".")
        if name in names:
            kinds.setdefault(name, set()).add(role)
    return kinds


def test_every_package_is_found():
    for package in ("nmmm", "nmmm.ema", "nmmm.layers", "nmmm.ellipsometry", "nmmm.microstructure",
                    "nmmm.appearance", "nmmm.appearance.render", "nmmm.recipes"):
        assert package in PACKAGES


@pytest.mark.parametrize("package", PACKAGES)
def test_public_names_resolve_to_one_object(package):
    report = _report(package)
    assert report["has_all"], f"{package} has no __all__: say which names are public"
    assert not report["problems"], f"{package}: public names that do not resolve to one object:\n" + "\n".join(
        report["problems"])


@pytest.mark.parametrize("package", PACKAGES)
def test_public_names_are_of_the_documented_kind(package):
    report = _report(package)
    kinds = report["kinds"]
    documented = documented_kinds(package, report["doc"], set(kinds))
    wrong = []
    for name, kind in sorted(kinds.items()):
        roles = documented.get(name, set())
        if "mod" in roles:
            if not kind["module"]:
                wrong.append(f"{name}: documented as :mod: but is a {kind['type']}")
            continue
        if kind["module"]:
            wrong.append(f"{name}: is a module, documented as {sorted(roles) or 'nothing'} "
                         "(a submodule shadows the public name, or the export points at the module)")
        if roles & {"func", "meth"} and not kind["callable"]:
            wrong.append(f"{name}: documented as :func: but is a non-callable {kind['type']}")
        if roles & {"class", "exc"} and not kind["class"]:
            wrong.append(f"{name}: documented as :class: but is a {kind['type']}")
    assert not wrong, f"{package}: public names of the wrong kind:\n" + "\n".join(wrong)


@pytest.mark.parametrize("package", PACKAGES)
def test_no_submodule_named_like_a_public_name(package):
    report = _report(package)
    clash = sorted(set(report["submodules"]) & set(report["kinds"]))
    assert not clash, (f"{package}: submodules named like public names {clash}: importing the submodule rebinds "
                       f"the package attribute; rename the module (e.g. {clash[0]}_rule / {clash[0]}_method)")
