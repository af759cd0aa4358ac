"""Benchmark of the 2AFC experiment server and response store.

1. The response store alone: committed responses per second with ``synchronous=FULL`` (the
   server's setting: every response on disk before it is acknowledged) against
   ``synchronous=NORMAL`` and ``OFF`` (what a user would get from a default SQLite set-up that
   trades durability for speed) — the ratio is the price of durability.
2. The real server (``nmmm experiment serve`` subprocess on 127.0.0.1 only): N simulated
   participants at once (lean asyncio HTTP/1.1 clients), each registering, fetching every trial and its
   stimuli (one raw body per trial, as the page does) and answering. With ``--kill-after K``
   the server is SIGKILLed once K responses are stored and restarted at once (as a supervisor
   would); clients retry network errors and 5xx like the page (100 ms, doubling, at most 1 s
   between tries, same response id). Prints throughput, the restart time (kill to healthy,
   stimuli reused from the content-addressed cache), latency percentiles of every request
   (including the retries across the restart) and checks that every response is stored exactly
   once.

Every loop is bounded (a deadline; the server is killed at the end), and no address outside
127.0.0.0/8 is ever used.

Run: ``python benchmarks/bench_experiment.py [--participants 200 --pairs 10 --kill-after 2000]``
(``--json`` prints the result as JSON). Numbers depend on the disk (fsync) and on the
machine's load.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import socket
import sqlite3
import subprocess
import sys
import tempfile
import time
import uuid
from pathlib import Path

import numpy as np

HOST = "127.0.0.1"   # loopback only


def store_rate(pairset, sync: str, n_participants: int = 20) -> float:
    from nmmm.experiment.storage import ResponseStore

    with tempfile.TemporaryDirectory() as d:
        with ResponseStore(Path(d) / "r.sqlite", synchronous=sync) as store:
            store.register_pairs(pairset)
            parts = [store.create_participant(f"P{i}", pairset, consent_sha256="-") for i in range(n_participants)]
            t0 = time.perf_counter()
            n = 0
            for p in parts:
                for t in range(p["n_trials"]):
                    store.record_response(p["participant_id"], t, str(uuid.uuid4()), t % 2, 500.0)
                    n += 1
            return n / (time.perf_counter() - t0)


class Server:
    """``nmmm experiment serve`` on 127.0.0.1 in a subprocess (SIGKILL to stop it)."""

    def __init__(self, pairs_toml, db, cache_dir):
        with socket.socket() as s:
            s.bind((HOST, 0))
            self.port = s.getsockname()[1]
        self.args = [sys.executable, "-c", "import sys; from nmmm.cli import main; sys.exit(main())", "experiment",
                     "serve", str(pairs_toml), "--db", str(db), "--host", HOST, "--port", str(self.port)]
        self.env = dict(os.environ, NMMM_STIMULUS_CACHE=str(cache_dir))
        self.url = f"http://{HOST}:{self.port}"
        self.proc = None

    def start(self, timeout_s: float = 60.0) -> float:
        import httpx

        t0 = time.perf_counter()
        self.proc = subprocess.Popen(self.args, env=self.env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        while time.perf_counter() - t0 < timeout_s:
            if self.proc.poll() is not None:
                raise RuntimeError("the server exited at start")
            try:
                if httpx.get(self.url + "/healthz", timeout=0.5).status_code == 200:
                    return time.perf_counter() - t0
            except httpx.HTTPError:
                time.sleep(0.02)
        self.kill()
        raise RuntimeError("the server did not start in time")

    def kill(self):
        if self.proc is not None and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(timeout=10)
        self.proc = None


def count_rows(db) -> int:
    con = sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=30)
    try:
        return con.execute("SELECT COUNT(*) FROM responses").fetchone()[0]
    except sqlite3.Error:
        return 0
    finally:
        con.close()


class LeanClient:
    """One participant's keep-alive HTTP/1.1 connection over asyncio streams.

    The load generator runs on the same machine as the server; httpx would spend about three
    times the server's CPU on parsing (measured: 14 s against 5 s for 1000 trials), so the
    benchmark would mostly measure itself. This client does no more than a browser's network
    stack must: write the request, read the status line, the headers and Content-Length bytes.
    """

    def __init__(self, port: int):
        self.port = port
        self.reader = self.writer = None

    async def close(self):
        if self.writer is not None:
            self.writer.close()
            try:
                await self.writer.wait_closed()
            except OSError:
                pass
        self.reader = self.writer = None

    async def request(self, method: str, path: str, payload=None, timeout_s: float = 30.0):
        if self.writer is None:
            self.reader, self.writer = await asyncio.open_connection(HOST, self.port)
        body = b"" if payload is None else json.dumps(payload).encode()
        head = f"{method} {path} HTTP/1.1\r\nHost: {HOST}:{self.port}\r\nContent-Length: {len(body)}\r\n"
        if payload is not None:
            head += "Content-Type: application/json\r\n"
        self.writer.write(head.encode() + b"\r\n" + body)

        async def read():
            status = int((await self.reader.readline()).split()[1])
            length, close = 0, False
            while (line := await self.reader.readline()) not in (b"\r\n", b""):
                k, _, v = line.decode("latin-1").partition(":")
                k = k.strip().lower()
                if k == "content-length":
                    length = int(v)
                elif k == "connection" and v.strip().lower() == "close":
                    close = True
            data = await self.reader.readexactly(length)
            if close:
                await self.close()
            return status, data

        return await asyncio.wait_for(read(), timeout_s)


def server_load(pairs_toml, n_participants: int, kill_after: int | None = None, deadline_s: float = 900.0,
                work=None, rt_ms: float = 0.0, blank_ms: float = 0.0, seed: int = 0) -> dict:
    """Run the load (and the kill/restart); return the measurements and the exactly-once check.

    Each simulated participant behaves as the page does: the blank interval (``blank_ms``)
    runs while the trial and its stimuli are fetched, then the participant answers after a
    response time (log-normal around ``rt_ms``; 0: at once, the worst case for the server).
    """
    work = Path(work or tempfile.mkdtemp(prefix="nmmm-bench-"))
    db = work / "load.sqlite"
    srv = Server(pairs_toml, db, work / "stimulus-cache")
    first_start = srv.start()
    latencies = {"register": [], "trial": [], "stimuli": [], "response": []}
    sent: dict[tuple, str] = {}
    outcome = {"restart_s": None, "killed_at_rows": None, "errors": 0}
    t_end = time.perf_counter() + deadline_s
    rng = np.random.default_rng(seed)

    async def call(conn, kind, method, url, payload=None):
        """One request as the page makes it: retried on network errors and 5xx (same body)."""
        t0 = time.perf_counter()
        delay = 0.1
        while True:
            if time.perf_counter() > t_end:
                raise TimeoutError("benchmark deadline passed")
            try:
                status, data = await conn.request(method, url, payload)
                if status < 500:
                    latencies[kind].append(time.perf_counter() - t0)
                    return status, data
            except (OSError, asyncio.IncompleteReadError, asyncio.TimeoutError, IndexError, ValueError):
                await conn.close()
            await asyncio.sleep(delay)
            delay = min(2 * delay, 1.0)

    async def participant(i):
        conn = LeanClient(srv.port)
        pid = f"B{i:04d}"
        token = uuid.uuid4().hex
        status, data = await call(conn, "register", "POST", "/api/participants",
                                  {"participant_id": pid, "consent": True, "client_token": token})
        assert status in (200, 201), data
        s = json.loads(data)["session"]
        try:
            while True:
                blank = asyncio.create_task(asyncio.sleep(blank_ms / 1e3))
                t = json.loads((await call(conn, "trial", "GET", f"/api/session/{s}/trial"))[1])
                if t["done"]:
                    blank.cancel()
                    return
                _, body = await call(conn, "stimuli", "GET", t["stimuli"]["url"])
                assert len(body) == t["stimuli"]["bytes"]
                await blank
                if rt_ms > 0:
                    await asyncio.sleep(rt_ms / 1e3 * float(np.exp(rng.normal(0, 0.35))))
                key = (pid, t["trial_index"])
                rid = sent.setdefault(key, str(uuid.uuid4()))   # a resent answer keeps its id
                status, _ = await call(conn, "response", "POST", f"/api/session/{s}/responses",
                                       {"response_id": rid, "trial_index": t["trial_index"],
                                        "choice": "left" if (i + t["trial_index"]) % 2 else "right", "rt_ms": 700})
                if status not in (200, 201):
                    outcome["errors"] += 1
        finally:
            await conn.close()

    async def killer():
        if kill_after is None:
            return
        while count_rows(db) < kill_after:
            if time.perf_counter() > t_end:
                return
            await asyncio.sleep(0.05)
        outcome["killed_at_rows"] = count_rows(db)
        srv.kill()   # SIGKILL: no shutdown hook runs
        outcome["restart_s"] = await asyncio.to_thread(srv.start)

    async def main():
        kill_task = asyncio.create_task(killer())
        await asyncio.gather(*(participant(i) for i in range(n_participants)))
        await kill_task

    t0 = time.perf_counter()
    load0 = os.getloadavg()[0]
    try:
        asyncio.run(main())
        wall = time.perf_counter() - t0
    finally:
        srv.kill()
    con = sqlite3.connect(db)
    rows = con.execute("SELECT response_id, participant_id, trial_index FROM responses").fetchall()
    n_trials = con.execute("SELECT n_trials FROM participants LIMIT 1").fetchone()[0]
    con.close()
    stored = {(p, t): rid for rid, p, t in rows}
    all_lat = np.concatenate([np.asarray(v) for v in latencies.values() if v])
    return {
        "participants": n_participants, "trials_per_participant": n_trials, "wall_s": wall,
        "blank_ms": blank_ms, "rt_ms": rt_ms, "load_average": [load0, os.getloadavg()[0]],
        "first_start_s": first_start, "restart_s": outcome["restart_s"], "killed_at_rows": outcome["killed_at_rows"],
        "expected": n_participants * n_trials, "stored": len(rows), "unique": len(stored),
        "exactly_once": len(rows) == len(stored) == n_participants * n_trials and stored == sent,
        "errors": outcome["errors"],
        "latency_ms": {k: {"median": 1e3 * float(np.median(v)), "p95": 1e3 * float(np.percentile(v, 95)),
                           "p99": 1e3 * float(np.percentile(v, 99)), "max": 1e3 * float(np.max(v))}
                       for k, v in [*latencies.items(), ("all", all_lat)] if len(v)},
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--participants", type=int, default=200)
    ap.add_argument("--pairs", type=int, default=10)
    ap.add_argument("--repetitions", type=int, default=2)
    ap.add_argument("--size-px", type=int, default=256)
    ap.add_argument("--kill-after", type=int, default=None,
                    help="SIGKILL the server once this many responses are stored, then restart it "
                         "(default: half of all responses; 0: no kill)")
    ap.add_argument("--deadline-s", type=float, default=900.0, help="stop the run after this many seconds")
    ap.add_argument("--blank-ms", type=float, default=0.0, help="blank interval before each trial (page default 1000)")
    ap.add_argument("--rt-ms", type=float, default=0.0, help="median response time of the simulated participants")
    ap.add_argument("--no-store", action="store_true", help="skip the response-store benchmark")
    ap.add_argument("--json", action="store_true", help="print the server measurement as JSON")
    args = ap.parse_args()
    from nmmm.experiment.pairs import load_pairs
    from nmmm.experiment.simulation import synthetic_pairs

    work = Path(tempfile.mkdtemp(prefix="nmmm-bench-"))
    toml = synthetic_pairs(work, n_pairs=args.pairs, size_px=args.size_px, repetitions=args.repetitions, blank_ms=0)
    ps = load_pairs(toml)
    if not args.no_store and not args.json:
        rates = {s: store_rate(ps, s) for s in ("FULL", "NORMAL", "OFF")}
        print("response store, committed responses/s: " + ", ".join(f"{k} {v:,.0f}" for k, v in rates.items()))
        print(f"  price of durability: FULL is {rates['NORMAL'] / rates['FULL']:.2f}x slower than NORMAL, "
              f"{rates['OFF'] / rates['FULL']:.2f}x slower than OFF")
    kill = args.kill_after if args.kill_after is not None else args.participants * ps.n_trials // 2
    res = server_load(toml, args.participants, kill_after=kill or None, deadline_s=args.deadline_s, work=work,
                      rt_ms=args.rt_ms, blank_ms=args.blank_ms)
    if args.json:
        print(json.dumps(res, indent=2))
        return 0 if res["exactly_once"] else 1
    n = res["stored"]
    print(f"server: {res['participants']} participants x {res['trials_per_participant']} trials = {n} of "
          f"{res['expected']} responses stored in {res['wall_s']:.1f} s; exactly once: {res['exactly_once']} "
          f"(cpu count {os.cpu_count()}, load average {res['load_average'][0]:.1f} at start)")
    print(f"  participants answer {res['rt_ms']:g} ms (median) after a blank of {res['blank_ms']:g} ms")
    print(f"  first start {res['first_start_s']:.2f} s; "
          + (f"SIGKILL at {res['killed_at_rows']} stored, restart (stimuli from the cache) {res['restart_s']:.2f} s"
             if res["restart_s"] is not None else "no kill"))
    for k, v in res["latency_ms"].items():
        print(f"  {k:>9} latency: median {v['median']:.1f} ms, p95 {v['p95']:.1f} ms, p99 {v['p99']:.1f} ms, "
              f"max {v['max']:.1f} ms")
    return 0 if res["exactly_once"] else 1


if __name__ == "__main__":
    sys.exit(main())
