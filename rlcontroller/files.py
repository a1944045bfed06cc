"""Writes that never leave a half-made file or folder (a temporary in the same folder, then a rename),
and the lock that keeps a folder to one writer at a time."""

from __future__ import annotations

import datetime as dt
import json
import os
import shutil
import socket
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from rlcontroller.config import ConfigError


def atomic_write(path: Path, content: str | bytes) -> Path:
    """Write text or bytes to `path` through a temporary beside it."""
    write = (
        (lambda t: t.write_bytes(content))
        if isinstance(content, bytes)
        else (lambda t: t.write_text(content))
    )
    return _replace_with(path, path.with_name(f".{path.name}.{os.getpid()}.tmp"), write)


def atomic_savefig(figure, path: Path, dpi: int = 120) -> Path:
    """`figure` as an image at `path`; PNGs compressed at zlib level 1 (10 % larger, 0.04 s less a plot)."""
    temporary = path.with_name(f".{path.stem}.{os.getpid()}.tmp{path.suffix}")  # one per writing process
    options = {"pil_kwargs": {"compress_level": 1}} if path.suffix == ".png" else {}
    return _replace_with(path, temporary, lambda temporary: figure.savefig(temporary, dpi=dpi, **options))


def _replace_with(path: Path, temporary: Path, write) -> Path:
    """Write `temporary` with `write(temporary)`, then rename it to `path`; remove it if writing fails."""
    try:
        write(temporary)
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
    return path


def check_new_folder(path: Path, what: str = "output", hint: str = "") -> None:
    """`path` must not exist, or be an empty folder: work is never overwritten."""
    if path.exists() and not path.is_dir():
        raise ConfigError(f"{path}: is a file, expected a new {what} folder")
    for parent in path.parents:
        if parent.exists() and not parent.is_dir():
            raise ConfigError(f"{path}: {parent} is a file, so it cannot hold the {what} folder")
    if path.is_dir() and any(path.iterdir()):
        raise ConfigError(f"{path}: {what} folder exists and is not empty; it is never overwritten{hint}")


@contextmanager
def new_folder(path: Path, what: str = "output") -> Iterator[Path]:
    """Fill a new folder as one step: the block writes into a hidden sibling, which becomes `path`
    when the block ends and is removed if it fails (a full disk leaves nothing half-written)."""
    check_new_folder(path, what)
    path.parent.mkdir(parents=True, exist_ok=True)
    staging = path.with_name(f".{path.name}.incomplete")
    shutil.rmtree(staging, ignore_errors=True)
    staging.mkdir()
    try:
        yield staging
        if path.is_dir():
            path.rmdir()
        os.rename(staging, path)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


LOCK = ".lock"  # in a locked folder: the holder's host, pid, command and start time (JSON)
UNREADABLE_LOCK_GRACE_S = 5.0  # a lock file still empty or half-written after this was left by a crash


def process_alive(pid: int) -> bool:
    """Whether a process with this id runs on this host (signal 0 only asks)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # it exists, under another user
        return True
    return True


def _lock_holder(path: Path) -> dict | None:
    """The holder a lock file names, or None when it is unreadable (being written, or left half-written)."""
    try:
        holder = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return holder if isinstance(holder, dict) and {"host", "pid"} <= set(holder) else None


def _stale(path: Path, holder: dict | None) -> bool:
    """A lock whose holder is gone: a dead process on this host, or a file unreadable for a while."""
    if holder is None:
        try:
            return time.time() - path.stat().st_mtime > UNREADABLE_LOCK_GRACE_S
        except FileNotFoundError:
            return True
    return holder["host"] == socket.gethostname() and not process_alive(int(holder["pid"]))


def _describe(holder: dict) -> str:
    return (
        f"{holder.get('what', 'another command')} on {holder['host']} (pid {holder['pid']}, "
        f"since {holder.get('started', '?')})"
    )


def active_holder(folder: Path) -> str | None:
    """Who holds `folder`'s lock, when a live process does (e.g. a run still training); else None."""
    path = folder / LOCK
    holder = _lock_holder(path)
    return None if holder is None or _stale(path, holder) else _describe(holder)


def lock_pid(folder: Path) -> int | None:
    """The process id `folder`'s lock names (its holder, alive or not), or None without a readable lock."""
    holder = _lock_holder(folder / LOCK)
    return None if holder is None else int(holder["pid"])


@contextmanager
def folder_lock(folder: Path, what: str) -> Iterator[None]:
    """Hold `folder`'s lock (`folder`/.lock) for the block: one writer at a time. A lock held by a live
    process, or by one on another host (which cannot be asked), is a one-line `ConfigError` naming it;
    one left by a process that is gone (killed) is taken over. The lock is removed at the end."""
    path = folder / LOCK
    mine = {
        "host": socket.gethostname(),
        "pid": os.getpid(),
        "what": what,
        "started": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
    }
    while True:
        try:
            descriptor = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            holder = _lock_holder(path)
            if not _stale(path, holder):
                who = "a process still writing its lock" if holder is None else _describe(holder)
                raise ConfigError(
                    f"{folder}: in use by {who}; wait for it to end, or if it is gone, delete {path}"
                ) from None
            try:  # take the stale lock over: only one of several takers wins the rename
                os.rename(path, path.with_name(f"{LOCK}.stale.{os.getpid()}"))
                path.with_name(f"{LOCK}.stale.{os.getpid()}").unlink()
            except FileNotFoundError:
                pass
            continue
        with os.fdopen(descriptor, "w") as handle:
            json.dump(mine, handle)
        break
    try:
        yield
    finally:
        if (_lock_holder(path) or {}).get("pid") == mine["pid"]:
            path.unlink(missing_ok=True)
