"""Runs fanned out over processes, for plants that hold one model per process (an OpenSees model).

The engine is `local` (forked processes here, as many as cores) or `dask` (the workers of a Dask cluster: a
local one, or an existing scheduler's); a command chooses it for what it runs inside `engine(...)`
(`--engine dask` of `rlc evaluate`, `compare lqg`, `check`). `rlc sweep` connects to Dask the same way
(`dask_client`). Inside `model_messages()` what the model itself prints while it runs (OpenSees' warnings and
FAILURE lines, on its standard output and error) goes to a log instead of the terminal; the command keeps it
in its output folder and says how many lines it holds (local engine: the forked workers, or this process).
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import shutil
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
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
        raise ConfigError(
            "--engine dask needs Dask distributed: pip install 'rlcontroller[distributed]'"
        ) from None
    for name in [*logging.root.manager.loggerDict, "distributed", "distributed.client"]:
        # a lost scheduler is reported by the caller, once, not as log tracebacks
        if name.startswith("distributed"):
            logging.getLogger(name).setLevel(logging.CRITICAL)
    cluster = None
    if address is None:
        cluster = LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
        )
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


class ModelMessages:
    """A log of what a model printed during the runs (`model_messages`): `lines` counts them, `keep(folder)`
    copies a non-empty log into a command's output folder as `opensees.log` and returns its path."""

    def __init__(self, path: Path) -> None:
        self.path = path

    @property
    def lines(self) -> int:
        return len(self.path.read_bytes().splitlines()) if self.path.is_file() else 0

    def keep(self, folder: Path) -> Path | None:
        if not self.lines:
            return None
        shutil.copyfile(self.path, folder / MODEL_LOG)
        return folder / MODEL_LOG


MODEL_LOG = "opensees.log"
_MESSAGES: ContextVar[ModelMessages | None] = ContextVar("the model's messages", default=None)


@contextmanager
def model_messages() -> Iterator[ModelMessages]:
    """Inside: the models' own output during fanned-out runs goes to a log (module docstring)."""
    handle, name = tempfile.mkstemp(prefix="rlc-model-", suffix=".log")
    os.close(handle)
    messages = ModelMessages(Path(name))
    token = _MESSAGES.set(messages)
    try:
        yield messages
    finally:
        _MESSAGES.reset(token)
        messages.path.unlink(missing_ok=True)


@contextmanager
def _printing_to(log: Path | None) -> Iterator[None]:
    """File descriptors 1 and 2 (what C code such as OpenSees prints to) appended to `log` inside."""
    if log is None:
        yield
        return
    sys.stdout.flush()
    sys.stderr.flush()
    saved, target = [os.dup(1), os.dup(2)], os.open(log, os.O_WRONLY | os.O_APPEND | os.O_CREAT)
    os.dup2(target, 1)
    os.dup2(target, 2)
    try:
        yield
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        for stream, kept in zip((1, 2), saved, strict=True):
            os.dup2(kept, stream)
            os.close(kept)
        os.close(target)


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
    messages = _MESSAGES.get()
    log = None if messages is None else messages.path
    if workers <= 1:
        for item in items:
            with _printing_to(log):
                result = function(shared, item)
            yield result
        return
    global _SHARED
    _SHARED = (function, shared)
    context = multiprocessing.get_context("fork")
    pool = ProcessPoolExecutor(
        workers, mp_context=context, initializer=_start_worker, initargs=(os.getpid(), log)
    )
    try:
        yield from pool.map(_call, items)
    finally:
        pool.shutdown(cancel_futures=True)
        _SHARED = ()


def _start_worker(parent: int, log: Path | None) -> None:
    """Worker initializer: what the worker's model prints goes to `log` (if any), and the worker ends once its
    parent is gone (a SIGTERM or kill of rlc would otherwise leave it running its FE model, or waiting for
    work, for good)."""
    if log is not None:
        target = os.open(log, os.O_WRONLY | os.O_APPEND | os.O_CREAT)
        os.dup2(target, 1)
        os.dup2(target, 2)
        os.close(target)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, name="end-with-parent", daemon=True).start()


def _call(item: Any) -> Any:
    function, shared = _SHARED
    return function(shared, item)
