"""An experiment read from YAML files (its parts inline or in files of their own), checked part by part
and across parts (`checks`), and changed by overrides; every problem one `ConfigError` line naming the
file and the key."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from pydantic import TypeAdapter, ValidationError

from rlcontroller.config.base import (
    ConfigError,
    display_path,
    first_error,
    inside,
    read_yaml,
)
from rlcontroller.config.building import MatrixBuildingConfig
from rlcontroller.config.checks import check_cross_references
from rlcontroller.config.experiment import OPTIONAL_PARTS, PARTS, Experiment
from rlcontroller.config.matrices import read_matrix_part, read_state_space_part
from rlcontroller.config.state_space import StateSpaceBuildingConfig


def _check_part_type(part: str, value: Any, where: str) -> None:
    expected = list if part in ("actuators", "devices") else dict
    if not isinstance(value, expected):
        what = f"a list of {part}" if expected is list else f"a mapping of {part} keys"
        got = "text" if isinstance(value, str) else type(value).__name__
        raise ConfigError(f"{where}: expected {what}, got {got}")


OWN_FILES = "a run or model folder names only its own files"


def _relative(target: Path, folder: Path) -> str:
    """`target` as a path relative to `folder` (with '..' where it leaves it), both resolved."""
    return os.path.relpath(target.resolve(), folder.resolve())


# an FE model file and its function -> its design building part
Reduction = Callable[[Path, str], dict[str, Any]]


def load_experiment(
    path: str | Path, self_contained: bool = False, reduce: Reduction | None = None
) -> Experiment:
    """Load an experiment YAML and the part files it names; raise ConfigError on any problem. With
    `self_contained` (the config.yaml of a run or model folder) every file it names must lie in its
    folder: a folder from someone else never makes us read a file elsewhere. An experiment whose plant is
    an OpenSees model and that gives no building of its own gets `reduce(model, function)` as its design
    model (`physics.fe.build.reduced_building`, passed in from above: `api.load` does)."""
    path = Path(path)
    raw = read_yaml(path)
    if not isinstance(raw, dict):
        raise ConfigError(f"{path}: expected a mapping of experiment keys, got {type(raw).__name__}")
    origins: dict[str, tuple[str, str]] = {}
    for part in PARTS:
        value = raw.get(part)
        if self_contained and isinstance(value, str) and not inside(path.parent, value):
            raise ConfigError(f"{path}: {part}: {value!r} is outside {path.parent}; {OWN_FILES}")
        if isinstance(value, str):
            part_path = (path.parent / value).resolve()
            if not part_path.exists():
                raise ConfigError(
                    f"{path}: {part}: file not found: {value} (relative to {path.parent}); a part's path is "
                    "relative to the experiment file: copy the parts along with it, or give absolute paths"
                )
            raw[part] = read_yaml(part_path)
            origins[part] = (display_path(part_path), "")
            _check_part_type(part, raw[part], display_path(part_path))
            folder, where = part_path.parent, display_path(part_path)
        else:
            origins[part] = (str(path), part)
            if part in raw and not (part in OPTIONAL_PARTS and value is None):
                _check_part_type(part, value, f"{path}: {part}")
            folder, where = path.parent, f"{path}: {part}"
        if part == "building" and isinstance(raw.get(part), dict):
            raw[part] = _read_building_files(
                raw[part], folder, where, path.parent if self_contained else None
            )
        if part == "plant" and isinstance(raw.get(part), dict) and "building" in raw[part]:
            raw[part] = dict(raw[part])
            raw[part]["building"] = _plant_building(
                raw[part]["building"], folder, f"{where}.building", path, self_contained
            )
        if (
            part == "plant"
            and isinstance(raw.get(part), dict)
            and isinstance(raw[part].get("opensees"), dict)
        ):
            if self_contained:
                raise ConfigError(f"{where}.opensees: {UNTRUSTED_MODEL}")
            _resolve_fe_model(raw, folder, where, reduce)
    return build_experiment(raw, origins, str(path))


def _read_building_files(part: dict[str, Any], folder: Path, where: str, own: Path | None) -> dict[str, Any]:
    """A building part with the file it names (`matrices:` or `state_space:`, relative to `folder`) read in;
    with `own` (a run or model folder) that file must lie in it."""
    for key, read in (("matrices", read_matrix_part), ("state_space", read_state_space_part)):
        if key not in part:
            continue
        name = part[key]
        if own is not None and isinstance(name, str) and not inside(own, _relative(folder / name, own)):
            raise ConfigError(f"{where}.{key}: {name!r} is outside {own}; {OWN_FILES}")
        return read(part, folder, where)
    return part


def _plant_building(value: Any, folder: Path, where: str, experiment: Path, self_contained: bool) -> Any:
    """The plant part's own building: inline, or a building file relative to `folder`, its matrix or model
    file read in."""
    if isinstance(value, str):
        if self_contained and not inside(experiment.parent, _relative(folder / value, experiment.parent)):
            raise ConfigError(f"{where}: {value!r} is outside {experiment.parent}; {OWN_FILES}")
        building_path = (folder / value).resolve()
        if not building_path.is_file():
            raise ConfigError(f"{where}: file not found: {value} (relative to {folder})")
        value = read_yaml(building_path)
        if not isinstance(value, dict):
            raise ConfigError(f"{display_path(building_path)}: expected a mapping of building keys")
        folder, where = building_path.parent, display_path(building_path)
    if not isinstance(value, dict):
        return value
    return _read_building_files(value, folder, where, experiment.parent if self_contained else None)


UNTRUSTED_MODEL = (
    "names an OpenSees model file, which is code: a run or model folder never runs one; to run it, name "
    "the experiment yourself (--config EXPERIMENT.yaml)"
)


def _resolve_fe_model(raw: dict[str, Any], folder: Path, where: str, reduce: Reduction | None) -> None:
    """The plant's model file made absolute; an experiment with no building of its own gets the FE
    model's reduced one as its design model (`reduce`: the file runs, the user named this experiment)."""
    fe = raw["plant"]["opensees"] = dict(raw["plant"]["opensees"])
    model = fe.get("model")
    if not isinstance(model, str) or not (folder / model).is_file():
        raise ConfigError(
            f"{where}.opensees.model: expected the path of a Python or Tcl file (relative to {folder}), got "
            f"{model!r}"
        )
    fe["model"] = str((folder / model).resolve())
    if "building" in raw:
        return
    if reduce is None:
        raise ConfigError(
            f"{where}.opensees: no building: its design model is reduced from the model when the experiment "
            "is loaded with a reduction (rlcontroller.api.load, or load_experiment(..., "
            "reduce=reduced_building))"
        )
    raw["building"] = reduce(Path(fe["model"]), fe.get("function", "build_model"))
    if "system" in fe:  # the FE model's lateral system is its design model's
        raw["building"]["system"] = fe["system"]


