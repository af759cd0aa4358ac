"""Ellipsometric data sets (Ψ, Δ at wavelengths and angles) and their files.

Public objects
--------------
- :class:`EllipsometryData` — flat arrays of wavelength, angle, Ψ, Δ and optional σΨ, σΔ.
- :func:`read_csv` — plain CSV with a header naming the columns.
- :func:`read_woollam` — J. A. Woollam ASCII exports (WVASE ``.dat``, CompleteEASE).
- :func:`read_data` — dispatcher on the file's content/suffix (``DATA_READERS`` registry).
- :func:`write_csv` — write a data set as plain CSV (readable by :func:`read_csv`).
- :func:`write_material_csv` — write fitted n, k as a Material file for
  ``nmmm.materials.read_csv``.
- :class:`DataScan` — what the readers found wrong in a file before using it (rows with NaN,
  truncated lines, repeated or unsorted points); ``data.metadata["scan"]``.

Every reader scans the file first. Rows with a NaN / infinite value and truncated lines (fewer
numbers than the other data lines: a file cut off mid-line would otherwise be read with the
wrong columns, e.g. ``E 660 70 26.600 1`` as Δ = 1°) are left out *with a warning naming the
lines*; repeated (wavelength, angle) points and wavelengths out of order within one angle are
warned about. With ``strict=True`` (``nmmm ellipsometry fit --strict``) each of these is a
:class:`DataFileError` instead.

Plain CSV format
----------------
Comma-separated (``#`` starts a comment line), one header row naming the columns, case and
spaces ignored; the wavelength column name carries its unit::

    wavelength_nm, angle_deg, psi_deg, delta_deg, sigma_psi_deg, sigma_delta_deg
    400, 65, 22.41, 118.6, 0.02, 0.05

Accepted names: ``wavelength_nm`` / ``wavelength`` (nm), ``wavelength_um``, ``energy_ev``;
``angle_deg`` / ``angle`` / ``aoi``; ``psi_deg`` / ``psi``; ``delta_deg`` / ``delta``;
optional ``sigma_psi_deg`` / ``sigma_psi`` / ``psi_err`` and ``sigma_delta_deg`` /
``sigma_delta`` / ``delta_err``. A missing required column raises :class:`DataFileError`.

Woollam ASCII format (WVASE32 ``.dat`` and CompleteEASE export)
--------------------------------------------------------------
Header lines first (a title, optional ``VASEmethod[...]`` / ``Original[...]`` lines), the
last of which names the spectral unit: ``nm``, ``eV``, ``Angstroms`` or ``microns``/``um``.
Then one line per data point, whitespace separated, either

    E  <wavelength>  <angle>  <Ψ>  <Δ>  <σΨ>  <σΔ>     (tagged; CompleteEASE, WVASE "E" lines)
    <wavelength>  <angle>  <Ψ>  <Δ>  <σΨ>  <σΔ>        (untagged WVASE tabular)

Only ellipsometric Ψ/Δ lines (tag ``E``) are read; other tags (``T``, ``R``, ``dpolE`` …)
are skipped and counted in ``metadata``. The tan Ψ / cos Δ variant (``nm TRIG`` header) is
refused with a clear error. σ columns are optional; columns after the sixth (depolarization)
are ignored. Δ is taken in the usual convention (0° < Δ < 180° for a bulk absorber).
"""

from __future__ import annotations

import csv
import io
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from nmmm.ellipsometry.forward import check_angle_deg, check_psi_deg
from nmmm.errors import DataFileError, InvalidInputError
from nmmm.materials.material import HC_EV_NM
from nmmm.spectra import as_wavelength_nm, check_finite, check_positive

__all__ = [
    "EllipsometryData",
    "read_csv",
    "read_woollam",
    "read_data",
    "write_csv",
    "write_material_csv",
    "DATA_READERS",
    "DataScan",
]


