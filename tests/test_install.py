"""What ``pip install -e .`` (no extras) gives a new user is enough to import and run nmmm.

The test environment has the ``[test]`` extra installed, which drags in packages the core never
declares (pyElli pulls in h5py, which hid issue 14: since h5netcdf 1.7 h5py comes only with
``h5netcdf[h5py]``, and every ``results.nc`` is written with ``engine="h5netcdf"``). So:

- the dependency closures of ``[project] dependencies`` and of every optional-dependency group are
  read from ``pyproject.toml`` and the installed metadata; every import name that only the optional
  groups bring in is *blocked* in a subprocess by a ``sys.meta_path`` finder that raises ImportError;
- in that subprocess every module of nmmm is imported (``pkgutil.walk_packages``), and the file
  writers nmmm names in its source (``to_netcdf(engine=...)``, ``to_parquet``) are exercised;
  a failure names the module and the blocked package it reached for;
- every third-party import in ``src/nmmm`` (``ast``, imports inside functions included) must come
  from a core dependency, or be optional by design (:data:`OPTIONAL_IMPORTS`, with the reason);
- ``python -m nmmm --help`` works.
"""

from __future__ import annotations

import ast
import importlib.machinery
import importlib.metadata as metadata
import json
import re
import subprocess
import sys
import tomllib
from functools import cache
from pathlib import Path

import pytest
from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "nmmm"

#: import names nmmm uses on purpose without declaring them as core dependencies
OPTIONAL_IMPORTS = {
    "mitsuba": "the Mitsuba 3 plugins (extra nmmm[mitsuba]); imported inside require_mitsuba(), which "
               "raises MitsubaUnavailableError with the install hint",
    "drjit": "comes with mitsuba; imported only inside the Mitsuba plugin functions",
    "zarr": "extra nmmm[zarr]; imported only inside recipes.labelled.write_sweep_cube for sweeps of 1000+ "
            "points, which warns and keeps results.nc (the same cube) when zarr is missing",
}

#: always blocked, even where the metadata walk misses them (e.g. an extra that is not installed here)
TEST_ONLY_IMPORTS = {"miepython", "tmm", "iadpython", "elli", "pytest", "_pytest", "pytest_timeout",
                     "httpx", "playwright", "mitsuba", "drjit", "porespy"}


def _canonical(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _pyproject() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))


def dependency_closure(requirements: list[str]) -> tuple[set[str], set[str]]:
    """Installed distributions (canonical names) a list of requirement strings pulls in, extras and
    environment markers honoured; and the names required but not installed here."""
    found: set[str] = set()
    missing: set[str] = set()
    seen: set[tuple[str, frozenset[str]]] = set()
    todo = [(Requirement(r), frozenset({""})) for r in requirements]
    while todo:
        req, parent_extras = todo.pop()
        if req.marker is not None and not any(req.marker.evaluate({"extra": e}) for e in parent_extras):
            continue
        key = (_canonical(req.name), frozenset(req.extras))
        if key in seen:
            continue
        seen.add(key)
        try:
            dist = metadata.distribution(req.name)
        except metadata.PackageNotFoundError:
            missing.add(key[0])
            continue
        found.add(key[0])
        extras = frozenset({""} | set(req.extras))
        todo.extend((Requirement(r), extras) for r in (dist.requires or []))
    return found, missing


@cache
def core_and_optional() -> tuple[set[str], set[str]]:
    """(core closure, closure of all optional groups minus the core) as canonical distribution names."""
    project = _pyproject()["project"]
    core, _ = dependency_closure(project["dependencies"])
    optional: set[str] = set()
    for group in project.get("optional-dependencies", {}).values():
        optional |= dependency_closure(group)[0]
    return core, optional - core


@cache
def import_names() -> dict[str, set[str]]:
    """top-level import name -> canonical names of the installed distributions that provide it
    (``packages_distributions``, plus top-level extension modules such as ``OpenEXR.*.so``,
    which Python 3.11's inference from RECORD misses)."""
    names = {name: {_canonical(d) for d in dists} for name, dists in metadata.packages_distributions().items()}
    suffixes = tuple(importlib.machinery.all_suffixes())
    for dist in metadata.distributions():
        for file in dist.files or []:
            if len(file.parts) == 1 and file.name.endswith(suffixes):
                names.setdefault(file.name.partition(".")[0], set()).add(_canonical(dist.metadata["Name"]))
    return names


