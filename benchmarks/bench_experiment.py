"""Benchmark of the 2AFC experiment server and response store.

1. The response store alone: committed responses per second with ``synchronous=FULL`` (the
   server's setting: every response on disk before it is acknowledged) against
   ``synchronous=NORMAL`` and ``OFF`` (what a user would get from a default SQLite set-up that
   trades durability for speed) — the ratio is the price of durability.
2. The real server (uvicorn subprocess on 127.0.0.1): N simulated participants at once, each
   registering, fetching every trial and its two images, and answering. Prints throughput and
   the latency percentiles of the response POST.

Run: ``python benchmarks/bench_experiment.py [--participants 50]``. Numbers depend on the disk
(fsync) and on the machine's load.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import os
import socket
import subprocess
import sys
import tempfile
import time
import uuid
from pathlib import Path

import numpy as np


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


def server_load(pairs_toml, n_participants: int):
    import httpx

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    d = tempfile.mkdtemp()
    proc = subprocess.Popen([sys.executable, "-c", "import sys; from nmmm.cli import main; sys.exit(main())",
                             "experiment", "serve", str(pairs_toml), "--db", f"{d}/load.sqlite", "--port", str(port)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    url = f"http://127.0.0.1:{port}"
    try:
        for _ in range(300):
            try:
                if httpx.get(url + "/healthz", timeout=1).status_code == 200:
                    break
            except httpx.HTTPError:
                time.sleep(0.1)
        client = httpx.Client(base_url=url, timeout=60, limits=httpx.Limits(max_connections=n_participants + 8))
        latencies = []

        def participant(i):
            s = client.post("/api/participants", json={"participant_id": f"B{i}", "consent": True}).json()["session"]
            while True:
                t = client.get(f"/api/session/{s}/trial").json()
                if t["done"]:
                    return
                for slot in ("left", "right"):
                    client.get(t["images"][slot])
                t0 = time.perf_counter()
                r = client.post(f"/api/session/{s}/responses", json={
                    "response_id": str(uuid.uuid4()), "trial_index": t["trial_index"], "choice": "left", "rt_ms": 700})
                latencies.append(time.perf_counter() - t0)
                assert r.status_code == 201

        t0 = time.perf_counter()
        with cf.ThreadPoolExecutor(n_participants) as pool:
            list(pool.map(participant, range(n_participants)))
        wall = time.perf_counter() - t0
        client.close()
        return wall, np.array(latencies)
    finally:
        proc.kill()
        proc.wait()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--participants", type=int, default=50)
    ap.add_argument("--pairs", type=int, default=10)
    args = ap.parse_args()
    from nmmm.experiment.simulation import synthetic_pairs
    from nmmm.experiment.pairs import load_pairs

    work = Path(tempfile.mkdtemp())
    toml = synthetic_pairs(work, n_pairs=args.pairs, size_px=256, repetitions=2, blank_ms=0)
    ps = load_pairs(toml)
    rates = {s: store_rate(ps, s) for s in ("FULL", "NORMAL", "OFF")}
    print(f"response store, committed responses/s: " + ", ".join(f"{k} {v:,.0f}" for k, v in rates.items()))
    print(f"  price of durability: FULL is {rates['NORMAL'] / rates['FULL']:.2f}x slower than NORMAL, "
          f"{rates['OFF'] / rates['FULL']:.2f}x slower than OFF")
    wall, lat = server_load(toml, args.participants)
    n = lat.size
    print(f"server: {args.participants} participants x {ps.n_trials} trials = {n} responses in {wall:.1f} s "
          f"({n / wall:,.0f} responses/s with their trial and image requests)")
    print(f"  response POST latency: median {1e3 * np.median(lat):.1f} ms, p95 {1e3 * np.percentile(lat, 95):.1f} ms, "
          f"max {1e3 * lat.max():.1f} ms  (cpu count {os.cpu_count()})")


if __name__ == "__main__":
    main()