@dataclass(frozen=True, repr=False)
class EllipsometryData:
    """Measured (or simulated) Ψ and Δ at N (wavelength, angle) points — flat arrays of length N.

    Attributes
    ----------
    wavelength_nm, angle_deg, psi_deg, delta_deg : ndarray (N,)
    sigma_psi_deg, sigma_delta_deg : ndarray (N,) or None
        Standard uncertainties; ``None`` when the file gave none (fits then scale the
        parameter covariance by the reduced χ²).
    name : str
    metadata : dict
    """

    wavelength_nm: np.ndarray
    angle_deg: np.ndarray
    psi_deg: np.ndarray
    delta_deg: np.ndarray
    sigma_psi_deg: np.ndarray | None = None
    sigma_delta_deg: np.ndarray | None = None
    name: str = "data"
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        w = as_wavelength_nm(np.atleast_1d(self.wavelength_nm)).ravel()
        n = w.size
        if n == 0:
            raise InvalidInputError(f"{self.name}: no data points")

        def _vec(x, what):
            a = np.asarray(x, dtype=float)
            if a.ndim == 0:
                a = np.full(n, float(a))
            a = a.ravel()
            if a.size != n:
                raise InvalidInputError(f"{self.name}: {what} has {a.size} values but wavelength_nm has {n}")
            return a

        a = check_angle_deg(_vec(self.angle_deg, "angle_deg"), f"{self.name}: angle_deg")
        p = check_psi_deg(_vec(self.psi_deg, "psi_deg"), f"{self.name}: psi_deg")
        d = check_finite(_vec(self.delta_deg, "delta_deg"), f"{self.name}: delta_deg")
        object.__setattr__(self, "wavelength_nm", w)
        object.__setattr__(self, "angle_deg", a)
        object.__setattr__(self, "psi_deg", p)
        object.__setattr__(self, "delta_deg", d)
        for attr in ("sigma_psi_deg", "sigma_delta_deg"):
            s = getattr(self, attr)
            if s is not None:
                s = check_positive(_vec(s, attr), f"{self.name}: {attr}")
                object.__setattr__(self, attr, s)
        if (self.sigma_psi_deg is None) != (self.sigma_delta_deg is None):
            raise InvalidInputError(f"{self.name}: give both sigma_psi_deg and sigma_delta_deg, or neither")

    # -- convenience ------------------------------------------------------------------
    def __len__(self) -> int:
        return self.wavelength_nm.size

    def __repr__(self) -> str:
        return (f"<EllipsometryData '{self.name}': {len(self)} points, "
                f"{self.wavelength_nm.min():g}-{self.wavelength_nm.max():g} nm, "
                f"angles {', '.join(f'{a:g}' for a in self.angles_deg)} deg>")

    @property
    def has_sigma(self) -> bool:
        return self.sigma_psi_deg is not None

    @property
    def angles_deg(self) -> np.ndarray:
        """The distinct angles of incidence."""
        return np.unique(self.angle_deg)

    def subset(self, mask) -> "EllipsometryData":
        """The points where ``mask`` is true (boolean or index array)."""
        m = np.asarray(mask)
        sig = (None, None) if not self.has_sigma else (self.sigma_psi_deg[m], self.sigma_delta_deg[m])
        return EllipsometryData(self.wavelength_nm[m], self.angle_deg[m], self.psi_deg[m], self.delta_deg[m],
                                sig[0], sig[1], name=self.name, metadata=dict(self.metadata))

    def at_angle(self, angle_deg=None) -> "EllipsometryData":
        """Points at one angle (default: the only one), sorted by wavelength."""
        angles = self.angles_deg
        if angle_deg is None:
            if angles.size != 1:
                raise InvalidInputError(
                    f"{self.name} holds several angles ({', '.join(f'{a:g}' for a in angles)} deg); "
                    "choose one with angle_deg=")
            angle_deg = angles[0]
        sel = np.isclose(self.angle_deg, float(angle_deg), atol=1e-6)
        if not sel.any():
            raise InvalidInputError(f"{self.name} has no data at {angle_deg:g} deg; it has "
                                    f"{', '.join(f'{a:g}' for a in angles)} deg")
        idx = np.flatnonzero(sel)
        idx = idx[np.argsort(self.wavelength_nm[idx], kind="stable")]
        return self.subset(idx)

    def within(self, wavelength_min_nm=None, wavelength_max_nm=None) -> "EllipsometryData":
        """Points inside a wavelength window."""
        lo = -np.inf if wavelength_min_nm is None else wavelength_min_nm
        hi = np.inf if wavelength_max_nm is None else wavelength_max_nm
        m = (self.wavelength_nm >= lo) & (self.wavelength_nm <= hi)
        if not m.any():
            raise InvalidInputError(f"{self.name}: no data between {lo:g} and {hi:g} nm")
        return self.subset(m)

    @classmethod
    def from_model(cls, stack, wavelength_nm, angle_deg, sigma_psi_deg=None, sigma_delta_deg=None,
                   noise_seed=None, name: str = "synthetic") -> "EllipsometryData":
        """Synthetic data of ``stack`` on the grid wavelength × angle; with ``noise_seed`` set,
        Gaussian noise of the given σ is added (a synthetic measurement)."""
        from nmmm.ellipsometry.forward import psi_delta

        w = as_wavelength_nm(np.atleast_1d(wavelength_nm)).ravel()
        a = check_angle_deg(np.atleast_1d(angle_deg)).ravel()
        W, A = np.meshgrid(w, a, indexing="ij")
        W, A = W.ravel(), A.ravel()
        psi, delta = psi_delta(stack, W, A)
        sp = None if sigma_psi_deg is None else np.broadcast_to(np.asarray(sigma_psi_deg, float), W.shape).copy()
        sd = None if sigma_delta_deg is None else np.broadcast_to(np.asarray(sigma_delta_deg, float), W.shape).copy()
        if noise_seed is not None:
            if sp is None or sd is None:
                raise InvalidInputError("noise needs sigma_psi_deg and sigma_delta_deg")
            rng = np.random.default_rng(noise_seed)
            psi = np.clip(psi + rng.normal(0.0, sp), 0.0, 90.0)
            delta = delta + rng.normal(0.0, sd)
        return cls(W, A, psi, delta, sp, sd, name=name, metadata={"source": "model"})

    def to_dataframe(self):
        """A pandas DataFrame of the columns (pandas is optional, imported here only)."""
        import pandas as pd

        cols = {"wavelength_nm": self.wavelength_nm, "angle_deg": self.angle_deg,
                "psi_deg": self.psi_deg, "delta_deg": self.delta_deg}
        if self.has_sigma:
            cols.update(sigma_psi_deg=self.sigma_psi_deg, sigma_delta_deg=self.sigma_delta_deg)
        return pd.DataFrame(cols)


