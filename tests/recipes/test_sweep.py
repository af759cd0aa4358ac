"""Sweeps: a LocalCluster of 2 worker processes gives the serial numbers, a worker killed
mid-sweep loses nothing, and a rerun resumes."""

import os
import signal
import threading
import time

import numpy as np
import pytest

from nmmm.errors import RecipeError
from nmmm.recipes.sweep import load_results, sweep

from .conftest import fast_raw

VARY = [("pigment.fraction", [0.03, 0.06, 0.09]), ("pigment.body_diagonal_nm", [150.0, 400.0])]


def _raw():
    return fast_raw("hematite_paint", step_nm=40.0)


@pytest.fixture(scope="module")
def serial_results(tmp_path_factory):
    out = tmp_path_factory.mktemp("serial")
    return sweep(_raw(), VARY, out, serial=True, progress=False, plots=False)["results"]


@pytest.fixture(scope="module")
def client():
    distributed = pytest.importorskip("dask.distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def _check_same(a, b):
    cols = ["param:pigment.fraction", "param:pigment.body_diagonal_nm", "L_D65", "a_D65", "b_D65", "L_A"]
    a = a.sort_values(cols[:2]).reset_index(drop=True)
    b = b.sort_values(cols[:2]).reset_index(drop=True)
    assert len(a) == len(b)
    np.testing.assert_allclose(a[cols].to_numpy(float), b[cols].to_numpy(float), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(np.stack(a["spectrum"]), np.stack(b["spectrum"]), rtol=1e-12, atol=1e-15)


def test_cluster_gives_the_serial_numbers(client, serial_results, tmp_path):
    # through the scheduler's address, as `nmmm sweep --scheduler tcp://HOST:8786` does
    s = sweep(_raw(), VARY, tmp_path, scheduler=client.scheduler.address, progress=False)
    assert s["n_points"] == 6 and s["n_computed"] == 6
    assert s["results"]["worker"].nunique() >= 1
    assert len(list((tmp_path / "points").glob("*.parquet"))) == 6
    assert (tmp_path / "results.parquet").exists() and (tmp_path / "sweep.png").exists()
    _check_same(s["results"], serial_results)


def test_killed_worker_mid_sweep_still_completes(client, serial_results, tmp_path):
    out = {}
    th = threading.Thread(target=lambda: out.update(s=sweep(_raw(), VARY, tmp_path, client=client, progress=False,
                                                            plots=False)))
    th.start()
    killed = None
    deadline = time.time() + 120
    while killed is None and time.time() < deadline and th.is_alive():
        for addr, keys in client.processing().items():
            if any(str(k).startswith("nmmm-point-") for k in keys):
                pid = client.run(os.getpid, workers=[addr])[addr]
                os.kill(pid, signal.SIGKILL)
                killed = addr
                break
        time.sleep(0.02)
    th.join(300)
    assert killed is not None, "no point was in flight to kill"
    s = out["s"]
    assert s["n_computed"] == 6
    _check_same(s["results"], serial_results)


def test_rerun_resumes_and_skips_finished_points(serial_results, tmp_path):
    first = sweep(_raw(), VARY[:1], tmp_path, serial=True, progress=False, plots=False)
    assert first["n_computed"] == 3
    files = sorted((tmp_path / "points").glob("*.parquet"))
    files[0].unlink()  # as if the sweep had stopped before this point
    (tmp_path / "points" / ".junk.tmp").write_text("partial write")  # interrupted writes are ignored
    again = sweep(_raw(), VARY[:1], tmp_path, serial=True, progress=False, plots=False)
    assert (again["n_skipped"], again["n_computed"]) == (2, 1)
    assert len(load_results(tmp_path)) == 3
    np.testing.assert_allclose(first["results"]["L_D65"], again["results"]["L_D65"], rtol=1e-12)
    # a changed recipe does not reuse the old points
    from nmmm.recipes.schema import set_key

    changed = sweep(set_key(_raw(), "film.thickness_nm", 5000.0), VARY[:1], tmp_path, serial=True, progress=False,
                    plots=False)
    assert changed["n_computed"] == 3 and len(changed["results"]) == 3


def test_invalid_grid_value_is_refused_before_computing(tmp_path):
    with pytest.raises(RecipeError, match=r"pigment\.fraction: must be in \[0, 1\]"):
        sweep(_raw(), ["pigment.fraction=0.5:1.5:3"], tmp_path, serial=True, progress=False)
    assert not list((tmp_path / "points").glob("*.parquet")) if (tmp_path / "points").exists() else True
    with pytest.raises(RecipeError, match="no such key"):
        sweep(_raw(), ["pigmnt.fraction=0.1"], tmp_path, serial=True, progress=False)
