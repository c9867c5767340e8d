"""Where the recordings of a fleet run: in this process, or on a Dask cluster.

``run_tasks(fn, items, engine=, address=, workers=, on_done=)`` returns ``fn(item)`` for every
item in input order: ``"local"`` (serial) or ``"dask"`` (a ``LocalCluster`` of one-thread
workers, or an existing scheduler at ``address``; the extra ``fogbayes[dask]``, checked by
:func:`check_engine`). Workers import :mod:`fogbayes` first (float64) and need the same paths.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from ..support.extras import DASK, require
from .files import FleetError

ENGINES = ("local", "dask")


def check_engine(engine: str, address: str | None, workers: int) -> None:
    if engine not in ENGINES:
        raise FleetError(f"unknown engine '{engine}'", column="--engine",
                         fix=f"use one of {', '.join(ENGINES)}")
    if address and engine != "dask":
        raise FleetError("--address names a Dask scheduler", column="--address",
                         fix="add --engine dask, or drop --address")
    if int(workers) < 1:
        raise FleetError(f"--workers {workers} is below 1", column="--workers",
                         fix="use e.g. --workers 2")
    if engine == "dask":  # before any work starts: one line naming the extra if it is missing
        require("distributed", *DASK)


def _worker_plugin():
    distributed = require("distributed", *DASK)

    class ImportFogbayes(distributed.WorkerPlugin):
        """Import fogbayes (float64 on) in the worker before any task runs."""

        name = "fogbayes-float64"

        def setup(self, worker):
            import jax

            import fogbayes  # noqa: F401

            if not jax.config.jax_enable_x64:
                raise RuntimeError("fogbayes did not turn on JAX float64 in this worker")

    return ImportFogbayes()


@contextmanager
def dask_client(address: str | None = None, workers: int = 2) -> Iterator[Any]:
    """A Dask client: on a local cluster we start (and close), or on ``address``."""
    distributed = require("distributed", *DASK)
    Client, LocalCluster = distributed.Client, distributed.LocalCluster

    cluster = None
    try:
        if address:
            client = Client(address, timeout="20s")
        else:
            cluster = LocalCluster(n_workers=int(workers), threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=logging.ERROR)
            client = Client(cluster)
    except (OSError, TimeoutError) as exc:  # no scheduler there, or it did not answer
        raise FleetError(f"cannot reach a Dask scheduler at {address!r} ({exc})",
                         column="--address",
                         fix="start one ('dask scheduler' and 'dask worker ADDRESS') or drop "
                             "--address for a local cluster") from None
    try:
        client.register_plugin(_worker_plugin())
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def n_workers(client) -> int:
    return len(client.scheduler_info().get("workers", {}))


def run_tasks(fn: Callable[[Any], Any], items: Sequence[Any], *, engine: str = "local",
              address: str | None = None, workers: int = 2,
              on_done: Callable[[Any], None] | None = None,
              on_error: Callable[[Any, BaseException], Any] | None = None,
              on_start: Callable[[], None] | None = None) -> dict:
    """``fn`` over ``items`` on ``engine``; returns ``{"results": [...], "workers": n}``.

    ``on_done(result)`` is called as each item finishes (progress bars); ``on_error(item,
    exc)`` turns an exception that escaped ``fn`` (or a lost worker) into that item's
    result -- without it, the exception propagates. ``on_start()`` is called once the
    engine is up (the cluster reached), just before the first item is run.
    """
    check_engine(engine, address, workers)
    items = list(items)
    on_done = on_done or (lambda r: None)

    def failed(item, exc):
        if on_error is None:
            raise exc
        return on_error(item, exc)

    if engine == "local":
        if on_start is not None:
            on_start()
        results = []
        for item in items:
            try:
                r = fn(item)
            except Exception as exc:  # noqa: BLE001  (handed to on_error)
                r = failed(item, exc)
            results.append(r)
            on_done(r)
        return {"results": results, "workers": 1}

    as_completed = require("distributed", *DASK).as_completed

    with dask_client(address, workers) as client:
        if on_start is not None:
            on_start()
        # pure=False: a rerun of the same file is new work, never a cached key
        futures = client.map(fn, items, pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        results: list[Any] = [None] * len(items)
        for fut in as_completed(futures):
            i = index[fut.key]
            try:
                results[i] = fut.result()
            except Exception as exc:  # noqa: BLE001  (a task error or a lost worker)
                results[i] = failed(items[i], exc)
            on_done(results[i])
        return {"results": results, "workers": n_workers(client)}
