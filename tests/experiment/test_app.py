"""The web application in-process (Starlette TestClient): protocol, idempotence, privacy, bad input."""

from __future__ import annotations

import csv
import io
import json
import uuid
import warnings

import pytest
from experiment_helpers import make_pairs
from PIL import Image

with warnings.catch_warnings():  # starlette's notice about httpx vs httpx2 in its TestClient
    warnings.simplefilter("ignore")
    from starlette.testclient import TestClient

from nmmm.experiment.app import create_app
from nmmm.experiment.pairs import load_pairs
from nmmm.experiment.storage import assign_trials, read_responses

TOKEN = "test-admin-token"


@pytest.fixture
def client(tmp_path, pairs_toml):
    app = create_app(load_pairs(pairs_toml), tmp_path / "responses.sqlite", admin_token=TOKEN,
                     cache_dir=tmp_path / "cache")
    with TestClient(app) as c:
        c.db = tmp_path / "responses.sqlite"
        c.pairset = app.state.pairset
        yield c


def register(client, pid="P01"):
    r = client.post("/api/participants", json={"participant_id": pid, "consent": True})
    assert r.status_code == 201, r.text
    return r.json()["session"]


def answer(client, session, trial_index, choice="left", rid=None, rt=850.0):
    return client.post(f"/api/session/{session}/responses",
                       json={"response_id": rid or str(uuid.uuid4()), "trial_index": trial_index,
                             "choice": choice, "rt_ms": rt})


def test_whole_session_and_export(client):
    s = register(client)
    n = client.get("/api/config").json()["n_trials"]
    assert n == 4
    for i in range(n):
        t = client.get(f"/api/session/{s}/trial").json()
        assert t["trial_index"] == i and not t["done"]
        for slot in ("left", "right"):
            img = client.get(t["images"][slot])
            assert img.status_code == 200 and img.headers["content-type"] == "image/bmp"
        both = client.get(t["stimuli"]["url"])
        assert both.status_code == 200 and both.headers["content-type"] == "application/octet-stream"
        assert len(both.content) == t["stimuli"]["bytes"] == 2 * 3 * t["width"] * t["height"]
        r = answer(client, s, i, "left" if i % 2 else "right")
        assert r.status_code == 201 and r.json()["status"] == "stored"
    assert client.get(f"/api/session/{s}/trial").json()["done"]
    rows = read_responses(client.db)
    assert len(rows) == n and {r["trial_index"] for r in rows} == set(range(n))
    # correctness is computed server-side from the stored placement
    for r in rows:
        assert r["correct"] == int(r["chosen_slot"] == r["photo_slot"])
    # the admin export route needs the token
    assert client.get("/admin/export.csv").status_code == 401
    assert client.get("/admin/export.csv", headers={"Authorization": "Bearer wrong"}).status_code == 403
    resp = client.get("/admin/export.csv", headers={"Authorization": f"Bearer {TOKEN}"})
    assert resp.status_code == 200
    table = list(csv.DictReader(io.StringIO(resp.text)))
    assert len(table) == n and table[0]["participant_id"] == "P01"
    assert {t["photo_position"] for t in table} <= {"left", "right"}
    page = client.get(f"/admin?token={TOKEN}")
    assert page.status_code == 200 and "resume link" in page.text and "P01" in page.text


def test_randomisation_per_participant_is_stored_and_balanced(client):
    sessions = [register(client, f"P{i:02d}") for i in range(6)]
    import sqlite3

    con = sqlite3.connect(client.db)
    orders = []
    for i in range(6):
        seed = con.execute("SELECT seed FROM participants WHERE participant_id=?", (f"P{i:02d}",)).fetchone()[0]
        trials = con.execute("SELECT pair_id, repetition, photo_slot FROM trials WHERE participant_id=? "
                             "ORDER BY trial_index", (f"P{i:02d}",)).fetchall()
        # the stored assignment is the one the participant's seed gives (auditable)
        assert [tuple(t) for t in trials] == assign_trials([p.pair_id for p in client.pairset.pairs], 1, seed)
        assert sorted(t[0] for t in trials) == sorted(p.pair_id for p in client.pairset.pairs)
        assert sum(t[2] for t in trials) == 2  # photograph left on half of the 4 trials
        orders.append(tuple(t[0] for t in trials))
    con.close()
    assert len(set(orders)) > 1
    assert len(set(sessions)) == 6


