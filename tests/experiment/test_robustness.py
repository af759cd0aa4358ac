"""No 500s (issue 20): hostile numbers and JSON get a 4xx with a message, a database that cannot
store gets a 503 with a message and acknowledges nothing, participant creation resumes."""

from __future__ import annotations

import sqlite3
import uuid
import warnings

import pytest

with warnings.catch_warnings():  # starlette's notice about httpx vs httpx2 in its TestClient
    warnings.simplefilter("ignore")
    from starlette.testclient import TestClient

from nmmm.experiment.app import MAX_JSON_DEPTH, create_app
from nmmm.experiment.pairs import load_pairs
from nmmm.experiment.storage import _SCHEMA, ResponseStore, read_responses

JSON = {"Content-Type": "application/json"}


@pytest.fixture
def client(tmp_path, pairs_toml):
    app = create_app(load_pairs(pairs_toml), tmp_path / "r.sqlite", cache_dir=tmp_path / "cache")
    # raise_server_exceptions=False: a bug would show as a 500 here instead of an exception
    with TestClient(app, raise_server_exceptions=False) as c:
        c.db = tmp_path / "r.sqlite"
        c.store = app.state.store
        yield c


def _session(c, pid="P01", **extra):
    r = c.post("/api/participants", json={"participant_id": pid, "consent": True, **extra})
    assert r.status_code == 201, r.text
    return r.json()["session"]


def _raw_answer(c, s, text):
    return c.post(f"/api/session/{s}/responses", content=text.encode(), headers=JSON)


def _body(trial="0", rt="500", choice='"left"', rid=None):
    return (f'{{"response_id": "{rid or uuid.uuid4()}", "trial_index": {trial}, '
            f'"choice": {choice}, "rt_ms": {rt}}}')


def test_the_five_500s_of_the_issue_are_4xx_with_a_message(client):
    s = _session(client)
    cases = [
        ("GET", f"/api/session/{s}/image/99999999999999999999/left", None, 404, "no trial"),
        ("GET", f"/api/session/{s}/stimuli/99999999999999999999", None, 404, "no trial"),
        ("POST", f"/api/session/{s}/responses", "[" * 5000 + "]" * 5000, 400, "nested too deeply"),
        ("POST", f"/api/session/{s}/responses", _body(trial="1" + "0" * 30), 400, "out of range"),
        ("POST", f"/api/session/{s}/responses", _body(trial="1e30"), 400, "trial_index"),
        ("POST", f"/api/session/{s}/responses", _body(rt="1" + "0" * 400), 400, "out of range"),
    ]
    for method, url, text, status, word in cases:
        r = client.request(method, url, content=None if text is None else text.encode(), headers=JSON)
        assert r.status_code == status, (url, text and text[:60], r.status_code, r.text[:200])
        assert word in r.json()["error"], r.json()
    assert read_responses(client.db) == []


@pytest.mark.parametrize("text, word", [
    (_body(rt="NaN"), "NaN is not a number JSON allows"),
    (_body(rt="Infinity"), "Infinity is not a number"),
    (_body(rt="-Infinity"), "-Infinity is not a number"),
    (_body(rt="1e999"), "out of the range of a double"),
    (_body(rt="1e30"), "rt_ms must be a finite number of milliseconds in [0, 3600000]"),
    (_body(rt="3600000.5"), "rt_ms must be"),
    (_body(trial="12345678901234567"), "there is no trial 12345678901234567"),
    (_body(trial="-1" + "0" * 40), "out of range"),
    (_body(trial="1" * 5000), "out of range"),          # beyond Python's own int-digit limit
    (_body(choice="[" * 3 + "]" * 3), "choice must be one of"),
    (_body(choice='{"a": {"b": {"c": {"d": 1}}}}'), "nested too deeply"),
    ('{"a": ' * 900 + "1" + "}" * 900, "nested too deeply"),
    ('"\\ud800"', "JSON object"),
])
def test_hostile_numbers_and_nesting_are_refused(client, text, word):
    s = _session(client)
    r = _raw_answer(client, s, text)
    assert 400 <= r.status_code < 500, (r.status_code, r.text[:300])
    assert word in r.json()["error"], r.json()["error"]
    assert read_responses(client.db) == []


def test_json_depth_limit_is_what_the_api_needs(client):
    # the participant route's 'screen' object is depth 2: accepted; MAX_JSON_DEPTH + 1 is not
    r = client.post("/api/participants", json={"participant_id": "P9", "consent": True,
                                               "screen": {"width": 1920, "height": 1080, "dpr": 1.0}})
    assert r.status_code == 201
    deep = {"x": 1}
    for _ in range(MAX_JSON_DEPTH):
        deep = {"x": deep}
    r = client.post("/api/participants", json={"participant_id": "P8", "consent": True, "screen": deep})
    assert r.status_code == 400 and "nested too deeply" in r.json()["error"]


