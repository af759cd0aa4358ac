"""CSV export of the response database.

- :func:`write_csv` — one row per answered trial (to a path or an open text file).
- :data:`CSV_COLUMNS` — the columns, in order.

Columns: ``participant_id, trial_index, pair_id, label, repetition, stereo, photo_position,
chosen_position, correct, rt_ms, response_id, answered_at_utc, n_trials, started_at_utc``.
Positions are ``left``/``right`` (``top``/``bottom`` in stereo mode); ``correct`` is 1 when the
participant picked the photograph.
"""

from __future__ import annotations

import csv
from pathlib import Path

from nmmm.errors import DataFileError
from nmmm.experiment.storage import read_responses

CSV_COLUMNS = ("participant_id", "trial_index", "pair_id", "label", "repetition", "stereo", "photo_position",
               "chosen_position", "correct", "rt_ms", "response_id", "answered_at_utc", "n_trials",
               "started_at_utc")

_POS = {0: ("left", "right"), 1: ("top", "bottom")}


def _rows(db_path):
    for r in read_responses(db_path):
        names = _POS[int(r["stereo"])]
        yield {"participant_id": r["participant_id"], "trial_index": r["trial_index"], "pair_id": r["pair_id"],
               "label": r["label"], "repetition": r["repetition"], "stereo": r["stereo"],
               "photo_position": names[r["photo_slot"]], "chosen_position": names[r["chosen_slot"]],
               "correct": r["correct"], "rt_ms": f"{r['rt_ms']:.1f}", "response_id": r["response_id"],
               "answered_at_utc": r["answered_at"], "n_trials": r["n_trials"], "started_at_utc": r["created_at"]}


def write_csv(db_path, out) -> int:
    """Write every answered trial of ``db_path`` as CSV to ``out`` (path or text file); return the row count."""
    rows = list(_rows(db_path))  # read first: a bad database leaves no empty CSV behind
    if hasattr(out, "write"):
        return _write(rows, out)
    out = Path(out)
    if not out.parent.is_dir():
        raise DataFileError(f"cannot write {out}: the directory {out.parent} does not exist; create it first")
    with open(out, "w", newline="", encoding="utf-8") as fh:
        return _write(rows, fh)


def _write(rows, fh) -> int:
    w = csv.DictWriter(fh, fieldnames=CSV_COLUMNS, lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    return len(rows)


__all__ = ["write_csv", "CSV_COLUMNS"]