# ----------------------------------------------------------------------------------------
# pre-scan of a measured file
# ----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class DataScan:
    """What a reader found in a file before using it.

    Attributes
    ----------
    path : str
    n_points : int
        Data points kept.
    dropped_nonfinite : tuple of int
        Line (CSV: data row) numbers left out because a value is NaN or infinite.
    dropped_truncated : tuple of int
        Lines left out because they hold fewer numbers than the other data lines.
    duplicates : int
        Repeated (wavelength, angle) points (kept; a fit weights them twice).
    unsorted_angles : tuple of float
        Angles whose wavelengths are not in increasing or decreasing order.
    dropped_cut : tuple of int
        The last line, left out because the file does not end with a newline and the line's last
        number has far fewer digits than that column elsewhere (a file cut off mid-number).
    """

    path: str
    n_points: int
    dropped_nonfinite: tuple = ()
    dropped_truncated: tuple = ()
    duplicates: int = 0
    unsorted_angles: tuple = ()
    dropped_cut: tuple = ()

    @property
    def problems(self) -> list:
        """One sentence per problem found (empty for a clean file)."""
        out = []

        def lines(nums):
            shown = ", ".join(str(n) for n in nums[:8])
            return shown + (f" and {len(nums) - 8} more" if len(nums) > 8 else "")

        if self.dropped_nonfinite:
            out.append(f"{len(self.dropped_nonfinite)} row(s) with a NaN or infinite value left out (line "
                       f"{lines(self.dropped_nonfinite)})")
        if self.dropped_truncated:
            out.append(f"{len(self.dropped_truncated)} truncated line(s) left out, fewer numbers than the other data "
                       f"lines (line {lines(self.dropped_truncated)}; a file cut off mid-line?)")
        if self.dropped_cut:
            out.append(f"last line {lines(self.dropped_cut)} left out: the file does not end with a newline and the "
                       "line's last number has far fewer digits than that column elsewhere (a file cut off "
                       "mid-number?)")
        if self.duplicates:
            out.append(f"{self.duplicates} repeated (wavelength, angle) point(s), weighted twice in a fit")
        if self.unsorted_angles:
            out.append("wavelengths out of order at angle(s) "
                       + ", ".join(f"{a:g}" for a in self.unsorted_angles) + " deg (points merged from several runs?)")
        return out

    @property
    def clean(self) -> bool:
        return not self.problems

    def summary(self) -> str:
        head = f"scan of {self.path}: {self.n_points} points kept"
        return head + ("; no problems found" if self.clean else "; " + "; ".join(self.problems))


