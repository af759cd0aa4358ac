"""The response database of the 2AFC experiment (SQLite, write-ahead log).

- :class:`ResponseStore` — participants, their randomised trials and their responses.
- :func:`assign_trials` — the randomised trial order and photo placement of one participant,
  a pure function of the pair ids, the repetitions and the participant's seed.
- :func:`read_responses` — every answered trial of a database, as a list of dicts (for
  :mod:`nmmm.experiment.stats` and :mod:`nmmm.experiment.export`).

Durability: the database runs in WAL mode with ``synchronous=FULL``; every response is its
own committed transaction before the server answers, so killing the server (or the machine)
loses no acknowledged response, and a participant resumes at their first unanswered trial.

Storage failures: a full disk (``SQLITE_FULL``), a read-only file or file system, an I/O
error or a database locked by another program raise :class:`StorageUnavailableError` (the
server answers 503 with its message): the transaction is rolled back, so nothing is
acknowledged that was not stored, and the same request succeeds once the cause is removed.

Participants: creating one is idempotent for the browser that created it. The page sends a
random ``client_token`` with the participant id (only its SHA-256 is stored); a retry with the
same id and token (e.g. after the reply was lost in a server crash) resumes that participant
instead of being refused.

Idempotence: a response carries a client-generated ``response_id`` (a UUID) and
``(participant_id, trial_index)`` is unique. Replaying the same submission returns the stored
response unchanged; a different answer to an already answered trial is refused
(:class:`DuplicateSubmissionError`), never stored twice.

References
----------
- SQLite, "Write-Ahead Logging", https://www.sqlite.org/wal.html
"""

from __future__ import annotations

import hashlib
import json
import secrets
import sqlite3
import threading
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from nmmm.errors import DataFileError, InvalidInputError

