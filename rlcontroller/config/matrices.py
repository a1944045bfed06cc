"""Buildings given by matrices: reading a matrix file into a building part
(`config.building.MatrixBuildingConfig` checks the matrices)."""

from __future__ import annotations

import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from rlcontroller.config.base import ConfigError, display_path
from rlcontroller.config.building import FORCE_UNITS, LENGTH_UNITS, MASS_UNITS

ARRAYS = ("M", "K", "C", "modal_damping")


def read_matrix_part(raw: dict[str, Any], folder: Path, where: str) -> dict[str, Any]:
    """A building part that names `matrices: FILE.npz` (relative to `folder`) and its `units`, as the
    inline part in SI (mass_matrix, stiffness_matrix, damping_matrix or modal_damping)."""
    raw = dict(raw)
    name = raw.pop("matrices")
    units = raw.pop("units", None)
    if not isinstance(name, str):
        raise ConfigError(f"{where}.matrices: expected the path of an .npz file, got {type(name).__name__}")
    if not isinstance(units, dict) or set(units) != {"mass", "force", "length"}:
        raise ConfigError(f"{where}.units: expected {{mass, force, length}}, e.g. {{mass: t, force: kN, length: m}}")
    for key, table in (("mass", MASS_UNITS), ("force", FORCE_UNITS), ("length", LENGTH_UNITS)):
        if units[key] not in table:
            raise ConfigError(f"{where}.units.{key}: {units[key]!r}, expected one of {', '.join(table)}")
    path = folder / name
    try:
        with np.load(path, allow_pickle=False) as archive:
            arrays = {key: np.asarray(archive[key], dtype=float) for key in ARRAYS if key in archive.files}
            unknown = sorted(set(archive.files) - set(ARRAYS))
    except (OSError, ValueError, zipfile.BadZipFile) as error:
        raise ConfigError(f"{display_path(path)}: cannot read the matrices ({type(error).__name__})") from None
    if unknown:
        raise ConfigError(f"{display_path(path)}: unknown arrays {unknown}, expected {', '.join(ARRAYS)}")
    for key in ("M", "K"):
        if key not in arrays:
            raise ConfigError(f"{display_path(path)}: no array {key!r}; expected M, K and C or modal_damping")
    mass = MASS_UNITS[units["mass"]]
    force = FORCE_UNITS[units["force"]]
    length = LENGTH_UNITS[units["length"]]
    raw["mass_matrix"] = (arrays["M"] * mass).tolist()  # kg
    raw["stiffness_matrix"] = (arrays["K"] * force / length).tolist()  # N/m
    if "C" in arrays:
        raw["damping_matrix"] = (arrays["C"] * force / length).tolist()  # N*s/m
    if "modal_damping" in arrays:
        raw["modal_damping"] = arrays["modal_damping"].ravel().tolist()
    raw.setdefault("source", display_path(path))
    return raw
