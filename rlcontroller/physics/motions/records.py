"""Motion suites to evaluate on: a folder of records, one record file, or the embedded synthetic suite.

A folder holds `.AT2` (PEER NGA, in g) and two-column `.csv` records. With a `manifest.csv` (a
`file` column, optional `event`, `year`, `station`, `component`, `rsn` columns) the manifest
lists the records, in its order, and gives their descriptions; without one every `.AT2` and
`.csv` file of the folder is a record, in name order. Every suite has a label that names where
its motions came from and how many there are; it goes on every table and plot.
"""

from __future__ import annotations

import csv
import os
from dataclasses import replace
from pathlib import Path

from rlcontroller.config import KanaiTajimiConfig, display_path, inside
from rlcontroller.physics.motions.excitation import (
    MOTION_SUFFIXES,
    STANDARD_GRAVITY,
    Load,
    MotionError,
    read_motion,
    scale_to_pga,
)
from rlcontroller.physics.motions.generators import generate_suite

RECORDS_VARIABLE = "RLC_RECORDS"
MANIFEST = "manifest.csv"
SYNTHETIC_LABEL = "SYNTHETIC suite (7 seeded Kanai-Tajimi motions), not the paper's records"
SYNTHETIC_SEED = 2024
DESCRIPTION_COLUMNS = ("event", "year", "station", "component")


def read_manifest(path: Path) -> list[dict[str, str]]:
    """Rows of a record manifest; it must have a `file` column naming each record."""
    try:
        with open(path, newline="", encoding="utf-8") as handle:
            reader = csv.DictReader(handle)
            rows = list(reader)
            columns = reader.fieldnames or []
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise MotionError(f"{path}: cannot read the manifest ({error})") from None
    if "file" not in columns:
        raise MotionError(f"{path}:1: expected a 'file' column naming each record, got columns {columns}")
    for number, row in enumerate(rows, start=2):
        name = (row.get("file") or "").strip()
        if not name:
            raise MotionError(f"{path}:{number}: empty 'file'")
        if not inside(path.parent, name):
            raise MotionError(
                f"{path}:{number}: file {name!r} is outside the records folder; expected a file in it"
            )
    return rows


def _description(row: dict[str, str]) -> str:
    return ", ".join(row[c].strip() for c in DESCRIPTION_COLUMNS if (row.get(c) or "").strip())


def _folder_motions(folder: Path) -> list[Load]:
    manifest = folder / MANIFEST
    if manifest.is_file():
        rows = read_manifest(manifest)
        missing = [row for row in rows if not (folder / row["file"]).is_file()]
        if missing:
            names = ", ".join(row["file"] for row in missing)
            rsns = ", ".join(row["rsn"] for row in missing if row.get("rsn"))
            source = f" (PEER NGA-West2 RSN {rsns}: https://ngawest2.berkeley.edu, see records/README.md)"
            raise MotionError(
                f"{folder}: {len(missing)} of {len(rows)} records of {MANIFEST} missing: {names}; put them "
                f"in that folder{source if rsns else ''}, or point --records (or ${RECORDS_VARIABLE}) at the "
                "right folder"
            )
        return [replace(read_motion(folder / row["file"]), description=_description(row)) for row in rows]
    files = sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in MOTION_SUFFIXES)
    if not files:
        raise MotionError(
            f"{folder}: no records: expected .AT2 or .csv files (and optionally a {MANIFEST}); "
            f"--records (or ${RECORDS_VARIABLE}) names a folder of records or one record file"
        )
    return [read_motion(path) for path in files]


def load_records(path: Path, scale_pga_g: float | None = None) -> tuple[list[Load], str]:
    """The records of a folder (or one record file), as recorded or scaled to a PGA (in g),
    and the suite's label."""
    path = Path(path)
    if path.is_dir():
        motions = _folder_motions(path)
        label = f"{len(motions)} record{'s' if len(motions) != 1 else ''} from {display_path(path)}"
    elif path.is_file():
        motions = [read_motion(path)]
        label = f"record {display_path(path)}"
    else:
        raise MotionError(
            f"{path}: no such file or folder (--records or ${RECORDS_VARIABLE}: a folder or a record)"
        )
    if scale_pga_g is not None:
        motions = [scale_to_pga(motion, scale_pga_g * STANDARD_GRAVITY) for motion in motions]
    return motions, label + (
        f", scaled to PGA {scale_pga_g:g} g" if scale_pga_g is not None else ", as recorded"
    )


def synthetic_suite(count: int = 7, seed: int = SYNTHETIC_SEED) -> list[Load]:
    """The embedded default: seeded Kanai-Tajimi motions, strong enough to matter (PGA 2-6 m/s^2)."""
    config = KanaiTajimiConfig(duration=(25.0, 40.0), pga=(2.0, 6.0), strong_duration=(6.0, 15.0))
    motions = generate_suite(config, count, seed)
    return [replace(motion, name=f"synthetic_KT_{i + 1}") for i, motion in enumerate(motions)]


def choose_motions(records: Path | None, scale_pga_g: float | None = None) -> tuple[list[Load], str]:
    """The records at `records` (or $RLC_RECORDS); without either, the labelled synthetic suite."""
    source = records or (Path(os.environ[RECORDS_VARIABLE]) if os.environ.get(RECORDS_VARIABLE) else None)
    if source is not None:
        return load_records(source, scale_pga_g)
    motions = synthetic_suite()
    if scale_pga_g is not None:
        motions = [scale_to_pga(motion, scale_pga_g * STANDARD_GRAVITY) for motion in motions]
    return motions, SYNTHETIC_LABEL
