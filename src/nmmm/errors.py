"""The one error hierarchy of nmmm.

Every error message says what was wrong and what would be right.

- :class:`NmmmError` — base of all nmmm errors.
- :class:`OutOfRangeError` — a wavelength (or other parameter) outside the domain of
  the data or formula; a ``ValueError``.
- :class:`InvalidInputError` — NaN, infinities, negative k, fractions outside [0, 1],
  non-physical model parameters; a ``ValueError``.
- :class:`MaterialNotFoundError` — an unknown database key; a ``KeyError`` listing close
  matches.
- :class:`DataFileError` — a missing or malformed file, naming the path (and row).
- :class:`ConvergenceError` — an iterative solver or a fit that did not converge; it
  carries its diagnostics (e.g. the residual history).
- :class:`RecipeError` — an invalid recipe, naming the offending key.
"""

from __future__ import annotations


class NmmmError(Exception):
    """Base class of every error raised by nmmm."""


class InvalidInputError(NmmmError, ValueError):
    """An input value is not physical or not finite (NaN, k < 0, fraction outside [0, 1])."""


class OutOfRangeError(InvalidInputError):
    """A value lies outside the validity range of data or of a formula.

    Raised, for instance, for a wavelength outside a material's tabulated range: nothing
    is extrapolated silently.
    """


class MaterialNotFoundError(NmmmError, KeyError):
    """An unknown material key; the message lists close matches."""

    def __str__(self) -> str:  # KeyError quotes its message; keep it readable
        return str(self.args[0]) if self.args else ""


class DataFileError(NmmmError, ValueError):
    """A missing, unreadable or malformed data file; the message names the path and row."""


class ConvergenceError(NmmmError, RuntimeError):
    """An iterative computation did not converge.

    Attributes
    ----------
    history : list of float or None
        The residual (or cost) history, for diagnosis.
    """

    def __init__(self, message: str, history=None):
        super().__init__(message)
        self.history = history


class RecipeError(NmmmError, ValueError):
    """An invalid recipe; the message names the offending key."""


__all__ = [
    "NmmmError",
    "InvalidInputError",
    "OutOfRangeError",
    "MaterialNotFoundError",
    "DataFileError",
    "ConvergenceError",
    "RecipeError",
]
