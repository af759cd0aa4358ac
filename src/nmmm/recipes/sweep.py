"""Parameter sweeps of a recipe on Dask, written incrementally and resumable.

- :func:`parse_vary` — ``"pigment.fraction=0.05:0.10:11"`` (inclusive linear grid of 11
  values) or ``"pigment.diameter_nm=100,250,500"`` -> ``(key, values)``.
- :func:`grid_points` — the Cartesian grid of several ``--vary`` as a list of
  ``{key: value}``.
- :func:`evaluate_point` — one point: the recipe with the values set, validated and
  computed; returns a flat row (parameters, CIELAB per illuminant, the primary spectrum).
- :func:`sweep` — the whole grid on a Dask cluster (a ``LocalCluster`` of worker
  processes by default, or an existing scheduler ``tcp://HOST:8786``), or serially.
- :func:`load_results` — the finished points of a sweep folder as a pandas DataFrame.

Storage: one Parquet file per finished point, ``OUT/points/<point_id>.parquet``, written
by the client (atomically: temporary name, then rename) as soon as the point's result
arrives — so workers need no shared file system, a worker killed mid-sweep loses only its
running point (Dask reschedules it on another worker), and a sweep whose client is
interrupted keeps everything finished so far. ``point_id`` is a hash of the recipe and the
point's values: a rerun of the same sweep skips the points already on disk (resume), and
a changed recipe does not reuse stale results. ``OUT/sweep.json`` records the recipe and
the grid; ``OUT/results.parquet`` and ``OUT/results.csv`` gather all points at the end.

Verified resume: after each point file is in place, a line with its SHA-256 and size is
appended to ``OUT/manifest.jsonl`` (and flushed to disk). A rerun trusts a point only when its
file matches the manifest; a truncated, bit-flipped, empty or unlisted file is recomputed, with
a warning naming it (``SweepSummary["warnings"]``). Two sweeps into one folder at once are
refused (:func:`nmmm.atomic_io.folder_lock`).

Bounded work: ``n_workers < 1`` is refused; a grid of more than :data:`MAX_POINTS` points (or a
range of more than :data:`MAX_VALUES` values) is refused with the estimate of its points,
validation time, physics time and disk, unless ``max_points`` raises the limit
(``nmmm sweep --max-points N``); validating a grid of more than a few hundred points shows a
progress bar.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import warnings
import socket
import time
import tomllib
from itertools import product
from pathlib import Path

import numpy as np

from nmmm.errors import InvalidInputError, RecipeError
from nmmm.recipes.schema import get_key, parse_recipe, read_toml, set_key

__all__ = ["parse_vary", "grid_points", "point_id", "evaluate_point", "sweep", "load_results", "SweepSummary",
           "MAX_POINTS", "MAX_VALUES", "grid_size", "verified_points"]

#: largest grid :func:`sweep` runs without ``max_points`` (10 000 points ~ hours of paint physics)
MAX_POINTS = 10_000
#: largest number of values one ``--vary`` range may give (beyond, the list itself costs GBs)
MAX_VALUES = 1_000_000
#: measured cost of validating one point (parse + pydantic), for the estimate; s
_VALIDATE_S = 1e-3
#: the least physics per point (a thin-film recipe; paints take 0.5-10 s); s
_PHYSICS_MIN_S = 0.05
MANIFEST = "manifest.jsonl"


def _value(text: str):
    text = text.strip()
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def parse_vary(spec: str) -> tuple[str, list]:
    """``key=start:stop:num`` (``num`` values from start to stop inclusive), ``key=a,b,c``
    or ``key=value`` -> ``(key, [values])``."""
    if "=" not in spec:
        raise RecipeError(f"--vary {spec!r}: write KEY=START:STOP:NUM or KEY=V1,V2,... (e.g. pigment.fraction=0.05:0.10:11)")
    key, rhs = (s.strip() for s in spec.split("=", 1))
    if not key or not rhs:
        raise RecipeError(f"--vary {spec!r}: empty key or values")
    if ":" in rhs:
        parts = rhs.split(":")
        if len(parts) != 3:
            raise RecipeError(f"--vary {spec!r}: a range is START:STOP:NUM (NUM values, inclusive)")
        try:
            a, b, n = float(parts[0]), float(parts[1]), int(parts[2])
        except ValueError:
            raise RecipeError(f"--vary {spec!r}: START and STOP must be numbers and NUM an integer") from None
        if n < 1:
            raise RecipeError(f"--vary {spec!r}: NUM must be >= 1")
        if n > MAX_VALUES:
            raise RecipeError(f"--vary {spec!r}: NUM = {n} values is more than {MAX_VALUES:,} (a sweep of that many "
                              f"points would take > {n * _PHYSICS_MIN_S / 86400:.0f} days); use fewer values")
        if not (math.isfinite(a) and math.isfinite(b)):
            raise RecipeError(f"--vary {spec!r}: START and STOP must be finite numbers")
        vals = [float(f"{v:.12g}") for v in np.linspace(a, b, n)]
    else:
        vals = [_value(v) for v in rhs.split(",") if v.strip()]
    if not vals:
        raise RecipeError(f"--vary {spec!r}: no values")
    return key, vals


def grid_points(varies) -> list[dict]:
    """Cartesian product of ``[(key, values), ...]`` -> ``[{key: value, ...}, ...]``."""
    varies = [parse_vary(v) if isinstance(v, str) else v for v in varies]
    keys = [k for k, _ in varies]
    if len(set(keys)) != len(keys):
        raise RecipeError(f"--vary: a key is given twice: {keys}")
    return [dict(zip(keys, combo)) for combo in product(*[vals for _, vals in varies])]


def grid_size(varies) -> int:
    """Number of points of the grid of ``varies`` (without building it)."""
    return math.prod(len(vals) for _, vals in _varies_list(varies))


def _estimate(n: int, n_workers: int, nw: int = 81) -> str:
    disk = n * (2500 + 16 * nw)
    return (f"{n:,} points: validating them takes ~{n * _VALIDATE_S:,.0f} s, the physics at least "
            f"{n * _PHYSICS_MIN_S / max(n_workers, 1) / 3600:,.1f} h on {n_workers} worker(s) "
            f"({_PHYSICS_MIN_S} s a point for the quickest recipes; paints take 10-100x more), "
            f"and ~{disk / 1e6:,.0f} MB of point files")


def point_id(raw: dict, params: dict) -> str:
    """Stable id of a point: a hash of the recipe and the point's values."""
    blob = json.dumps({"recipe": raw, "params": params}, sort_keys=True, default=str)
    return hashlib.sha1(blob.encode()).hexdigest()[:16]


