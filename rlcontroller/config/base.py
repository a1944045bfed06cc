"""Bounds, shared types and one-line errors of every configuration part, and YAML input."""

from __future__ import annotations

import difflib
import math
from pathlib import Path
from types import UnionType
from typing import Annotated, Any, Literal, Union, get_args, get_origin

import yaml
from pydantic import (
    AfterValidator,
    BaseModel,
    Field,
    ValidationError,
)

from rlcontroller.bounds import MAX_DURATION, MAX_GROUND_ACCELERATION, MAX_SEED, MAX_TIME_STEP, MIN_TIME_STEP
from rlcontroller.errors import ConfigError  # noqa: F401
from rlcontroller.schema import StrictModel  # noqa: F401

Scale = Annotated[float, Field(ge=1.0e-9, le=1.0e12)]  # a quantity's scale, in its SI unit


NoiseStd = Annotated[float, Field(ge=0.0, le=1.0e6)]


Seed = Annotated[int, Field(ge=0, le=MAX_SEED)]


TimeStep = Annotated[float, Field(ge=MIN_TIME_STEP, le=MAX_TIME_STEP)]


def _ordered_range(value: tuple[float, float]) -> tuple[float, float]:
    if value[0] > value[1]:
        raise ValueError(f"expected [low, high] with low <= high, got {list(value)}")
    return value


def bounded_range(low: float, high: float, low_open: bool = False) -> Any:
    bound = Annotated[float, Field(gt=low) if low_open else Field(ge=low), Field(le=high)]
    return Annotated[tuple[bound, bound], AfterValidator(_ordered_range)]


Range = bounded_range(0.0, 1.0e6)


AccelerationRange = bounded_range(0.0, MAX_GROUND_ACCELERATION)  # m/s^2


DurationRange = bounded_range(0.0, MAX_DURATION, low_open=True)  # s


IntRange = Annotated[
    tuple[Annotated[int, Field(ge=0, le=1000)], Annotated[int, Field(ge=0, le=1000)]],
    AfterValidator(_ordered_range),
]


Quantity = Literal[
    "displacement",  # floor displacement relative to the ground (m), one per floor
    "velocity",  # relative floor velocity (m/s), one per floor
    "drift",  # inter-story drift x_i - x_{i-1} (m), one per story
    "absolute_acceleration",  # absolute floor acceleration (m/s^2), one per floor
    "story_shear",  # story shear V_i = sum_{j>=i} m_j a_j (N), one per story
    "base_shear",  # V_1 (N)
    "force",  # actuator force (N), one per commanded device (actuators, then active masses)
    "stroke",  # an auxiliary mass' displacement relative to its floor (m), one per mass device
]


def first_repeat(values: list[Any]) -> tuple[int, int] | None:
    """The indices (first, second) of the first value listed twice, or None."""
    for index, value in enumerate(values):
        if value in values[:index]:
            return values.index(value), index
    return None


def unique(values: list[int]) -> list[int]:
    if len(set(values)) != len(values):
        raise ValueError(f"each number once, got {values}")
    return values


Factor = Annotated[float, Field(ge=0.05, le=20.0)]


GENERATOR_KINDS = ("noise_impulses", "kanai_tajimi", "near_fault", "site_based", "mixture", "wind")


MAX_NESTING = 50  # levels of YAML nesting; deeper is not a configuration


def location(file: str, prefix: str, key: str = "") -> str:
    """'file: prefix.key' as every configuration message starts."""
    path = ".".join(part for part in (prefix, key) if part)
    return f"{file}: {path}" if path else file


def format_location(location: tuple[Any, ...], prefix: str) -> str:
    text = prefix
    for item in location:
        if isinstance(item, int):
            text += f"[{item}]"
        elif item not in GENERATOR_KINDS:
            text += f".{item}" if text else str(item)
    return text or "(top level)"


def _short(value: Any, limit: int = 60) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def first_error(error: ValidationError, file: str, prefix: str, model: Any = None) -> ConfigError:
    """The first problem of a validation as one line; for an unknown key of `model` (the type that was
    validated), the closest known key or the list of them."""
    detail = error.errors(include_url=False)[0]
    key = format_location(tuple(detail["loc"]), prefix)
    message = detail["msg"].removeprefix("Value error, ")
    if detail["type"] == "extra_forbidden":
        message = "unknown key" + _known_keys_hint(
            str(detail["loc"][-1]), _keys_at(model, tuple(detail["loc"][:-1]))
        )
    elif detail["type"] != "value_error" and not isinstance(detail.get("input"), dict | type(None)):
        message += f" (got {_short(detail['input'])})"
    return ConfigError(f"{file}: {key}: {message}")


def _known_keys_hint(key: str, known: list[str]) -> str:
    if not known:
        return ""
    close = difflib.get_close_matches(key, known, n=1, cutoff=0.6)
    return f"; did you mean {close[0]!r}?" if close else f"; expected one of: {', '.join(known)}"


def _unwrap(annotation: Any) -> Any:
    """The type inside Annotated[...] and Optional[...]."""
    while get_origin(annotation) is Annotated:
        annotation = get_args(annotation)[0]
    members = [member for member in get_args(annotation) if member is not type(None)]
    if get_origin(annotation) in (Union, UnionType) and len(members) == 1:
        return _unwrap(members[0])
    return annotation


