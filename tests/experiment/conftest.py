"""Fixtures of the experiment tests."""

from __future__ import annotations

import pytest
from experiment_helpers import ServerProcess, make_pairs


@pytest.fixture
def pairs_toml(tmp_path):
    return make_pairs(tmp_path, n_pairs=4, blank_ms=0)


@pytest.fixture
def server_factory():
    servers = []

    def make(*args, **kw):
        s = ServerProcess(*args, **kw)
        servers.append(s)
        return s

    yield make
    for s in servers:
        s.kill()
