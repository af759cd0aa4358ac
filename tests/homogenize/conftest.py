"""Fixtures shared by the homogenization tests."""

import logging

import pytest


@pytest.fixture(scope="module")
def client():
    """A Dask client of two single-threaded in-process workers (the spectral-batch tests)."""
    distributed = pytest.importorskip("dask.distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                       dashboard_address=None, silence_logs=logging.ERROR)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()