def _apply(raw: dict, params: dict) -> dict:
    for k, v in params.items():
        raw = set_key(raw, k, v)
    return raw


def evaluate_point(raw: dict, params: dict, base_dir=None, allow_outside_files: bool = False) -> dict:
    """Compute one point of a sweep; returns a flat row (JSON/Parquet friendly)."""
    from nmmm.recipes.run import compute
    from nmmm.recipes.schema import files_outside_allowed

    t0 = time.perf_counter()
    with files_outside_allowed(allow_outside_files):
        recipe = parse_recipe(_apply(raw, params), base_dir=base_dir)
    res = compute(recipe, progress=False)
    row = {f"param:{k}": v for k, v in params.items()}
    row.update({k: float(v) for k, v in res.scalars.items()})
    row["primary"] = res.primary
    row["wavelength_nm"] = [float(x) for x in res.wavelength_nm]
    row["spectrum"] = [float(x) for x in res.spectra[res.primary]]
    row["physics_s"] = time.perf_counter() - t0
    row["worker"] = f"{socket.gethostname()}:{os.getpid()}"
    return row


def _write_point(folder: Path, pid: str, index: int, row: dict) -> Path:
    import pyarrow as pa
    import pyarrow.parquet as pq

    from nmmm.atomic_io import atomic_path, sha256_file

    row = dict(row, point_id=pid, point_index=index)
    path = folder / f"{pid}.parquet"
    with atomic_path(path) as tmp:
        pq.write_table(pa.Table.from_pylist([row]), tmp)
    # the manifest line comes after the file: a point is trusted only once both are on disk
    entry = {"point_id": pid, "sha256": sha256_file(path), "bytes": path.stat().st_size}
    try:
        with open(folder.parent / MANIFEST, "a", encoding="utf-8") as fh:
            fh.write(json.dumps(entry) + "\n")
            fh.flush()
            os.fsync(fh.fileno())
    except OSError as exc:
        from nmmm.errors import DataFileError

        raise DataFileError(f"cannot write {str(folder.parent / MANIFEST)!r}: {exc.strerror or exc}") from None
    return path


def _manifest(out: Path) -> dict:
    """``{point_id: {"sha256", "bytes"}}`` from ``OUT/manifest.jsonl`` (a torn last line is ignored)."""
    entries = {}
    try:
        lines = (out / MANIFEST).read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError:
        return entries
    for line in lines:
        try:
            e = json.loads(line)
            entries[str(e["point_id"])] = e
        except (ValueError, KeyError, TypeError):
            continue
    return entries