def build_experiment(
    raw: dict[str, Any], origins: dict[str, tuple[str, str]] | None = None, file: str = "<config>"
) -> Experiment:
    """Validate a raw mapping whose parts are inlined. `origins` maps a part to the file it came
    from and the key prefix to show in messages (empty when the part has a file of its own)."""
    origins = origins or {}
    for part, model in PARTS.items():
        if part in raw and not (part in OPTIONAL_PARTS and raw[part] is None):
            part_file, prefix = origins.get(part, (file, part))
            if part == "building" and isinstance(raw[part], dict) and "mass_matrix" in raw[part]:
                model = MatrixBuildingConfig
            if part == "building" and isinstance(raw[part], dict) and "state_matrix" in raw[part]:
                model = StateSpaceBuildingConfig
            try:
                TypeAdapter(model).validate_python(raw[part])
            except ValidationError as error:
                raise first_error(error, part_file, prefix, model) from None
    try:
        experiment = Experiment.model_validate(raw)
    except ValidationError as error:
        raise first_error(error, file, "", Experiment) from None
    experiment._origins.update({part: origins.get(part, (file, part)) for part in PARTS})
    check_cross_references(experiment)
    return experiment


def with_overrides(experiment: Experiment, values: dict[str, Any], where: str) -> Experiment:
    """The experiment with each dotted path (`algorithm.kwargs.gamma`, `reward.terms.0.weight`) set to
    its value, validated as a whole; errors name `where` (an option or a trial) and the path."""
    raw = experiment.model_dump(mode="json")
    for path, value in values.items():
        keys = path.split(".")
        node: Any = raw
        for depth, key in enumerate(keys):
            last = depth == len(keys) - 1
            free = keys[:depth] == ["algorithm", "kwargs"]  # the learner's own keyword arguments
            if isinstance(node, list):
                if not key.isdigit() or int(key) >= len(node):
                    raise ConfigError(f"{where}: {path}: {key!r} is not an index below {len(node)}")
                key = int(key)
            elif not isinstance(node, dict) or (key not in node and not (free and last)):
                options = ", ".join(sorted(node)) if isinstance(node, dict) else "nothing: it is a value"
                raise ConfigError(f"{where}: {path}: no setting {key!r}; expected one of: {options}")
            if last:
                node[key] = value
            else:
                node = node[key]
    return build_experiment(raw, {part: (where, part) for part in PARTS}, where)