def blocked_imports() -> dict[str, str]:
    """Import names only the optional groups provide -> the distribution(s) they come from."""
    core, optional_only = core_and_optional()
    blocked = {}
    for name, dists in import_names().items():
        if dists & optional_only and not dists & core and name.isidentifier():
            blocked[name] = ", ".join(sorted(dists))
    for name in TEST_ONLY_IMPORTS:
        if not import_names().get(name, set()) & core:
            blocked.setdefault(name, "test-only")
    return blocked


def _third_party_imports() -> dict[str, set[str]]:
    """Top-level third-party import name -> nmmm modules that import it (anywhere in the module)."""
    out: dict[str, set[str]] = {}
    for path in sorted(SRC.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
                names = [node.module]
            else:
                continue
            for name in names:
                top = name.partition(".")[0]
                if top != "nmmm" and top not in sys.stdlib_module_names:
                    out.setdefault(top, set()).add(str(path.relative_to(SRC.parent)))
    return out


_IMPORT_ALL = r'''
import importlib, json, pkgutil, sys, tempfile, traceback
from pathlib import Path

BLOCKED = json.loads(sys.argv[1])
WRITERS = json.loads(sys.argv[2])
attempts = []

class BlockOptional:
    """Meta-path finder: the optional groups' packages are not installed in a bare environment."""
    def find_spec(self, name, path=None, target=None):
        top = name.partition(".")[0]
        if top in BLOCKED:
            attempts.append(top)
            raise ImportError(f"No module named {top!r} (blocked: only the optional extras install it, "
                              f"from {BLOCKED[top]})", name=name)
        return None

preloaded = sorted(m for m in sys.modules if m.partition(".")[0] in BLOCKED)
for m in preloaded:
    del sys.modules[m]
sys.meta_path.insert(0, BlockOptional())

report = {"preloaded": preloaded, "failed": {}, "reached": {}, "modules": [], "writers": {}}

def attempt(label, fn):
    before = len(attempts)
    try:
        fn()
    except BaseException as exc:  # noqa: BLE001 - report everything, name the module
        report["failed"][label] = {"error": f"{type(exc).__name__}: {exc}", "blocked": sorted(set(attempts[before:])),
                                   "traceback": traceback.format_exc(limit=-4)}
    else:
        if attempts[before:]:
            report["reached"][label] = sorted(set(attempts[before:]))

import nmmm
walk_errors = []
names = ["nmmm"] + [m.name for m in pkgutil.walk_packages(nmmm.__path__, "nmmm.", onerror=walk_errors.append)]
for name in walk_errors:
    attempt(name, lambda name=name: importlib.import_module(name))
for name in names:
    report["modules"].append(name)
    attempt(name, lambda name=name: importlib.import_module(name))

tmp = Path(tempfile.mkdtemp())
for engine in WRITERS["netcdf_engines"]:
    def write_nc(engine=engine):
        import numpy as np
        import xarray as xr
        ds = xr.Dataset({"reflectance": ("wavelength", np.array([0.1, 0.2]))}, coords={"wavelength": [400.0, 500.0]})
        ds.to_netcdf(tmp / f"{engine}.nc", engine=engine)
        with xr.open_dataset(tmp / f"{engine}.nc", engine=engine) as back:
            assert float(back["reflectance"][1]) == 0.2
    attempt(f"xarray.Dataset.to_netcdf(engine={engine!r})", write_nc)
if WRITERS["parquet"]:
    def write_parquet():
        import pandas as pd
        pd.DataFrame({"a": [1.0, 2.0]}).to_parquet(tmp / "t.parquet")
        assert pd.read_parquet(tmp / "t.parquet")["a"].tolist() == [1.0, 2.0]
    attempt("pandas.DataFrame.to_parquet", write_parquet)
print("@@REPORT@@" + json.dumps(report))
'''


def _writers() -> dict:
    source = "\n".join(p.read_text(encoding="utf-8") for p in SRC.rglob("*.py"))
    return {"netcdf_engines": sorted(set(re.findall(r"to_netcdf\([^)]*engine\s*=\s*[\"'](\w+)[\"']", source))),
            "parquet": ".to_parquet(" in source}


@cache
def _bare_import_report() -> dict:
    proc = subprocess.run([sys.executable, "-c", _IMPORT_ALL, json.dumps(blocked_imports()), json.dumps(_writers())],
                          capture_output=True, text=True, cwd=ROOT, timeout=600)
    marker = [line for line in proc.stdout.splitlines() if line.startswith("@@REPORT@@")]
    assert proc.returncode == 0 and marker, f"the import subprocess died (exit {proc.returncode}):\n{proc.stderr[-4000:]}"
    return json.loads(marker[-1][len("@@REPORT@@"):])


def test_optional_groups_are_blocked_not_core():
    """The blocker is meaningful: it blocks the test extra's own packages and never a core one."""
    blocked = blocked_imports()
    core, optional_only = core_and_optional()
    assert {"numpy", "scipy", "xarray", "h5netcdf", "h5py", "numba"} <= {n for n in import_names() if import_names()[n] & core}
    assert not set(blocked) & {"numpy", "scipy", "xarray", "h5netcdf", "h5py", "numba", "nmmm"}
    for name in ("pytest", "elli", "miepython", "tmm", "iadpython", "httpx", "playwright", "mitsuba"):
        assert name in blocked, f"{name} should be blocked as test-only; blocked: {sorted(blocked)}"


def test_every_module_imports_with_core_dependencies_only():
    report = _bare_import_report()
    assert len(report["modules"]) > 50, f"walk_packages found only {report['modules']}"
    lines = [f"{label}: {info['error']}" + (f"  [reached for blocked: {', '.join(info['blocked'])}]" if info["blocked"] else "")
             + "\n    " + info["traceback"].strip().replace("\n", "\n    ")
             for label, info in sorted(report["failed"].items()) if not label.startswith(("xarray.", "pandas."))]
    assert not lines, ("modules of nmmm that do not import with the core dependencies only "
                       "(declare the package in [project] dependencies or import it where it is optional):\n"
                       + "\n".join(lines))


def test_file_writers_work_with_core_dependencies_only():
    """results.nc (engine='h5netcdf') and sweep Parquet files need only the core dependencies."""
    writers = _writers()
    assert "h5netcdf" in writers["netcdf_engines"], writers
    report = _bare_import_report()
    lines = [f"{label}: {info['error']}  [reached for blocked: {', '.join(info['blocked']) or '-'}]"
             for label, info in sorted(report["failed"].items()) if label.startswith(("xarray.", "pandas."))]
    assert not lines, "file writers that need a package outside the core dependencies:\n" + "\n".join(lines)


def test_third_party_imports_are_core_dependencies_or_optional_by_design():
    core, _ = core_and_optional()
    names = import_names()
    problems = []
    for name, modules in sorted(_third_party_imports().items()):
        if name in OPTIONAL_IMPORTS:
            continue
        dists = names.get(name, set())
        if not dists & core:
            problems.append(f"{name} (from {', '.join(sorted(dists)) or 'no installed distribution'}) imported by "
                            f"{', '.join(sorted(modules))}")
    assert not problems, ("third-party imports that no core dependency provides: add the distribution to "
                          "[project] dependencies in pyproject.toml, or to OPTIONAL_IMPORTS with the reason:\n"
                          + "\n".join(problems))


def test_optional_imports_stay_inside_functions():
    """mitsuba/drjit are imported where they are used, so their modules import without them."""
    top_level = []
    for path in sorted(SRC.rglob("*.py")):
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                mods = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""]
                top_level += [f"{path.relative_to(SRC.parent)}: {m}" for m in mods if m.partition(".")[0] in OPTIONAL_IMPORTS]
    assert not top_level, "optional packages imported at module level:\n" + "\n".join(top_level)