def verified_points(out_dir) -> tuple[list[Path], list[Path]]:
    """``(good, bad)`` point files of a sweep folder: good ones match their manifest line
    (size and SHA-256); bad ones are truncated, altered, empty or not listed."""
    from nmmm.atomic_io import sha256_file

    out = Path(out_dir)
    man = _manifest(out)
    good, bad = [], []
    for f in sorted((out / "points").glob("*.parquet")):
        if f.name.startswith("."):  # a temporary file of a write in progress or interrupted: never a point
            continue
        e = man.get(f.stem)
        try:
            ok = e is not None and f.stat().st_size == e.get("bytes") and sha256_file(f) == e.get("sha256")
        except OSError:
            ok = False
        (good if ok else bad).append(f)
    return good, bad


def load_results(out_dir):
    """All verified points of a sweep folder as a DataFrame (sorted by point index).

    Files that do not match the manifest are left out with a warning naming them."""
    import pandas as pd
    import pyarrow.parquet as pq

    files, bad = verified_points(out_dir)
    if bad:
        warnings.warn(f"sweep {str(out_dir)!r}: {len(bad)} point file(s) do not match {MANIFEST} and are left out: "
                      + ", ".join(f.name for f in bad[:5]) + (" ..." if len(bad) > 5 else "")
                      + "; rerun the sweep to recompute them", stacklevel=2)
    if not files:
        return pd.DataFrame()
    df = pd.concat([pq.read_table(f).to_pandas() for f in files], ignore_index=True)
    return df.sort_values("point_index").reset_index(drop=True)


class SweepSummary(dict):
    """What :func:`sweep` did: ``n_points``, ``n_skipped`` (already on disk), ``n_computed``,
    ``wall_s``, ``physics_s`` (sum over computed points), ``out_dir``, ``results`` (DataFrame),
    ``warnings`` (point files found corrupt and recomputed)."""


def sweep(recipe, varies, out_dir, scheduler=None, n_workers: int = 2, serial: bool = False,
          progress: bool = True, plots: bool = True, client=None, max_points: int | None = None,
          allow_outside_files: bool = False) -> SweepSummary:
    """Run a recipe over the grid of ``varies`` and write one Parquet file per point.

    Parameters
    ----------
    recipe : path, TOML text or raw dict
    varies : list of ``"key=..."`` strings or ``(key, values)`` pairs
    out_dir : folder of the sweep (created; reused to resume)
    scheduler : ``"tcp://HOST:8786"`` of a running Dask scheduler, or None for a
        ``LocalCluster`` of ``n_workers`` single-threaded worker processes.
    serial : compute in this process, without Dask (the reference for the cluster runs).
    client : an existing ``dask.distributed.Client`` (overrides ``scheduler``).
    max_points : largest grid accepted (default :data:`MAX_POINTS`); a larger one is refused
        with its estimate.
    allow_outside_files : compound files may lie outside the recipe's folder.
    """
    from nmmm.atomic_io import folder_lock
    from nmmm.recipes.schema import files_outside_allowed

    if not isinstance(n_workers, int) or n_workers < 1:
        raise InvalidInputError(f"n_workers = {n_workers!r}: a local cluster needs at least 1 worker process "
                                "(-n 1 or more; or --serial to compute in this process)")
    with files_outside_allowed(allow_outside_files), folder_lock(out_dir):
        return _sweep(recipe, varies, out_dir, scheduler, n_workers, serial, progress, plots, client,
                      MAX_POINTS if max_points is None else int(max_points), allow_outside_files)


