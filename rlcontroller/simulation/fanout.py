"""Runs fanned out over processes, for plants that hold one model per process (an OpenSees model).

The engine is `local` (forked processes here, as many as cores) or `dask` (the workers of a Dask cluster: a
local one, or an existing scheduler's); a command chooses it for what it runs inside `engine(...)`
(`--engine dask` of `rlc evaluate`, `compare lqg`, `check`). `rlc sweep` connects to Dask the same way
(`dask_client`).
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any

from rlcontroller.errors import ConfigError

ENGINES = ("local", "dask")
_ENGINE: ContextVar[tuple[str, str | None]] = ContextVar("fan-out engine", default=("local", None))


@contextmanager
def engine(name: str, address: str | None = None) -> Iterator[None]:
    """Fan runs out on the engine `name` (`local` or `dask`; `address` an existing Dask scheduler) inside."""
    if name not in ENGINES:
        raise ConfigError(f"--engine: expected one of {', '.join(ENGINES)}, got {name!r}")
    if address is not None and name != "dask":
        raise ConfigError("--address: only with --engine dask")
    token = _ENGINE.set((name, address))
    try:
        yield
    finally:
        _ENGINE.reset(token)


@contextmanager
def dask_client(workers: int, address: str | None) -> Iterator[Any]:
    """A client of the Dask scheduler at `address`, or of a local cluster of `workers` processes."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise ConfigError("--engine dask needs Dask distributed: pip install 'rlcontroller[distributed]'") from None
    for name in [*logging.root.manager.loggerDict, "distributed", "distributed.client"]:
        if name.startswith("distributed"):  # a lost scheduler is reported by the caller, once, not as log tracebacks
            logging.getLogger(name).setLevel(logging.CRITICAL)
    cluster = None
    if address is None:
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
    try:
        client = Client(cluster if cluster is not None else address, timeout="30s")
    except OSError as error:
        raise ConfigError(f"--address {address}: cannot reach a Dask scheduler ({error})") from None
    try:
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


_SHARED: tuple = ()  # what forked workers read: set before the pool starts


def fanned_map(function: Callable[[Any, Any], Any], shared: Any, items: list) -> Iterator[Any]:
    """`function(shared, item)` for each item, in order, each in a process of the chosen engine (`shared`
    is sent to each process once)."""
    name, address = _ENGINE.get()
    workers = min(os.cpu_count() or 1, len(items))
    if name == "dask":
        with dask_client(workers, address) as client:
            handle = client.scatter(shared, broadcast=True)
            futures = [client.submit(function, handle, item, pure=False) for item in items]
            for future in futures:
                yield future.result()
        return
    if workers <= 1:
        yield from (function(shared, item) for item in items)
        return
    global _SHARED
    _SHARED = (function, shared)
    context = multiprocessing.get_context("fork")
    pool = ProcessPoolExecutor(workers, mp_context=context, initializer=_end_with_parent, initargs=(os.getpid(),))
    try:
        yield from pool.map(_call, items)
    finally:
        pool.shutdown(cancel_futures=True)
        _SHARED = ()


def _end_with_parent(parent: int) -> None:
    """Worker initializer: the worker ends once its parent is gone (a SIGTERM or kill of rlc would otherwise
    leave it running its FE model, or waiting for work, for good)."""

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, name="end-with-parent", daemon=True).start()


def _call(item: Any) -> Any:
    function, shared = _SHARED
    return function(shared, item)
