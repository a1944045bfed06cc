"""Buildings given by matrices: reading a matrix file (M, K, C) or a state-space model (A, B, C, D) into a
building part (`config.building.MatrixBuildingConfig` and `config.state_space.StateSpaceBuildingConfig` check
them). The files are data: read without unpickling."""

from __future__ import annotations

import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from rlcontroller.config.base import ConfigError, display_path
from rlcontroller.config.building import FORCE_UNITS, LENGTH_UNITS, MASS_UNITS
from rlcontroller.untrusted import npz_headers, read_npz

ARRAYS = ("M", "K", "C", "modal_damping")
STATE_SPACE_ARRAYS = ("A", "B", "C", "D", "dt")


def read_matrix_part(raw: dict[str, Any], folder: Path, where: str) -> dict[str, Any]:
    """A building part that names `matrices: FILE.npz` (relative to `folder`) and its `units`, as the
    inline part in SI (mass_matrix, stiffness_matrix, damping_matrix or modal_damping)."""
    raw = dict(raw)
    name = raw.pop("matrices")
    units = raw.pop("units", None)
    if not isinstance(name, str):
        raise ConfigError(f"{where}.matrices: expected the path of an .npz file, got {type(name).__name__}")
    if not isinstance(units, dict) or set(units) != {"mass", "force", "length"}:
        raise ConfigError(
            f"{where}.units: expected {{mass, force, length}}, e.g. {{mass: t, force: kN, length: m}}"
        )
    for key, table in (("mass", MASS_UNITS), ("force", FORCE_UNITS), ("length", LENGTH_UNITS)):
        if units[key] not in table:
            raise ConfigError(f"{where}.units.{key}: {units[key]!r}, expected one of {', '.join(table)}")
    path = folder / name
    arrays = _read_arrays(path, ARRAYS)
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


def read_state_space_part(raw: dict[str, Any], folder: Path, where: str) -> dict[str, Any]:
    """A building part that names `state_space: FILE.npz` (relative to `folder`; arrays A, B, C, D in SI and
    `dt`, s, for a discrete model) as the inline part (state_matrix, input_matrix, output_matrix,
    feedthrough_matrix, sample_time)."""
    raw = dict(raw)
    name = raw.pop("state_space")
    if not isinstance(name, str):
        raise ConfigError(
            f"{where}.state_space: expected the path of an .npz file, got {type(name).__name__}"
        )
    path = folder / name
    arrays = _read_arrays(path, STATE_SPACE_ARRAYS)
    for key in ("A", "B", "C", "D"):
        if key not in arrays:
            raise ConfigError(
                f"{display_path(path)}: no array {key!r}; expected A, B, C, D (and dt if discrete)"
            )
    for key, field in (
        ("A", "state_matrix"),
        ("B", "input_matrix"),
        ("C", "output_matrix"),
        ("D", "feedthrough_matrix"),
    ):
        raw[field] = np.atleast_2d(arrays[key]).tolist()
    if "dt" in arrays:
        if arrays["dt"].size != 1:
            raise ConfigError(f"{display_path(path)}: dt must be one number (the sample time, s)")
        raw["sample_time"] = float(arrays["dt"].ravel()[0])
    raw.setdefault("source", display_path(path))
    return raw


def _read_arrays(path: Path, names: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The real arrays of an .npz file, each as float, read as controller files are (`untrusted.npz_headers`:
    headers checked and the size bounded before any data); anything else in it is refused in one line."""
    try:
        headers = npz_headers(path)
    except ValueError as error:
        raise ConfigError(f"{display_path(path)}: {error}") from None
    except (OSError, zipfile.BadZipFile) as error:
        raise ConfigError(
            f"{display_path(path)}: cannot read the matrices ({type(error).__name__})"
        ) from None
    unknown = sorted(set(headers) - set(names))
    if unknown:
        raise ConfigError(f"{display_path(path)}: unknown arrays {unknown}, expected {', '.join(names)}")
    for key, (_, dtype) in headers.items():
        if dtype.kind not in "fiu":
            raise ConfigError(f"{display_path(path)}: array {key!r} holds {dtype}, expected real numbers")
    return {key: array.astype(float) for key, array in read_npz(path).items()}
