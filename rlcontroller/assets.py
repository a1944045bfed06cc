"""Where the files the commands need are: the experiment configs (`configs/`) and the shipped
controllers (`models/`). Both are installed with the package as `rlcontroller.configs` and
`rlcontroller.models` (pyproject.toml maps the checkout's top-level folders there), so the commands
find them from a wheel as from a checkout (`.ci/run` installs the wheel and runs `rlc demo` with it)."""

from __future__ import annotations

from importlib.util import find_spec
from pathlib import Path


def _folder(name: str) -> Path:
    """The installed `rlcontroller.NAME` folder, or the checkout's top-level NAME folder (an editable
    install, whose import finder does not map data folders)."""
    spec = find_spec(f"rlcontroller.{name}")
    if spec is not None and spec.submodule_search_locations:
        return Path(next(iter(spec.submodule_search_locations)))
    return Path(__file__).resolve().parents[1] / name


CONFIGS = _folder("configs")
MODELS = _folder("models")
DEFAULT_MODEL = MODELS / "five_story_every_story"  # the rule: models/README.md
DEMO_CONFIG = CONFIGS / "experiments" / "demo.yaml"
STANDARD_SCENARIOS = CONFIGS / "scenarios" / "standard.yaml"
DEVICE_SCENARIOS = CONFIGS / "scenarios" / "devices.yaml"  # the standard's for buildings with mass devices
DAMPER_SCENARIOS = CONFIGS / "scenarios" / "dampers.yaml"  # and with semi-active dampers
# for a building given by matrices, without devices
MATRIX_SCENARIOS = CONFIGS / "scenarios" / "matrices.yaml"
SAFETY_STANDARD = CONFIGS / "checks" / "standard.yaml"
WIND_STANDARD = CONFIGS / "checks" / "wind.yaml"  # the check's standard for experiments under wind