def _digits(field: str) -> int:
    """Digits in the mantissa of a number as written (``'34.377'`` -> 5, ``'1'`` -> 1)."""
    return sum(ch.isdigit() for ch in re.split(r"[eE]", field)[0])


def _cut_last_line(text: str, fields: list, line_nos) -> tuple:
    """``(line,)`` when the file does not end with a newline and its last data line's last number
    has fewer than half the digits (median) of that column in the other lines: a line cut off
    mid-number (``E 1000 75 34.377 1`` read as Delta = 1 deg); else ``()``."""
    if not fields or len(fields) < 2 or text.endswith(("\n", "\r")):
        return ()
    j = len(fields[-1]) - 1
    others = [_digits(f[j]) for f in fields[:-1] if len(f) > j]
    if others and _digits(fields[-1][j]) < 0.5 * float(np.median(others)):
        return (int(line_nos[-1]),)
    return ()


def _scan_rows(path, rows, line_nos, min_fields: int, strict: bool, used=(0, 1, 2, 3), sigma=(4, 5), cut=()):
    """Drop non-finite and truncated rows of ``rows`` (``(values, count)``: floats NaN-padded to a
    common width and the count of numbers the line held; ``line_nos`` their line numbers),
    returning (array, dropped info). ``min_fields``: the fewest numbers a row may have before it
    counts as truncated; ``used`` / ``sigma``: the columns read (σ only when the rows have them);
    ``cut``: line numbers of a last line cut mid-number (:func:`_cut_last_line`), left out too."""
    counts = np.array([r[1] for r in rows])
    full = int(np.max(counts)) if counts.size else 0
    # the usual width of a data line: lines shorter than it (and shorter than min_fields, or the
    # last line) are truncated
    values, widths = np.unique(counts, return_counts=True)
    usual = int(values[np.argmax(widths)]) if counts.size else 0
    arr = np.array([r[0] for r in rows], dtype=float) if rows else np.zeros((0, full))
    trunc = (counts < usual) | (counts < min_fields)
    cut_row = np.zeros(counts.shape, bool)
    if cut and counts.size and int(line_nos[-1]) in cut and not trunc[-1]:
        cut_row[-1] = True  # a short last line is reported as truncated already
    cut = np.asarray(line_nos)[cut_row]
    trunc_or_cut = trunc | cut_row
    nonfinite = ~trunc_or_cut & ~np.all(np.isfinite(arr[:, list(used)]), axis=1) if arr.size else np.zeros(0, bool)
    if arr.size and sigma and usual > max(sigma):  # the sigma columns are read: they must be finite as well
        nonfinite |= ~trunc_or_cut & ~np.all(np.isfinite(arr[:, list(sigma)]), axis=1)
    keep = ~(trunc_or_cut | nonfinite)
    info = dict(dropped_nonfinite=tuple(int(n) for n in np.asarray(line_nos)[nonfinite]),
                dropped_truncated=tuple(int(n) for n in np.asarray(line_nos)[trunc]))
    info["dropped_cut"] = tuple(int(n) for n in cut)
    if strict and (info["dropped_nonfinite"] or info["dropped_truncated"] or info["dropped_cut"]):
        scan = DataScan(str(path), int(keep.sum()), **info)
        raise DataFileError(f"{path}: " + "; ".join(q.replace(" left out", "") for q in scan.problems)
                            + " (strict: fix the file, or run without --strict to leave these rows out)")
    if not keep.any():
        raise DataFileError(f"{path}: no complete, finite data row (" +
                            "; ".join(DataScan(str(path), 0, **info).problems) + ")")
    return arr[keep], info