def test_assign_trials_balance_odd_and_repetitions():
    t = assign_trials(["a", "b", "c"], 3, seed=42)
    assert len(t) == 9 and sorted(x[0] for x in t) == ["a"] * 3 + ["b"] * 3 + ["c"] * 3
    assert sum(x[2] for x in t) in (4, 5)
    assert t == assign_trials(["a", "b", "c"], 3, seed=42)
    assert t != assign_trials(["a", "b", "c"], 3, seed=43)


def test_nothing_leaks_which_image_is_the_photograph(client, tmp_path):
    s = register(client)
    html = client.get("/").text + client.get("/static/app.js").text
    cfg = client.get("/api/config").text
    t = client.get(f"/api/session/{s}/trial")
    assert t.headers["cache-control"] == "no-store"
    body = t.text
    names = [p.name for pair in client.pairset.pairs for p in (pair.rendered, pair.photo)]
    ids = [pair.pair_id for pair in client.pairset.pairs] + [pair.label for pair in client.pairset.pairs]
    for text in (html, cfg, body):
        assert "photo_slot" not in text and "rendered" not in text
        for name in names + ids:
            assert name not in text
    trial = t.json()
    assert set(trial) == {"participant_id", "n_trials", "answered", "done", "trial_index", "images", "width", "height",
                          "stimuli"}
    # both stimuli are uncompressed BMPs of the same pixel size and length without metadata,
    # though the photo was a JPEG with twice the resolution of the PNG rendering
    imgs = [client.get(trial["images"][slot]) for slot in ("left", "right")]
    for r in imgs:
        im = Image.open(io.BytesIO(r.content))
        assert im.format == "BMP" and im.size == (trial["width"], trial["height"]) == (48, 32)
        assert not {"exif", "icc_profile", "dpi"} & set(im.info)
        assert "etag" not in r.headers and "last-modified" not in r.headers
    assert imgs[0].content != imgs[1].content and len(imgs[0].content) == len(imgs[1].content)
    # the acknowledgement of a response does not say whether it was correct
    ack = answer(client, s, 0).json()
    assert "correct" not in json.dumps(ack)
    # a participant cannot read another participant's data, nor the admin routes
    assert client.get("/admin/participants.json").status_code == 401
    assert client.get("/api/session/not-a-session/trial").status_code == 404


def test_idempotent_replay_and_conflicts(client):
    s = register(client)
    rid = str(uuid.uuid4())
    first = answer(client, s, 0, "left", rid)
    assert first.status_code == 201
    again = answer(client, s, 0, "left", rid)          # network retry: same id, same answer
    assert again.status_code == 200 and again.json()["status"] == "duplicate"
    changed = answer(client, s, 0, "right")             # another id for an answered trial
    assert changed.status_code == 409 and "already answered" in changed.json()["error"]
    reused = answer(client, s, 1, "left", rid)          # the id reused for another trial
    assert reused.status_code == 409 and "already used" in reused.json()["error"]
    skip = answer(client, s, 3, "left")                  # out of order
    assert skip.status_code == 409 and "not the next trial" in skip.json()["error"]
    beyond = answer(client, s, 99, "left")
    assert beyond.status_code == 409 and "no trial 99" in beyond.json()["error"]
    assert len(read_responses(client.db)) == 1


