"""The Dask client that sweeps (:mod:`nmmm.recipes.sweep`) and spectral batches
(:mod:`nmmm.homogenize.spectral_batches`) run on: a caller's client, a running scheduler, or a
``LocalCluster`` of single-threaded worker processes made for the call and closed after it.

- :func:`dask_client` — that client as a context manager, with clear errors when a scheduler
  cannot be reached or local worker processes do not start.

Dask is imported inside the function (it is a core dependency, but most of nmmm never needs it).

References
----------
- Dask Development Team, Dask: Library for dynamic task scheduling (2016), https://dask.org ;
  ``dask.distributed`` Client and LocalCluster.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

from nmmm.errors import InvalidInputError

__all__ = ["dask_client"]


@contextlib.contextmanager
def dask_client(client=None, scheduler: str | None = None, n_workers: int = 2, scheduler_option: str = "scheduler",
                caller: str = "this call") -> Iterator[object]:
    """Yield ``client`` if given; else a client of the scheduler at ``scheduler``
    (``"tcp://HOST:8786"``); else one of a new ``LocalCluster`` of ``n_workers`` single-threaded
    processes. What this function opened is closed on exit; a caller's client is left open.

    ``scheduler_option`` names the option the user gave (``"--scheduler"`` on the command line) and
    ``caller`` the function, in the error messages."""
    if client is not None:
        yield client
        return
    import logging

    from dask.distributed import Client, LocalCluster

    own_cluster = own_client = None
    try:
        if scheduler:
            try:
                own_client = Client(scheduler)
            except (OSError, TimeoutError, ValueError) as exc:
                raise InvalidInputError(
                    f"scheduler {scheduler!r}: no Dask scheduler could be reached ({exc}); start one with "
                    "'dask scheduler' (and workers with 'dask worker ADDRESS'), give its tcp://HOST:8786 "
                    f"address, or leave {scheduler_option} out for a local cluster") from None
        else:
            try:
                own_cluster = LocalCluster(n_workers=int(n_workers), threads_per_worker=1, processes=True,
                                           dashboard_address=None, silence_logs=logging.ERROR)
            except RuntimeError as exc:
                raise InvalidInputError(
                    f"the local Dask cluster's {int(n_workers)} worker processes did not start ({exc}); in a "
                    f"script, call {caller} under 'if __name__ == \"__main__\":' (worker processes import the "
                    "main module again), or give a client / scheduler") from exc
            own_client = Client(own_cluster)
        yield own_client
    finally:
        if own_client is not None:
            own_client.close()
        if own_cluster is not None:
            own_cluster.close()
