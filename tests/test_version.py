"""The version is written in one place (pyproject.toml) and nmmm.__version__ reads it; py.typed ships."""

import tomllib
from pathlib import Path

import nmmm

ROOT = Path(__file__).resolve().parents[1]


def test_version_from_pyproject():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert nmmm.__version__ == project["project"]["version"]
    assert "__version__ = \"" not in (ROOT / "src" / "nmmm" / "__init__.py").read_text()


def test_py_typed_is_package_data():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert (ROOT / "src" / "nmmm" / "py.typed").exists()
    assert "py.typed" in project["tool"]["setuptools"]["package-data"]["nmmm"]
