"""A piece of one command's work on the machine's other core: `in_background(function, *arguments)` forks a
child that runs it while the caller goes on, and `.result()` takes its value back through a pipe (pickled: our
own objects between our own processes, nothing read from a file). Forking shares everything already
built (plant, motions) at no cost. Without fork or a second core, or in a daemonic process (a Dask
worker), the call runs at once, here."""

from __future__ import annotations

import multiprocessing
import os
import sys
import traceback
from collections.abc import Callable
from functools import partial
from typing import Any


class Background:
    """The pending result of `in_background`; `result()` waits for it (once)."""

    def __init__(self, call: Callable[[], Any]) -> None:

        self._value, self._process = None, None
        if (os.cpu_count() or 1) < 2 or not hasattr(os, "fork") or multiprocessing.current_process().daemon:
            # no core to spare, or a daemonic process (a Dask worker) may not have children
            self._value = call()
            return

        sys.stdout.flush()  # the child must not write its copy of unflushed output again
        sys.stderr.flush()
        context = multiprocessing.get_context("fork")
        self._connection, child_end = context.Pipe(duplex=False)
        self._process = context.Process(target=_run, args=(call, child_end), daemon=True)
        self._process.start()
        child_end.close()

    def result(self) -> Any:
        """The call's value; its exception as a RuntimeError with the child's traceback; an error too if
        the child died without one."""
        if self._process is None:
            return self._value
        process, self._process = self._process, None
        try:
            status, value = self._connection.recv()
        except EOFError:
            process.join()
            raise RuntimeError(
                f"a background process ended without its result (exit code {process.exitcode})"
            ) from None
        finally:
            self._connection.close()
        process.join()
        if status == "error":
            raise RuntimeError(f"a background process failed:\n{value}")
        self._value = value
        return value


def in_background(function: Callable[..., Any], *arguments: Any) -> Background:
    """`function(*arguments)` on the other core (or here and now, `Background`)."""
    return Background(partial(function, *arguments))


def _run(call: Callable[[], Any], connection) -> None:
    try:
        outcome = ("ok", call())
    except BaseException:  # noqa: BLE001 - every failure goes back to the parent, which raises it
        outcome = ("error", traceback.format_exc())
    connection.send(outcome)
    connection.close()
