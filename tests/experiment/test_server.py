"""The real server in a subprocess: kill mid-session and resume; 50 concurrent participants."""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import sqlite3
import uuid

import httpx
import pytest
from experiment_helpers import make_pairs

from nmmm.experiment.storage import read_responses


def _register(c, pid):
    r = c.post("/api/participants", json={"participant_id": pid, "consent": True})
    assert r.status_code == 201, r.text
    return r.json()["session"]


def _answer(c, s, i, rid, choice="left"):
    return c.post(f"/api/session/{s}/responses",
                  json={"response_id": rid, "trial_index": i, "choice": choice, "rt_ms": 500.0})


def test_kill_between_trials_loses_nothing_and_participant_resumes(tmp_path, pairs_toml, server_factory):
    db = tmp_path / "responses.sqlite"
    srv = server_factory(pairs_toml, db).start()
    with httpx.Client(base_url=srv.url, timeout=10) as c:
        s = _register(c, "P01")
        acked = []
        for i in range(2):
            assert c.get(f"/api/session/{s}/trial").json()["trial_index"] == i
            rid = str(uuid.uuid4())
            assert _answer(c, s, i, rid).status_code == 201
            acked.append(rid)
    srv.kill()  # SIGKILL right after the acknowledgements: no clean shutdown
    # every acknowledged response is in the file, read by another process's connection
    assert {r["response_id"] for r in read_responses(db)} == set(acked)
    srv.start()
    with httpx.Client(base_url=srv.url, timeout=10) as c:
        info = c.get(f"/api/session/{s}").json()
        assert info["answered"] == 2 and not info["done"]
        assert c.get(f"/api/session/{s}/trial").json()["trial_index"] == 2   # resumes where it stopped
        # the client re-sends a response whose acknowledgement it lost: stored once
        assert _answer(c, s, 1, acked[1]).json()["status"] == "duplicate"
        for i in (2, 3):
            assert _answer(c, s, i, str(uuid.uuid4())).status_code == 201
        assert c.get(f"/api/session/{s}/trial").json()["done"]
        csv_text = c.get("/admin/export.csv", params={"token": srv.token}).text
    assert len(csv_text.strip().splitlines()) == 1 + 4
    con = sqlite3.connect(db)
    assert con.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    con.close()


def test_fifty_concurrent_participants_each_response_stored_once(tmp_path, server_factory):
    toml = make_pairs(tmp_path, n_pairs=3, repetitions=2, blank_ms=0)   # 6 trials each
    db = tmp_path / "load.sqlite"
    srv = server_factory(toml, db).start()
    n_part, n_trials = 50, 6
    limits = httpx.Limits(max_connections=64)

    shared = httpx.Client(base_url=srv.url, timeout=30, limits=limits)  # thread-safe; one pool

    def participant(i):
        with contextlib.nullcontext(shared) as c:
            s = _register(c, f"L{i:03d}")
            ids = []
            for t in range(n_trials):
                trial = c.get(f"/api/session/{s}/trial").json()
                assert trial["trial_index"] == t
                assert c.get(trial["images"]["left"]).status_code == 200
                rid = str(uuid.uuid4())
                r = _answer(c, s, t, rid, "left" if (i + t) % 2 else "right")
                assert r.status_code == 201, r.text
                if t % 3 == 0:   # replayed submissions (lost acknowledgements) change nothing
                    assert _answer(c, s, t, rid, "left" if (i + t) % 2 else "right").json()["status"] == "duplicate"
                ids.append(rid)
            assert c.get(f"/api/session/{s}/trial").json()["done"]
            return ids

    with cf.ThreadPoolExecutor(max_workers=n_part) as pool:
        futures = [pool.submit(participant, i) for i in range(n_part)]
        sent = [rid for f in cf.as_completed(futures, timeout=240) for rid in f.result()]
    rows = read_responses(db)
    assert len(sent) == n_part * n_trials
    assert len(rows) == n_part * n_trials
    assert sorted(r["response_id"] for r in rows) == sorted(sent)
    keys = {(r["participant_id"], r["trial_index"]) for r in rows}
    assert len(keys) == n_part * n_trials
    shared.close()
    srv.kill()
