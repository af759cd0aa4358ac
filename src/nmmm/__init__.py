"""nmmm — nano–micro–meso–macro: predictive colour and appearance of paints and coatings.

Data flows one way, from small scales to large, through one sub-package per scale, on a ground
floor (``errors``, ``spectra``, ``colour``) that every scale uses:
``materials`` → ``ema`` → ``microstructure`` → ``homogenize`` → ``layers`` → ``ellipsometry`` →
``appearance`` → ``experiment`` → ``recipes`` → ``demo``. Each imports only from those before it.

Conventions: wavelengths in nanometres at every public interface; n + ik with k ≥ 0;
ε = (n + ik)² with Im ε ≥ 0; time dependence exp(−iωt); volume fractions in [0, 1];
angles in degrees. Sub-packages are imported on demand (``import nmmm.layers``).
"""

from nmmm.errors import (
    ConvergenceError,
    DataFileError,
    InvalidInputError,
    MaterialNotFoundError,
    NmmmError,
    OutOfRangeError,
    RecipeError,
)

def _read_version() -> str:
    """The version from one place, pyproject.toml, through the installed package's metadata."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("nmmm")
    except PackageNotFoundError:  # run from a source tree that was never installed
        return "0+unknown"


__version__ = _read_version()

# before anything can launch Numba's threads: the pip ``tbb`` wheel's library made loadable, so the
# parallel kernels run on the fork- and thread-safe ``tbb`` layer rather than GNU OpenMP (see the module)
from nmmm._tbb_runtime import load_pip_tbb as _load_pip_tbb

_load_pip_tbb()

_SUBPACKAGES = ("errors", "spectra", "colour", "materials", "ema", "microstructure", "homogenize", "layers",
                "ellipsometry", "appearance", "experiment", "recipes", "demo")


def __getattr__(name):
    """Import a sub-package on first access, so ``import nmmm; nmmm.materials.get(...)`` works."""
    if name in _SUBPACKAGES:
        import importlib

        return importlib.import_module(f"nmmm.{name}")
    raise AttributeError(f"module 'nmmm' has no attribute {name!r}")

__all__ = [
    "ConvergenceError",
    "DataFileError",
    "InvalidInputError",
    "MaterialNotFoundError",
    "NmmmError",
    "OutOfRangeError",
    "RecipeError",
    "__version__",
]