def _keys_at(model: Any, location: tuple[Any, ...]) -> list[str]:
    """The keys the mapping at `location` inside `model` takes (empty when that cannot be told)."""
    current = model
    for item in location:
        current = _unwrap(current)
        if get_origin(current) is list and isinstance(item, int):
            current = get_args(current)[0]
        elif get_origin(current) in (Union, UnionType):  # a generator: the location names its kind
            kinds = [
                m
                for m in get_args(current)
                if isinstance(m, type) and "kind" in getattr(m, "model_fields", {})
            ]
            chosen = [m for m in kinds if m.model_fields["kind"].default == item]
            current = chosen[0] if chosen else None
        elif isinstance(current, type) and issubclass(current, BaseModel) and item in current.model_fields:
            current = current.model_fields[item].annotation
        else:
            return []
    current = _unwrap(current)
    return list(current.model_fields) if isinstance(current, type) and issubclass(current, BaseModel) else []


def _depth(value: Any) -> int:
    """Nesting depth of lists and mappings, without recursion."""
    deepest, stack = 0, [(value, 1)]
    while stack:
        item, level = stack.pop()
        if isinstance(item, dict | list):
            deepest = max(deepest, level)
            if level <= MAX_NESTING:
                stack.extend(
                    (child, level + 1) for child in (item.values() if isinstance(item, dict) else item)
                )
    return deepest


SAFE_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml's parser when PyYAML has it: the same
# safe constructors, ten times faster (a shipped model's config holds a 76-story building's matrices)


def read_yaml(path: Path) -> Any:
    """Read a YAML file; an unreadable file, a syntax error, non-text bytes, an empty file or
    absurd nesting becomes a one-line ConfigError."""
    if path.is_dir():
        raise ConfigError(f"{path}: is a folder, expected a YAML file")
    try:
        text = path.read_bytes().decode("utf-8")
    except OSError as error:
        raise ConfigError(f"{path}: cannot read the file ({error.strerror})") from None
    except UnicodeDecodeError as error:
        raise ConfigError(
            f"{path}: not a text (UTF-8) file: byte {error.start} is {text_byte(error)}"
        ) from None
    try:
        value = yaml.load(text, Loader=SAFE_LOADER)
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        where = f"{path}:{mark.line + 1}" if mark is not None else str(path)
        problem = getattr(error, "problem", None) or str(error).splitlines()[0]
        if "nesting depth" in problem:  # libyaml's own limit
            raise ConfigError(f"{path}: nested too deeply to be a configuration") from None
        raise ConfigError(f"{where}: invalid YAML: {problem}") from None
    except RecursionError:
        raise ConfigError(f"{path}: nested too deeply to be a configuration") from None
    if value is None:
        raise ConfigError(f"{path}: the file is empty, expected YAML keys")
    if _depth(value) > MAX_NESTING:
        raise ConfigError(f"{path}: nested more than {MAX_NESTING} levels deep, expected a configuration")
    return value


def text_byte(error: UnicodeDecodeError) -> str:
    return f"0x{error.object[error.start]:02x}"


def display_path(path: Path) -> str:
    """`path` relative to the working folder when it lies inside it (for messages and reports)."""
    path = Path(path)
    absolute = path.resolve() if path.is_absolute() else None
    if absolute is not None and absolute.is_relative_to(Path.cwd()):
        return str(absolute.relative_to(Path.cwd()))
    return str(path)


def inside(folder: Path, name: str) -> bool:
    """Whether `name`, a path relative to `folder` from a file, stays inside it (lexically: not absolute,
    no '..' that climbs out; the files a folder names are its own)."""
    relative = Path(name)
    if relative.is_absolute() or relative.drive:
        return False
    depth = 0
    for part in relative.parts:
        depth += -1 if part == ".." else 0 if part == "." else 1
        if depth < 0:
            return False
    return True


def check_seed(seed: int, where: str = "--seed") -> int:
    """A seed must be a whole number in [0, 2^32 - 1] (what numpy and torch accept)."""
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= MAX_SEED:
        raise ConfigError(f"{where}: expected a whole number in [0, {MAX_SEED}], got {seed!r}")
    return seed


def finite(
    value: float, where: str, *, low: float = 0.0, high: float = math.inf, low_open: bool = True
) -> float:
    """A finite number in (low, high] (or [low, high] with low_open=False), else a ConfigError."""
    ok = math.isfinite(value) and (value > low if low_open else value >= low) and value <= high
    if not ok:
        bracket = "(" if low_open else "["
        raise ConfigError(f"{where}: expected a finite number in {bracket}{low:g}, {high:g}], got {value!r}")
    return value


def read_model(path: str | Path, model: type[StrictModel], expected: str) -> Any:
    """A YAML file validated as `model`; anything else (not a mapping: "expected a mapping with
    `expected`") is a one-line ConfigError naming the file and the key."""
    path = Path(path)
    raw = read_yaml(path)
    if not isinstance(raw, dict):
        raise ConfigError(f"{path}: expected a mapping with {expected}, got {type(raw).__name__}")
    try:
        return model.model_validate(raw)
    except ValidationError as error:
        raise first_error(error, str(path), "", model) from None
