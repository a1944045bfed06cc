"""Writes that never leave a half-made file or folder: a temporary in the same folder, then a rename."""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from rlcontroller.config import ConfigError


def atomic_write(path: Path, content: str | bytes) -> Path:
    """Write text or bytes to `path` through a temporary beside it."""
    write = (lambda t: t.write_bytes(content)) if isinstance(content, bytes) else (lambda t: t.write_text(content))
    return _replace_with(path, path.with_name(f".{path.name}.{os.getpid()}.tmp"), write)


def atomic_savefig(figure, path: Path, dpi: int = 120) -> Path:
    temporary = path.with_name(f".{path.stem}.{os.getpid()}.tmp{path.suffix}")  # one per writing process
    return _replace_with(path, temporary, lambda temporary: figure.savefig(temporary, dpi=dpi))


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