def _sweep(recipe, varies, out_dir, scheduler, n_workers, serial, progress, plots, client, max_points,
           allow_outside_files):
    from tqdm import tqdm

    t_start = time.perf_counter()
    raw, source, base = read_toml(recipe)
    parse_recipe(raw, source, base)  # the base recipe itself must be valid
    varies = _varies_list(varies)
    n_grid = grid_size(varies)
    if n_grid > max_points:
        raise InvalidInputError(f"the grid has {_estimate(n_grid, 1 if serial else n_workers)}; that is more than "
                                f"the limit of {max_points:,} points: use fewer values, or raise the limit with "
                                f"--max-points {n_grid} (sweep(..., max_points={n_grid}))")
    points = grid_points(varies)
    for k in points[0]:
        try:
            get_key(raw, k)
        except RecipeError:
            # allowed when the parent table exists and the key is an optional field
            parent = k.rsplit(".", 1)[0] if "." in k else ""
            if parent:
                get_key(raw, parent)
    # validate every point before spending any compute (messages name the key)
    check = tqdm(points, desc="validating", unit="point", disable=not progress or len(points) < 500)
    for p in check:
        try:
            parse_recipe(_apply(raw, p), source, base)
        except RecipeError as exc:
            raise RecipeError(f"{exc} (sweep point {p})") from None
    check.close()
    out = Path(out_dir)
    folder = out / "points"
    folder.mkdir(parents=True, exist_ok=True)
    ids = [point_id(raw, p) for p in points]
    from nmmm.atomic_io import atomic_write_text

    atomic_write_text(out / "sweep.json", json.dumps({
        "recipe_source": source, "recipe": raw, "varies": [[k, list(v)] for k, v in varies],
        "points": [{"point_id": i, **p} for i, p in zip(ids, points)]}, indent=1, default=str))
    good, bad = verified_points(out)
    done = {f.stem for f in good}
    warned = []
    if bad:
        wanted = set(ids)
        names = [f.name for f in bad if f.stem in wanted]
        if names:
            warned.append(f"{len(names)} point file(s) did not match {MANIFEST} (truncated, altered or written by an "
                          "interrupted run) and are recomputed: " + ", ".join(names[:10]) + (" ..." if len(names) > 10 else ""))
            warnings.warn(warned[-1], stacklevel=3)
        for f in bad:
            try:
                f.unlink()
            except OSError:
                pass
    todo = [(i, pid, p) for i, (pid, p) in enumerate(zip(ids, points)) if pid not in done]
    skipped = len(points) - len(todo)
    physics = 0.0
    bar = tqdm(total=len(points), initial=skipped, desc="sweep", unit="point", disable=not progress)
    base_s = str(base) if base else None
    if serial or not todo:
        for i, pid, p in todo:
            row = evaluate_point(raw, p, base_s, allow_outside_files)
            physics += row["physics_s"]
            _write_point(folder, pid, i, row)
            bar.update()
    else:
        from dask.distributed import as_completed

        from nmmm.cluster import dask_client

        with dask_client(client, scheduler, n_workers, scheduler_option="--scheduler", caller="sweep") as client:
            futs = {}
            for i, pid, p in todo:
                f = client.submit(evaluate_point, raw, p, base_s, allow_outside_files, key=f"nmmm-point-{pid}",
                                  pure=False, retries=2)
                futs[f] = (i, pid)
            for f in as_completed(list(futs)):
                i, pid = futs[f]
                row = f.result()
                physics += row["physics_s"]
                _write_point(folder, pid, i, row)
                bar.update()
                f.release()
    bar.close()
    from nmmm.atomic_io import atomic_path

    df = load_results(out)
    df = df[df["point_id"].isin(ids)].reset_index(drop=True)
    with atomic_path(out / "results.parquet") as tmp:
        df.to_parquet(tmp)
    scalar_cols = [c for c in df.columns if c not in ("wavelength_nm", "spectrum")]
    with atomic_path(out / "results.csv") as tmp:
        df[scalar_cols].to_csv(tmp, index=False)
    summary = SweepSummary(n_points=len(points), n_skipped=skipped, n_computed=len(todo),
                           wall_s=time.perf_counter() - t_start, physics_s=physics, out_dir=str(out), results=df,
                           warnings=warned)
    from nmmm.recipes.labelled import write_sweep_cube  # the labelled cube: results.nc (+ results.zarr)

    summary["cube"] = write_sweep_cube(df, _varies_list(varies), out)
    if plots and len(df):
        try:
            summary["plot"] = str(plot_sweep(df, out / "sweep.png"))
            summary["report"] = str(_sweep_report(df, summary, raw, out))
        except Exception:  # pragma: no cover - a plot must never lose the sweep
            pass
    return summary


def _sweep_report(df, summary, raw, out):
    """The sweep's report: the plots, the points (folded when long, all in results.csv), the
    words that explain a masstone unchanged over a concentration series, and the command that
    reproduces the sweep."""
    from nmmm.recipes.sweep_report import sweep_report_section
    from nmmm.recipes.report import write_report

    sec = sweep_report_section(df, summary, raw, out)
    sec.pop("outro", None)
    return write_report([sec], out / "report.html", title=sec["title"])


def _varies_list(varies):
    return [parse_vary(v) if isinstance(v, str) else v for v in varies]


def _axis_label(key: str) -> str:
    """``pigment.body_diagonal_nm`` -> "pigment body diagonal (nm)"; ``L_D65`` -> "L* under D65 (1)"
    (:func:`nmmm.recipes.figures.quantity_label`)."""
    from nmmm.recipes.figures import quantity_label

    return quantity_label(key)


def plot_sweep(df, path, quantity: str | None = None):
    """L* (first illuminant) against the first varied parameter, one curve per value of the
    others; and the spectra of every point — legends in words with units, every curve its own
    colour and line style (:func:`nmmm.recipes.sweep_report.plot_sweep`)."""
    from nmmm.recipes.sweep_report import plot_sweep as _plot

    return _plot(df, path, quantity)