def _finish_scan(path, wl, angle, info, strict: bool) -> DataScan:
    """Count repeated and unsorted points, warn (or, ``strict``, raise) for every problem."""
    pts = np.stack([np.round(wl, 6), np.round(angle, 6)], axis=1)
    dup = int(pts.shape[0] - np.unique(pts, axis=0).shape[0])
    unsorted = []
    for a in np.unique(np.round(angle, 6)):
        w = wl[np.round(angle, 6) == a]
        d = np.diff(w)
        if w.size > 2 and not (np.all(d >= 0) or np.all(d <= 0)):
            unsorted.append(float(a))
    scan = DataScan(str(path), int(wl.size), duplicates=dup, unsorted_angles=tuple(unsorted), **info)
    if not scan.clean:
        if strict:
            raise DataFileError(f"{path}: " + "; ".join(scan.problems) + " (strict)")
        warnings.warn(f"{path}: " + "; ".join(scan.problems), UserWarning, stacklevel=3)
    return scan


# ----------------------------------------------------------------------------------------
# plain CSV
# ----------------------------------------------------------------------------------------
_ALIASES = {
    "wavelength_nm": ("wavelength_nm", "wavelength", "lambda_nm", "wl_nm", "wl"),
    "wavelength_um": ("wavelength_um", "wavelength_µm", "wavelength_micron"),
    "energy_ev": ("energy_ev", "energy", "e_ev"),
    "angle_deg": ("angle_deg", "angle", "aoi", "aoi_deg", "angle_of_incidence"),
    "psi_deg": ("psi_deg", "psi", "ψ"),
    "delta_deg": ("delta_deg", "delta", "δ"),
    "sigma_psi_deg": ("sigma_psi_deg", "sigma_psi", "psi_err", "psi_sigma", "dpsi"),
    "sigma_delta_deg": ("sigma_delta_deg", "sigma_delta", "delta_err", "delta_sigma", "ddelta"),
}


def _norm(name: str) -> str:
    return re.sub(r"[\s\-()\[\]]+", "_", name.strip().lower()).strip("_")


