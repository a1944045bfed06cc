"""Atomic file writes: a temporary file in the same folder, then a rename."""

from __future__ import annotations

import os
from pathlib import Path


def atomic_write(path: Path, text: str) -> Path:
    temporary = path.with_name(f".{path.name}.tmp")
    temporary.write_text(text)
    os.replace(temporary, path)
    return path


def atomic_savefig(figure, path: Path, dpi: int = 120) -> Path:
    temporary = path.with_name(f".{path.stem}.tmp{path.suffix}")
    figure.savefig(temporary, dpi=dpi)
    os.replace(temporary, path)
    return path