SCHEMA_VERSION = "2"   # 2: participants.client_token_sha256

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS pairs (
    pair_id TEXT PRIMARY KEY,
    label TEXT NOT NULL,
    rendered_sha256 TEXT NOT NULL,
    photo_sha256 TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS participants (
    participant_id TEXT PRIMARY KEY,
    session_token TEXT NOT NULL UNIQUE,
    seed INTEGER NOT NULL,
    stereo INTEGER NOT NULL,
    n_trials INTEGER NOT NULL,
    consent_at TEXT NOT NULL,
    consent_sha256 TEXT NOT NULL,
    user_agent TEXT,
    screen TEXT,
    created_at TEXT NOT NULL,
    client_token_sha256 TEXT
);
CREATE TABLE IF NOT EXISTS trials (
    participant_id TEXT NOT NULL REFERENCES participants(participant_id),
    trial_index INTEGER NOT NULL,
    pair_id TEXT NOT NULL REFERENCES pairs(pair_id),
    repetition INTEGER NOT NULL,
    photo_slot INTEGER NOT NULL CHECK (photo_slot IN (0, 1)),
    PRIMARY KEY (participant_id, trial_index)
);
CREATE TABLE IF NOT EXISTS responses (
    response_id TEXT PRIMARY KEY,
    participant_id TEXT NOT NULL,
    trial_index INTEGER NOT NULL,
    chosen_slot INTEGER NOT NULL CHECK (chosen_slot IN (0, 1)),
    correct INTEGER NOT NULL CHECK (correct IN (0, 1)),
    rt_ms REAL NOT NULL,
    answered_at TEXT NOT NULL,
    UNIQUE (participant_id, trial_index),
    FOREIGN KEY (participant_id, trial_index) REFERENCES trials(participant_id, trial_index)
);
"""


class UnknownParticipantError(InvalidInputError):
    """No participant has this id or session token."""


class ParticipantExistsError(InvalidInputError):
    """A participant id is already registered (resume from the same browser or the admin link)."""


class DuplicateSubmissionError(InvalidInputError):
    """A trial already has a different response, or a response id is reused for another trial."""


class TrialOrderError(InvalidInputError):
    """A response for a trial that is not the participant's next one."""


class StorageUnavailableError(DataFileError):
    """The database cannot store anything now (disk full, read-only, I/O error, locked).

    Nothing was stored; the same request may be repeated once the cause is removed.
    """


_STORAGE_CAUSES = {
    "SQLITE_FULL": "the disk (or the database's size limit) is full; free space on the disk that holds it",
    "SQLITE_READONLY": "the database is read-only; make the file and its directory writable",
    "SQLITE_IOERR": "the disk reported an input/output error; check the disk that holds it",
    "SQLITE_BUSY": "another program holds a lock on the database; close it",
    "SQLITE_LOCKED": "another connection holds a lock on the database; close it",
    "SQLITE_CANTOPEN": "the database file cannot be opened; check that its directory exists and is writable",
    "SQLITE_PERM": "the operating system refused access to the database; check its permissions",
}


def _unavailable(db_path, exc: sqlite3.Error) -> StorageUnavailableError:
    name = getattr(exc, "sqlite_errorname", "") or ""
    cause = next((v for k, v in _STORAGE_CAUSES.items() if name.startswith(k)), None)
    text = str(exc).lower()
    if cause is None:
        cause = ("the disk is full; free space on the disk that holds it" if "full" in text else
                 "the database is read-only; make the file and its directory writable" if "readonly" in text
                 else "the database cannot be written now; check the disk and the file")
    return StorageUnavailableError(
        f"the response database {str(db_path)!r} cannot store anything ({exc}): {cause}. Nothing was stored; "
        f"repeat the request once this is fixed")


def _token_digest(client_token: str | None) -> str | None:
    return None if client_token is None else hashlib.sha256(client_token.encode("utf-8")).hexdigest()


def utc_now() -> str:
    """The current UTC time, ISO 8601 with milliseconds."""
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds")


def _sha256_file(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def assign_trials(pair_ids, repetitions: int, seed: int) -> list[tuple[str, int, int]]:
    """Randomised trials of one participant: a list of ``(pair_id, repetition, photo_slot)``.

    The order of all ``len(pair_ids) * repetitions`` trials is a uniform random permutation,
    and the photograph's slot (0 = left/top, 1 = right/bottom) is counterbalanced: half of the
    trials (rounded at random for an odd count) have the photograph in each slot, in random
    order. Everything follows from ``seed`` (stored per participant), so an assignment can be
    re-derived and audited.
    """
    rng = np.random.Generator(np.random.PCG64(int(seed)))
    items = [(pid, rep) for rep in range(int(repetitions)) for pid in pair_ids]
    order = rng.permutation(len(items))
    n = len(items)
    slots = np.array([0, 1] * ((n + 1) // 2))[:n] if rng.random() < 0.5 else np.array([1, 0] * ((n + 1) // 2))[:n]
    slots = rng.permutation(slots)
    return [(items[i][0], items[i][1], int(s)) for i, s in zip(order, slots)]


class ResponseStore:
    """Participants, trials and responses in one SQLite file (WAL mode, one commit per response).

    Thread-safe: writes go through one connection guarded by a lock (the web server calls the
    store from worker threads); reads use one read-only connection per thread, which in WAL
    mode never wait for a commit in progress. Run one server per database; other processes may
    read the file concurrently.
    """

    def __init__(self, db_path, *, synchronous: str = "FULL"):
        self.db_path = Path(db_path)
        if self.db_path.parent and not self.db_path.parent.exists():
            raise DataFileError(f"directory of the response database {str(self.db_path)!r} does not exist")
        self._lock = threading.Lock()
        self._local = threading.local()
        self._readers: list[sqlite3.Connection] = []
        self._closed = False
        self._con = None
        try:
            self._con = sqlite3.connect(str(self.db_path), check_same_thread=False, isolation_level=None,
                                        timeout=30.0)
            mode = self._con.execute("PRAGMA journal_mode=WAL").fetchone()[0]
            if str(mode).lower() != "wal":
                raise DataFileError(f"{str(self.db_path)!r}: SQLite refused WAL mode (got {mode!r})")
            self._con.execute(f"PRAGMA synchronous={synchronous}")
            self._con.execute("PRAGMA foreign_keys=ON")
            self._con.executescript(_SCHEMA)
            cols = {r[1] for r in self._con.execute("PRAGMA table_info(participants)")}
            if "client_token_sha256" not in cols:   # a database written by schema version 1
                self._con.execute("ALTER TABLE participants ADD COLUMN client_token_sha256 TEXT")
            self._con.execute("INSERT OR REPLACE INTO meta VALUES ('schema_version', ?)", (SCHEMA_VERSION,))
        except sqlite3.DatabaseError as exc:
            if getattr(self, "_con", None) is not None:
                self._con.close()
            if isinstance(exc, sqlite3.OperationalError):
                raise _unavailable(self.db_path, exc) from None
            raise DataFileError(f"{str(self.db_path)!r} is not a usable SQLite response database: {exc}") from None
        self._con.row_factory = sqlite3.Row

    def close(self):
        with self._lock:
            self._closed = True
            for con in self._readers:
                con.close()
            self._readers.clear()
            self._con.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # -- transactions -------------------------------------------------------------------
    def _tx(self, fn):
        """Run ``fn(connection)`` in one IMMEDIATE transaction and commit it; any failure rolls
        it back. SQLite errors of the disk or the file become :class:`StorageUnavailableError`."""
        with self._lock:
            if self._closed:
                raise StorageUnavailableError(f"the response store {str(self.db_path)!r} is closed")
            try:
                self._con.execute("BEGIN IMMEDIATE")
                try:
                    out = fn(self._con)
                    self._con.execute("COMMIT")
                except BaseException:
                    if self._con.in_transaction:
                        try:
                            self._con.execute("ROLLBACK")
                        except sqlite3.Error:
                            pass
                    raise
            except sqlite3.OperationalError as exc:
                raise _unavailable(self.db_path, exc) from None
            return out

    def _reader(self) -> sqlite3.Connection:
        """This thread's read-only connection: WAL readers never wait for the writer's fsync."""
        con = getattr(self._local, "con", None)
        if con is None:
            # check_same_thread=False only so that close() may close it from another thread
            con = sqlite3.connect(str(self.db_path), isolation_level=None, timeout=30.0, check_same_thread=False)
            con.execute("PRAGMA query_only=ON")
            con.row_factory = sqlite3.Row
            self._local.con = con
            with self._lock:
                self._readers.append(con)
        return con

    def _read(self, sql, args=()):
        if self._closed:
            raise StorageUnavailableError(f"the response store {str(self.db_path)!r} is closed")
        try:
            return [dict(r) for r in self._reader().execute(sql, args).fetchall()]
        except sqlite3.OperationalError as exc:
            raise _unavailable(self.db_path, exc) from None

    # -- pairs --------------------------------------------------------------------------
    def register_pairs(self, pairset):
        """Record the pairs (ids, labels, image hashes); refuse a changed pair set once
        participants exist (their trials refer to it)."""
        rows = [(p.pair_id, p.label, _sha256_file(p.rendered), _sha256_file(p.photo)) for p in pairset.pairs]
        fingerprint = hashlib.sha256(json.dumps(
            [rows, pairset.settings.repetitions, pairset.settings.stereo]).encode()).hexdigest()

        def fn(con):
            old = con.execute("SELECT value FROM meta WHERE key='pairs_fingerprint'").fetchone()
            n_part = con.execute("SELECT COUNT(*) FROM participants").fetchone()[0]
            if old is not None and old[0] != fingerprint and n_part > 0:
                raise DataFileError(
                    f"the pairs file differs (pairs, images, repetitions or stereo) from the one the "
                    f"{n_part} participant(s) in {str(self.db_path)!r} were shown; use a new --db for a "
                    f"changed experiment, or restore the original pairs file")
            con.execute("DELETE FROM pairs WHERE pair_id NOT IN (SELECT DISTINCT pair_id FROM trials)")
            con.executemany("INSERT OR REPLACE INTO pairs VALUES (?, ?, ?, ?)", rows)
            con.execute("INSERT OR REPLACE INTO meta VALUES ('pairs_fingerprint', ?)", (fingerprint,))

        self._tx(fn)

    # -- participants -------------------------------------------------------------------
    def create_participant(self, participant_id: str, pairset, *, consent_sha256: str,
                           user_agent: str | None = None, screen: dict | None = None,
                           seed: int | None = None, client_token: str | None = None) -> dict:
        """Register a participant, draw their trials, and return their record.

        The record has ``resumed = False``. If the id is taken and ``client_token`` matches the
        one it was created with, that participant's record is returned with ``resumed = True``
        (a retried creation whose reply was lost); otherwise :class:`ParticipantExistsError`.
        """
        token = secrets.token_urlsafe(24)
        seed = secrets.randbits(62) if seed is None else int(seed)
        trials = assign_trials([p.pair_id for p in pairset.pairs], pairset.settings.repetitions, seed)
        now = utc_now()

        digest = _token_digest(client_token)

        def fn(con):
            old = con.execute("SELECT session_token, client_token_sha256 FROM participants WHERE participant_id=?",
                              (participant_id,)).fetchone()
            if old is not None:
                if digest is not None and old["client_token_sha256"] is not None and secrets.compare_digest(
                        old["client_token_sha256"], digest):
                    return old["session_token"], True
                raise ParticipantExistsError(
                    f"participant id {participant_id!r} has already started; resume from the same browser, "
                    f"or ask the experimenter for the resume link (admin page), or use a new id")
            con.execute("INSERT INTO participants (participant_id, session_token, seed, stereo, n_trials, "
                        "consent_at, consent_sha256, user_agent, screen, created_at, client_token_sha256) "
                        "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                        (participant_id, token, seed, int(pairset.settings.stereo), len(trials), now,
                         consent_sha256, (user_agent or "")[:500], json.dumps(screen or {})[:500], now, digest))
            con.executemany("INSERT INTO trials VALUES (?, ?, ?, ?, ?)",
                            [(participant_id, i, pid, rep, slot) for i, (pid, rep, slot) in enumerate(trials)])
            return token, False

        session, resumed = self._tx(fn)
        return {**self.participant_by_token(session), "resumed": resumed}

    def participant_by_token(self, token: str) -> dict:
        """The participant record of a session token; :class:`UnknownParticipantError` if none."""
        if not isinstance(token, str) or not token:
            raise UnknownParticipantError("unknown participant session: empty token")
        rows = self._read("SELECT * FROM participants WHERE session_token=?", (token,))
        if not rows:
            raise UnknownParticipantError("unknown participant session; start again from the home page")
        return rows[0]

    def participants(self) -> list[dict]:
        """Every participant with progress (answered trials), for the experimenter."""
        return self._read(
            "SELECT p.participant_id, p.session_token, p.n_trials, p.created_at, p.stereo, "
            "COUNT(r.response_id) AS answered FROM participants p "
            "LEFT JOIN responses r ON r.participant_id = p.participant_id "
            "GROUP BY p.participant_id ORDER BY p.created_at")

    # -- trials and responses -----------------------------------------------------------
    def next_trial(self, participant_id: str) -> dict | None:
        """The first unanswered trial of a participant (None when the session is complete)."""
        rows = self._read(
            "SELECT t.* FROM trials t LEFT JOIN responses r ON r.participant_id = t.participant_id "
            "AND r.trial_index = t.trial_index WHERE t.participant_id=? AND r.response_id IS NULL "
            "ORDER BY t.trial_index LIMIT 1", (participant_id,))
        return rows[0] if rows else None

    def answered_count(self, participant_id: str) -> int:
        return self._read("SELECT COUNT(*) AS n FROM responses WHERE participant_id=?", (participant_id,))[0]["n"]

    def trial(self, participant_id: str, trial_index: int) -> dict:
        if not (isinstance(trial_index, int) and 0 <= trial_index < 2**62):
            raise InvalidInputError(f"participant has no trial {str(trial_index)[:40]}")
        rows = self._read("SELECT * FROM trials WHERE participant_id=? AND trial_index=?",
                          (participant_id, int(trial_index)))
        if not rows:
            raise InvalidInputError(f"participant has no trial {trial_index}")
        return rows[0]

    def record_response(self, participant_id: str, trial_index: int, response_id: str, chosen_slot: int,
                        rt_ms: float) -> dict:
        """Store one response in its own committed transaction; idempotent on ``response_id``.

        Returns ``{"status": "stored" | "duplicate", ...}``. A replay of a stored response
        (same id, same trial, same answer) is a ``"duplicate"`` and changes nothing.

        Raises
        ------
        DuplicateSubmissionError
            The trial already has another response, or the id was used for another trial.
        TrialOrderError
            The trial is not the participant's next unanswered one.
        """
        if not (isinstance(trial_index, int) and not isinstance(trial_index, bool) and 0 <= trial_index < 2**62):
            raise TrialOrderError(f"there is no trial {str(trial_index)[:40]} for this participant")
        if chosen_slot not in (0, 1):
            raise InvalidInputError(f"chosen slot must be 0 or 1, got {chosen_slot!r}")
        # compare before any float(): an integer such as 10**400 has no float
        if not (isinstance(rt_ms, (int, float)) and not isinstance(rt_ms, bool) and 0 <= rt_ms <= 3_600_000):
            raise InvalidInputError(f"rt_ms must be a finite number of milliseconds in [0, 3600000], "
                                    f"got {str(rt_ms)[:40]}")

        def fn(con):
            prev = con.execute("SELECT * FROM responses WHERE response_id=?", (response_id,)).fetchone()
            if prev is not None:
                if (prev["participant_id"], prev["trial_index"], prev["chosen_slot"]) == (
                        participant_id, trial_index, chosen_slot):
                    return {"status": "duplicate", "trial_index": trial_index}
                raise DuplicateSubmissionError(
                    f"response id {response_id!r} was already used for another answer; each response "
                    f"needs a fresh id (a replay must repeat the same trial and choice)")
            other = con.execute("SELECT chosen_slot FROM responses WHERE participant_id=? AND trial_index=?",
                                (participant_id, trial_index)).fetchone()
            if other is not None:
                raise DuplicateSubmissionError(
                    f"trial {trial_index} was already answered (with another response id); "
                    f"an answer cannot be changed")
            trial = con.execute("SELECT * FROM trials WHERE participant_id=? AND trial_index=?",
                                (participant_id, trial_index)).fetchone()
            if trial is None:
                raise TrialOrderError(f"there is no trial {trial_index} for this participant")
            nxt = con.execute(
                "SELECT MIN(t.trial_index) FROM trials t LEFT JOIN responses r ON r.participant_id = "
                "t.participant_id AND r.trial_index = t.trial_index WHERE t.participant_id=? AND "
                "r.response_id IS NULL", (participant_id,)).fetchone()[0]
            if nxt != trial_index:
                raise TrialOrderError(f"trial {trial_index} is not the next trial (expected {nxt}); "
                                      f"reload the page to resume")
            correct = int(chosen_slot == trial["photo_slot"])
            con.execute("INSERT INTO responses VALUES (?, ?, ?, ?, ?, ?, ?)",
                        (response_id, participant_id, trial_index, chosen_slot, correct, float(rt_ms), utc_now()))
            return {"status": "stored", "trial_index": trial_index}

        return self._tx(fn)


def read_responses(db_path) -> list[dict]:
    """Every answered trial in a response database, ordered by participant and trial.

    Each dict has: participant_id, trial_index, pair_id, label, repetition, stereo,
    photo_slot, chosen_slot, correct, rt_ms, response_id, answered_at, n_trials, created_at.
    Safe to call while the server is running (WAL readers do not block the writer).
    """
    path = Path(db_path)
    if not path.is_file():
        raise DataFileError(f"response database {str(path)!r} not found")
    try:
        con = sqlite3.connect(path.resolve().as_uri() + "?mode=ro", uri=True, timeout=30.0)
        con.row_factory = sqlite3.Row
        try:
            rows = con.execute(
                "SELECT r.participant_id, r.trial_index, t.pair_id, COALESCE(pa.label, t.pair_id) AS label, "
                "t.repetition, p.stereo, t.photo_slot, r.chosen_slot, r.correct, r.rt_ms, r.response_id, "
                "r.answered_at, p.n_trials, p.created_at FROM responses r "
                "JOIN trials t ON t.participant_id = r.participant_id AND t.trial_index = r.trial_index "
                "JOIN participants p ON p.participant_id = r.participant_id "
                "LEFT JOIN pairs pa ON pa.pair_id = t.pair_id "
                "ORDER BY p.created_at, r.participant_id, r.trial_index").fetchall()
        finally:
            con.close()
    except sqlite3.DatabaseError as exc:
        raise DataFileError(f"{str(path)!r} is not an nmmm response database: {exc}") from None
    return [dict(r) for r in rows]


__all__ = ["ResponseStore", "assign_trials", "read_responses", "utc_now", "UnknownParticipantError",
           "ParticipantExistsError", "DuplicateSubmissionError", "TrialOrderError", "StorageUnavailableError"]