def read_csv(path, name: str | None = None, strict: bool = False) -> EllipsometryData:
    """Read a plain CSV of Ψ, Δ (see the module docstring for the columns).

    Raises :class:`DataFileError` naming the file (and row) when it is missing, a required
    column is absent, or a value is not a number; :class:`InvalidInputError` for values
    out of range (Ψ outside [0°, 90°], ...). Rows with NaN and short rows are left out with a
    warning (``strict=True``: refused); the scan is ``data.metadata["scan"]``.
    """
    path = Path(path)
    if not path.is_file():
        raise DataFileError(f"ellipsometry data file not found: {path}")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise DataFileError(f"{path}: not UTF-8 text; expected a CSV with the header "
                            "wavelength_nm, angle_deg, psi_deg, delta_deg[, sigma_psi_deg, sigma_delta_deg]") from None
    numbered = [(i, ln) for i, ln in enumerate(text.splitlines(), start=1)
                if ln.strip() and not ln.lstrip().startswith("#")]
    lines = [ln for _, ln in numbered]
    if len(lines) < 2:
        raise DataFileError(f"{path}: needs a header row and at least one data row")
    reader = csv.reader(io.StringIO("\n".join(lines)))
    header = [_norm(h) for h in next(reader)]
    col = {}
    for key, aliases in _ALIASES.items():
        for i, h in enumerate(header):
            if h in aliases:
                col[key] = i
                break
    wl_keys = [k for k in ("wavelength_nm", "wavelength_um", "energy_ev") if k in col]
    missing = [k for k in ("angle_deg", "psi_deg", "delta_deg") if k not in col]
    if not wl_keys:
        missing.insert(0, "wavelength_nm (or wavelength_um / energy_ev)")
    if missing:
        raise DataFileError(
            f"{path}: missing column(s) {', '.join(missing)}; the header has {', '.join(header)}. "
            "Expected: wavelength_nm, angle_deg, psi_deg, delta_deg[, sigma_psi_deg, sigma_delta_deg]")
    rows, row_nos = [], []
    needed = max(col.values()) + 1
    for r_i, row in enumerate(reader, start=2):
        cells = [x for x in row[: len(header)]]
        while cells and not cells[-1].strip():
            cells.pop()
        try:
            vals = [float(x) if x.strip() else np.nan for x in cells]
        except ValueError:
            raise DataFileError(f"{path}, data row {r_i}: not a number in {_shown_row(row)}") from None
        rows.append((vals + [np.nan] * (len(header) - len(vals)), min(len(vals), needed)))
        row_nos.append(numbered[r_i - 1][0] if reader.line_num == r_i else r_i)
    used = [col[k] for k in (wl_keys[0], "angle_deg", "psi_deg", "delta_deg")]
    sig_cols = [col[k] for k in ("sigma_psi_deg", "sigma_delta_deg") if k in col]
    arr, info = _scan_rows(path, rows, row_nos, needed, strict, used=used, sigma=sig_cols)
    wkey = wl_keys[0]
    wl = arr[:, col[wkey]]
    if wkey == "wavelength_um":
        wl = wl * 1e3
    elif wkey == "energy_ev":
        if np.any(wl <= 0):
            raise DataFileError(f"{path}: photon energies must be > 0 eV")
        wl = HC_EV_NM / wl
    psi = arr[:, col["psi_deg"]]
    outside = np.flatnonzero((psi < 0) | (psi > 90))
    if outside.size:
        i = int(outside[0])
        raise InvalidInputError(
            f"{path}, data row {i + 2}: psi_deg must lie in [0, 90] degrees (tan Psi = |r_p/r_s|), got {psi[i]:g}"
            f"{f' ({outside.size} rows in all)' if outside.size > 1 else ''}. Psi in radians, or tan(Psi)/cos(Delta) "
            "data? Convert first.")
    has_sig = "sigma_psi_deg" in col and "sigma_delta_deg" in col
    if ("sigma_psi_deg" in col) != ("sigma_delta_deg" in col):
        given, absent = ("sigma_psi_deg", "sigma_delta_deg") if "sigma_psi_deg" in col else \
            ("sigma_delta_deg", "sigma_psi_deg")
        raise DataFileError(f"{path}: has a {given} column but no {absent}; give both uncertainty columns "
                            "or neither (without them the fit scales its covariance by the reduced chi²)")
    scan = _finish_scan(path, wl, arr[:, col["angle_deg"]], info, strict)
    try:
        return EllipsometryData(
            wl, arr[:, col["angle_deg"]], arr[:, col["psi_deg"]], arr[:, col["delta_deg"]],
            arr[:, col["sigma_psi_deg"]] if has_sig else None,
            arr[:, col["sigma_delta_deg"]] if has_sig else None,
            name=name or path.stem, metadata={"path": str(path), "format": "csv", "scan": scan})
    except InvalidInputError as exc:
        raise InvalidInputError(f"{path}: {exc}") from None