def test_full_database_is_503_and_nothing_is_acknowledged(client):
    sessions = [_session(client, f"P{i:02d}") for i in range(40)]
    con = client.store._con   # the server's writer: cap the file at its current size (a full disk)
    con.execute(f"PRAGMA max_page_count={con.execute('PRAGMA page_count').fetchone()[0]}")
    acked, refused = [], None
    for t in range(4):                      # answer trial after trial until the file is full
        for s in sessions:
            rid = str(uuid.uuid4())
            r = _raw_answer(client, s, _body(trial=str(t), rid=rid))
            if r.status_code == 201:
                acked.append(rid)
                continue
            refused = (s, t, rid, r)
            break
        if refused:
            break
    assert refused is not None, "the capped database never filled"
    s, t, rid, r = refused
    assert r.status_code == 503, r.text
    msg = r.json()["error"]
    assert "cannot store" in msg and "full" in msg and "Nothing was stored" in msg
    assert r.headers["retry-after"].isdigit()
    stored = {x["response_id"] for x in read_responses(client.db)}
    assert stored == set(acked) and rid not in stored      # every 201 stored, the 503 not
    # a new participant cannot be created either: 503, not 500
    r = client.post("/api/participants", json={"participant_id": "Q01", "consent": True})
    assert r.status_code == 503 and "full" in r.json()["error"]
    # space again: the client's retry with the same id is stored once
    con.execute("PRAGMA max_page_count=1073741823")
    r = _raw_answer(client, s, _body(trial=str(t), rid=rid))
    assert r.status_code == 201 and r.json()["status"] == "stored"
    assert _raw_answer(client, s, _body(trial=str(t), rid=rid)).json()["status"] == "duplicate"
    assert {x["response_id"] for x in read_responses(client.db)} == set(acked) | {rid}


def test_read_only_database_is_503_with_a_message(client):
    s = _session(client)
    client.store._con.execute("PRAGMA query_only=ON")   # as a read-only file or file system
    r = _raw_answer(client, s, _body())
    assert r.status_code == 503 and "read-only" in r.json()["error"], r.text
    assert read_responses(client.db) == []
    client.store._con.execute("PRAGMA query_only=OFF")
    assert _raw_answer(client, s, _body()).status_code == 201


def test_read_only_database_at_start_is_a_clear_error(tmp_path, pairs_toml):
    from nmmm.errors import DataFileError

    db = tmp_path / "ro.sqlite"
    ResponseStore(db).close()
    uri = db.resolve().as_uri() + "?mode=ro"
    with pytest.raises(DataFileError, match="read-only"):
        # a store whose writer cannot write (as on a read-only file system)
        store = ResponseStore.__new__(ResponseStore)
        ResponseStore.__init__(store, db)
        store._con.close()
        store._con = sqlite3.connect(uri, uri=True, isolation_level=None, check_same_thread=False)
        store._con.row_factory = sqlite3.Row
        store.register_pairs(load_pairs(pairs_toml))


def test_participant_creation_is_idempotent_with_the_client_token(client):
    tok = "k" * 8 + uuid.uuid4().hex
    first = client.post("/api/participants", json={"participant_id": "P01", "consent": True, "client_token": tok})
    assert first.status_code == 201 and first.json()["resumed"] is False
    s = first.json()["session"]
    r = _raw_answer(client, s, _body())
    assert r.status_code == 201
    # the reply was lost (server crash): the page retries with the same id and token -> resumes
    again = client.post("/api/participants", json={"participant_id": "P01", "consent": True, "client_token": tok})
    assert again.status_code == 200 and again.json()["resumed"] is True
    assert again.json()["session"] == s and again.json()["answered"] == 1
    # another browser (another token, or none) cannot take the participant over
    for extra in ({"client_token": "z" * 32}, {}):
        r = client.post("/api/participants", json={"participant_id": "P01", "consent": True, **extra})
        assert r.status_code == 409 and "already started" in r.json()["error"]
    r = client.post("/api/participants", json={"participant_id": "P03", "consent": True, "client_token": "short"})
    assert r.status_code == 400 and "client_token" in r.json()["error"]


def test_participant_resumes_after_a_restart_lost_the_reply(tmp_path, pairs_toml, server_factory):
    import httpx

    db = tmp_path / "r.sqlite"
    srv = server_factory(pairs_toml, db).start()
    tok = uuid.uuid4().hex
    body = {"participant_id": "C01", "consent": True, "client_token": tok}
    with httpx.Client(base_url=srv.url, timeout=10) as c:
        s = c.post("/api/participants", json=body).json()["session"]
    srv.kill()   # SIGKILL right after the commit: the page never saw the reply
    srv.start()
    with httpx.Client(base_url=srv.url, timeout=10) as c:
        r = c.post("/api/participants", json=body)
        assert r.status_code == 200 and r.json()["session"] == s and r.json()["resumed"]
        assert c.get(f"/api/session/{s}/trial").json()["trial_index"] == 0


def test_schema_1_database_is_upgraded_in_place(tmp_path, pairs_toml):
    db = tmp_path / "old.sqlite"
    con = sqlite3.connect(db)
    con.executescript(_SCHEMA.replace(",\n    client_token_sha256 TEXT", ""))
    con.execute("INSERT INTO participants VALUES ('OLD', 'tok', 1, 0, 4, 'now', 'sha', '', '{}', 'now')")
    con.commit()
    con.close()
    with ResponseStore(db) as store:
        assert store.participant_by_token("tok")["client_token_sha256"] is None
        ps = load_pairs(pairs_toml)
        store.register_pairs(ps)
        assert store.create_participant("NEW", ps, consent_sha256="x", client_token="t" * 20)["resumed"] is False
