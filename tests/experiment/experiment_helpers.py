"""Helpers of the experiment tests: small image pairs, a pairs.toml, a server subprocess."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def write_image(path, size=(48, 32), colour=(120, 100, 80), fmt=None, seed=0, **save_kw):
    from PIL import Image

    rng = np.random.default_rng(seed)
    a = np.clip(np.array(colour)[None, None, :] + rng.normal(0, 4, (size[1], size[0], 3)), 0, 255)
    Image.fromarray(a.astype(np.uint8)).save(path, format=fmt, **save_kw)
    return Path(path)


def make_pairs(tmp_path, n_pairs=4, stereo=False, **settings):
    """n_pairs rendered/photo images (photo as JPEG with EXIF, render as PNG) and pairs.toml."""
    from nmmm.experiment.pairs import make_pairs_file

    img = tmp_path / "img"
    img.mkdir(exist_ok=True)
    triples, stereo_views = [], []
    for i in range(n_pairs):
        render = write_image(img / f"r{i}.png", size=(48, 32), colour=(100 + 10 * i, 90, 80), seed=i)
        photo = write_image(img / f"p{i}.jpg", size=(96, 64), colour=(100 + 10 * i, 92, 78), seed=100 + i,
                            quality=90)
        triples.append((render, photo, f"plate {i}"))
        if stereo:
            views = [write_image(img / f"{k}{i}_{e}.png", size=(40, 30), seed=7 * i + j)
                     for j, (k, e) in enumerate([("r", "L"), ("r", "R"), ("p", "L"), ("p", "R")])]
            stereo_views.append(((views[0], views[1]), (views[2], views[3])))
    if stereo:
        settings["stereo"] = True
    return make_pairs_file(triples, tmp_path / "pairs.toml", stereo_pairs=stereo_views if stereo else None,
                           **settings)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class ServerProcess:
    """``nmmm experiment serve`` in a real subprocess on 127.0.0.1."""

    def __init__(self, pairs_toml, db, port=None, token="admin-secret"):
        self.pairs_toml, self.db, self.port, self.token = pairs_toml, db, port or free_port(), token
        self.proc = None

    @property
    def url(self):
        return f"http://127.0.0.1:{self.port}"

    def start(self, timeout_s=30.0):
        import httpx

        env = dict(os.environ, NMMM_EXPERIMENT_ADMIN_TOKEN=self.token)
        self.proc = subprocess.Popen(
            [sys.executable, "-c", "import sys; from nmmm.cli import main; sys.exit(main())", "experiment",
             "serve", str(self.pairs_toml), "--db", str(self.db), "--port", str(self.port)],
            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError(f"server exited: {self.proc.stderr.read().decode()}")
            try:
                if httpx.get(self.url + "/healthz", timeout=1.0).status_code == 200:
                    return self
            except httpx.HTTPError:
                time.sleep(0.1)
        self.kill()
        raise RuntimeError("server did not start in time")

    def kill(self):
        """SIGKILL: no shutdown hook runs, as when the machine or the process dies."""
        if self.proc is not None and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(timeout=10)
        if self.proc is not None and self.proc.stderr:
            self.proc.stderr.close()
        self.proc = None
