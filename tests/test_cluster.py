"""nmmm.cluster.dask_client: a caller's client is passed through and left open; a scheduler that
cannot be reached is a clear error naming the option to leave out; a local cluster is closed on exit."""

import pytest

from nmmm.cluster import dask_client
from nmmm.errors import InvalidInputError

distributed = pytest.importorskip("dask.distributed")


def test_callers_client_is_passed_through_and_left_open():
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as lc, \
            distributed.Client(lc) as c:
        with dask_client(c) as got:
            assert got is c
        assert c.status == "running"


def test_unreachable_scheduler_names_the_option():
    with pytest.raises(InvalidInputError, match=r"no Dask scheduler could be reached.*leave --scheduler out"):
        with dask_client(scheduler="tcp://127.0.0.1:9", scheduler_option="--scheduler"):
            pass


def test_local_cluster_is_closed_on_exit():
    with dask_client(n_workers=1) as c:
        assert c.submit(sum, [1, 2]).result() == 3
    assert c.status in ("closed", "closing")