def write_csv(data: EllipsometryData, path) -> Path:
    """Write ``data`` as a plain CSV that :func:`read_csv` reads back."""
    path = Path(path)
    cols = ["wavelength_nm", "angle_deg", "psi_deg", "delta_deg"]
    arrs = [data.wavelength_nm, data.angle_deg, data.psi_deg, data.delta_deg]
    if data.has_sigma:
        cols += ["sigma_psi_deg", "sigma_delta_deg"]
        arrs += [data.sigma_psi_deg, data.sigma_delta_deg]
    return _write_columns(path, [f"{data.name}: ellipsometric angles, Delta convention of nmmm.ellipsometry.forward"],
                          cols, arrs)


def _write_columns(path: Path, comments, cols, arrs) -> Path:
    """A CSV of ``#`` comment lines, a header row and columns written with 10 significant digits,
    written atomically (complete, or the previous file untouched)."""
    from nmmm.atomic_io import atomic_write_text

    f = io.StringIO(newline="")
    for line in comments:
        f.write(f"# {line}\n")
    wr = csv.writer(f)
    wr.writerow(cols)
    for row in zip(*arrs):
        wr.writerow([f"{v:.10g}" for v in row])
    atomic_write_text(path, f.getvalue())
    return path


# ----------------------------------------------------------------------------------------
# J. A. Woollam ASCII
# ----------------------------------------------------------------------------------------
_UNITS_TO_NM = {"nm": ("nm", 1.0), "nanometers": ("nm", 1.0), "angstroms": ("nm", 0.1), "a": ("nm", 0.1),
                "microns": ("nm", 1e3), "um": ("nm", 1e3), "µm": ("nm", 1e3), "ev": ("ev", None)}
_NUM = r"(?:[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?i:nan|inf(?:inity)?))"
_TAGGED = re.compile(rf"^\s*([A-Za-z][A-Za-z0-9]*)((?:\s+{_NUM}){{1,8}})\s*$")
_UNTAGGED = re.compile(rf"^\s*((?:{_NUM}\s+){{1,7}}{_NUM})\s*$")


def read_woollam(path, name: str | None = None, strict: bool = False) -> EllipsometryData:
    """Read a J. A. Woollam ASCII Ψ/Δ export (WVASE32 ``.dat`` or CompleteEASE); see the module
    docstring for the layout supported. Data lines with NaN and truncated lines are left out
    with a warning naming them (``strict=True``: refused); the scan is ``data.metadata["scan"]``."""
    path = Path(path)
    if not path.is_file():
        raise DataFileError(f"ellipsometry data file not found: {path}")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        text = path.read_text(encoding="latin-1")
    header, rows, line_nos, skipped, fields = [], [], [], {}, []
    unit = None
    for i, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line:
            continue
        m_t = _TAGGED.match(line)
        m_u = None if m_t else _UNTAGGED.match(line)
        if m_u is not None and not rows and len(m_u.group(1).split()) < 4:
            m_u = None  # a short line of numbers before the data is a header line (a date, a count)
        if m_t is not None and not rows and m_t.group(1) != "E" and len(m_t.group(2).split()) < 4:
            m_t = None  # likewise "VASEmethod 2" style header lines
        if m_t is None and m_u is None:
            if rows:
                raise DataFileError(f"{path}, line {i}: cannot read {_shown_row(line)} among the data lines")
            header.append(line)
            low = line.lower()
            if re.match(r"^[a-zµ]+\s+trig\b", low):
                raise DataFileError(f"{path}: the tan(Psi)/cos(Delta) ('TRIG') variant is not supported; "
                                    "export Psi/Delta from WVASE instead")
            if low in _UNITS_TO_NM:
                unit = low
            continue
        if m_t is not None:
            tag = m_t.group(1)
            if tag != "E":
                skipped[tag] = skipped.get(tag, 0) + 1
                continue
            nums = m_t.group(2).split()
        else:
            nums = m_u.group(1).split()
        count = len(nums)
        nums = nums[:6]  # extra columns (e.g. depolarization) are not used
        fields.append(nums)
        rows.append(([float(x) for x in nums] + [np.nan] * (6 - len(nums)), min(count, 6)))
        line_nos.append(i)
    if not rows:
        raise DataFileError(f"{path}: no Psi/Delta data lines ('E wavelength angle psi delta [sigpsi sigdelta]') found")
    if unit is None:
        raise DataFileError(f"{path}: no spectral unit line (nm, eV, Angstroms or microns) in the header "
                            f"{header!r}; the last header line of a WVASE file names it")
    arr, info = _scan_rows(path, rows, line_nos, 4, strict, cut=_cut_last_line(text, fields, line_nos))
    kind, scale = _UNITS_TO_NM[unit]
    spectral = arr[:, 0]
    if kind == "ev" and np.any(spectral <= 0):
        raise DataFileError(f"{path}: photon energies must be > 0 eV")
    wl = HC_EV_NM / spectral if kind == "ev" else spectral * scale
    has_sig = not np.isnan(arr[:, 4:6]).any()
    scan = _finish_scan(path, wl, arr[:, 1], info, strict)
    try:
        return EllipsometryData(
            wl, arr[:, 1], arr[:, 2], arr[:, 3],
            arr[:, 4] if has_sig else None, arr[:, 5] if has_sig else None,
            name=name or (header[0] if header else path.stem),
            metadata={"path": str(path), "format": "woollam", "header": header, "unit": unit,
                      "skipped_lines": skipped, "scan": scan})
    except InvalidInputError as exc:
        raise InvalidInputError(f"{path}: {exc}") from None