def test_the_bug_of_issue_14_would_be_caught():
    """Without h5netcdf's [h5py] extra, h5py is only a test-extra package here, so it is blocked."""
    project = _pyproject()["project"]
    old_core = [r if _canonical(Requirement(r).name) != "h5netcdf" else "h5netcdf>=1.3" for r in project["dependencies"]]
    h5netcdf_requires = metadata.distribution("h5netcdf").requires or []
    if not any(Requirement(r).name == "h5py" and Requirement(r).marker is not None for r in h5netcdf_requires):
        pytest.skip("this h5netcdf (< 1.7) still requires h5py unconditionally")
    assert "h5py" not in dependency_closure(old_core)[0]
    assert "h5py" in core_and_optional()[0], "h5py must come with the core dependencies (h5netcdf[h5py])"


@pytest.mark.parametrize("args", [["--help"], ["demo", "--help"]])
def test_python_dash_m_nmmm(args):
    proc = subprocess.run([sys.executable, "-m", "nmmm", *args], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, f"python -m nmmm {' '.join(args)} exited {proc.returncode}:\n{proc.stderr}"
    assert proc.stdout.startswith("Usage: python -m nmmm"), proc.stdout[:300]
    if args == ["--help"]:
        for command in ("demo", "run", "materials", "render"):
            assert command in proc.stdout