def test_bad_requests_get_clear_errors(client):
    r = client.post("/api/participants", json={"participant_id": "P1"})
    assert r.status_code == 400 and "consent" in r.json()["error"]
    r = client.post("/api/participants", json={"participant_id": "bad id!", "consent": True})
    assert r.status_code == 400 and "participant_id" in r.json()["error"]
    s = register(client, "P1")
    r = client.post("/api/participants", json={"participant_id": "P1", "consent": True})
    assert r.status_code == 409 and "already started" in r.json()["error"]
    # unknown participant session
    r = answer(client, "unknown-session", 0)
    assert r.status_code == 404 and "unknown participant" in r.json()["error"]
    assert client.get("/api/session/unknown-session").status_code == 404
    # malformed responses
    url = f"/api/session/{s}/responses"
    for payload, word in [({"response_id": "x", "trial_index": 0, "choice": "left", "rt_ms": 1}, "UUID"),
                          ({"response_id": str(uuid.uuid4()), "trial_index": -1, "choice": "left", "rt_ms": 1},
                           "trial_index"),
                          ({"response_id": str(uuid.uuid4()), "trial_index": 0, "choice": "top", "rt_ms": 1},
                           "choice"),
                          ({"response_id": str(uuid.uuid4()), "trial_index": 0, "choice": "left", "rt_ms": "1"},
                           "rt_ms"),
                          ({"response_id": str(uuid.uuid4()), "trial_index": 0, "choice": "left", "rt_ms": -3},
                           "rt_ms")]:
        r = client.post(url, json=payload)
        assert r.status_code == 400 and word in r.json()["error"], payload
    # extra (e.g. misspelt) fields are refused, not silently dropped, and nothing is stored
    r = client.post(url, json={"response_id": str(uuid.uuid4()), "trial_index": 0, "choice": "left", "rt_ms": 1,
                               "correct": True})
    assert r.status_code == 422 and "['correct']" in r.json()["error"] and "rt_ms" in r.json()["error"]
    r = client.post("/api/participants", json={"participant_id": "P2", "consent": True, "age": 40})
    assert r.status_code == 422 and "['age']" in r.json()["error"]
    r = client.post(url, content=b"{not json", headers={"Content-Type": "application/json"})
    assert r.status_code == 400 and "not valid JSON" in r.json()["error"]
    r = client.post(url, content=b"[1, 2]", headers={"Content-Type": "application/json"})
    assert r.status_code == 400 and "JSON object" in r.json()["error"]
    # uploads: oversized bodies and non-JSON / image uploads are refused
    r = client.post(url, content=b"x" * 100_000, headers={"Content-Type": "application/json"})
    assert r.status_code == 413 and "too large" in r.json()["error"]
    png = io.BytesIO()
    Image.new("RGB", (8, 8)).save(png, format="PNG")
    r = client.post(url, files={"file": ("plate.png", png.getvalue(), "image/png")})
    assert r.status_code == 415 and "no file uploads" in r.json()["error"]
    r = client.post("/api/participants", content=b"GIF89a...", headers={"Content-Type": "image/gif"})
    assert r.status_code == 415
    # unknown routes, wrong methods, image slots
    assert client.get("/nope").status_code == 404
    assert client.get("/api/participants").status_code == 405
    assert client.get(f"/api/session/{s}/image/0/middle").status_code == 404
    assert client.get(f"/api/session/{s}/image/77/left").status_code == 404
    assert client.get(f"/api/session/{s}/image/0/left/left").status_code == 404  # mono server
    assert len(read_responses(client.db)) == 0


def test_changed_pairs_file_is_refused_for_an_existing_database(tmp_path, pairs_toml):
    from nmmm.errors import DataFileError

    db = tmp_path / "r.sqlite"
    app = create_app(load_pairs(pairs_toml), db, cache_dir=tmp_path / "c1")
    with TestClient(app) as c:
        register(c)
    (tmp_path / "other").mkdir()
    other = make_pairs(tmp_path / "other", n_pairs=2)
    with pytest.raises(DataFileError, match="pairs file differs"):
        create_app(load_pairs(other), db, cache_dir=tmp_path / "c2")
    # the same pairs file is fine (restart)
    create_app(load_pairs(pairs_toml), db, cache_dir=tmp_path / "c3").state.store.close()


def test_stereo_mode(tmp_path):
    toml = make_pairs(tmp_path, n_pairs=2, stereo=True, blank_ms=0, stereo_arrangement="cross")
    app = create_app(load_pairs(toml), tmp_path / "s.sqlite", cache_dir=tmp_path / "cache")
    with TestClient(app) as c:
        cfg = c.get("/api/config").json()
        assert cfg["stereo"] and cfg["slots"] == ["top", "bottom"]
        s = register(c)
        t = c.get(f"/api/session/{s}/trial").json()
        assert set(t["images"]) == {"top", "bottom"}
        for slot in ("top", "bottom"):
            for eye in ("left_eye", "right_eye"):
                assert c.get(t["images"][slot][eye]).status_code == 200
        assert answer(c, s, 0, "left").status_code == 400   # stereo choices are top/bottom
        assert answer(c, s, 0, "bottom").status_code == 201
        assert c.get(f"/api/session/{s}/image/0/top").status_code == 404  # stereo needs an eye