def _shown_row(row) -> str:
    """A data row for an error message: short plain text as is, else only its length (a binary
    or foreign file is never echoed)."""
    text = row if isinstance(row, str) else ",".join(row)
    if len(text) <= 80 and text.isprintable():
        return repr(text)
    return f"a {len(text)}-character line"


#: reader name -> function(path, name=None, strict=False) -> EllipsometryData
DATA_READERS = {"csv": read_csv, "woollam": read_woollam}


def read_data(path, format: str | None = None, name: str | None = None, strict: bool = False) -> EllipsometryData:
    """Read an ellipsometry file; ``format`` one of :data:`DATA_READERS` or ``None`` to decide from
    the suffix (``.csv`` → csv; ``.dat``/``.txt`` → woollam). ``strict``: refuse a file with
    NaN rows, truncated lines, repeated or unsorted points instead of warning (:class:`DataScan`)."""
    path = Path(path)
    if format is None:
        format = "csv" if path.suffix.lower() == ".csv" else "woollam"
    try:
        reader = DATA_READERS[format]
    except KeyError:
        raise InvalidInputError(f"unknown data format {format!r}; choose one of {sorted(DATA_READERS)}") from None
    return reader(path, name=name, strict=strict)


def write_material_csv(path, wavelength_nm, nk, name: str = "fitted", reference: str = "",
                       sigma_n=None, sigma_k=None) -> Path:
    """Write optical constants as the CSV Material file that ``nmmm.materials.read_csv`` loads.

    Layout: ``#`` comment lines (name, reference), a header ``wavelength_nm,n,k`` (plus
    ``sigma_n,sigma_k`` when given), rows in increasing wavelength.
    """
    from nmmm.spectra import check_nk

    w = as_wavelength_nm(np.atleast_1d(wavelength_nm)).ravel()
    nk = check_nk(np.atleast_1d(nk), "nk").ravel()
    if nk.size != w.size:
        raise InvalidInputError(f"nk has {nk.size} values for {w.size} wavelengths")
    order = np.argsort(w)
    path = Path(path)
    cols = ["wavelength_nm", "n", "k"]
    arrs = [w[order], nk.real[order], nk.imag[order]]
    if sigma_n is not None and sigma_k is not None:
        cols += ["sigma_n", "sigma_k"]
        arrs += [np.asarray(sigma_n, float).ravel()[order], np.asarray(sigma_k, float).ravel()[order]]
    return _write_columns(path, [f"name: {name}"] + ([f"reference: {reference}"] if reference else []), cols, arrs)
