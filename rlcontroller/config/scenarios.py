"""Files the studies read beside an experiment: robustness scenarios and the safety check's standard."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

from pydantic import AfterValidator, Field, ValidationError

from rlcontroller.assets import (
    DAMPER_SCENARIOS,
    DEVICE_SCENARIOS,
    MATRIX_SCENARIOS,
    SAFETY_STANDARD,
    STANDARD_SCENARIOS,
    WIND_STANDARD,
)
from rlcontroller.config.base import (
    ConfigError,
    Seed,
    StrictModel,
    first_error,
    first_repeat,
    read_model,
    read_yaml,
)
from rlcontroller.config.building import MatrixBuildingConfig
from rlcontroller.config.checks import check_plant
from rlcontroller.config.excitation import GeneratorConfig, WindGeneratorConfig
from rlcontroller.config.experiment import Experiment
from rlcontroller.config.plant import PlantConfig


class Scenario(StrictModel):
    """A named plant: how the simulated building differs from the design model (none: nominal)."""

    name: Annotated[str, Field(min_length=1, max_length=60)]
    plant: PlantConfig | None = None


def _unique_names(scenarios: list[Scenario]) -> list[Scenario]:
    names = [scenario.name for scenario in scenarios]
    repeat = first_repeat(names)
    if repeat is not None:
        raise ValueError(f"scenario name {names[repeat[1]]!r} is used twice")
    return scenarios


class ScenarioFile(StrictModel):
    scenarios: Annotated[list[Scenario], Field(min_length=1, max_length=200), AfterValidator(_unique_names)]


def load_scenarios(path: str | Path, experiment: Experiment) -> list[Scenario]:
    """The named scenarios of a YAML file, checked against the experiment's building."""
    scenarios = read_model(path, ScenarioFile, "'scenarios'").scenarios
    for index, scenario in enumerate(scenarios):
        if scenario.plant is not None:
            check_plant(scenario.plant, experiment, str(path), f"scenarios[{index}].plant")
    return scenarios


class SafetyCheckConfig(StrictModel):
    """The safety check's standard (`evaluation.safety`): a suite of `motions` generated motions drawn
    with its own `seed`, the drift below which a motion is insignificant (a ratio of the story
    height; `story_height` (m) where the building gives none), and the at-rest test: `rest_runs`
    noise realisations of `rest_duration` (s) without ground motion. A significant motion fails when its peak
    drift ratio (or mean J1) to the reference exceeds 1 + `tolerance`; k such motions of N significant pass
    while the one-sided `confidence` Clopper-Pearson upper bound on their probability is at most `risk_bound`
    (0: none may fail). The reference is the building with its controller failed safe
    (`evaluation.safety.fail_safe`). The closed loop must be stable on the design model and on each scenario
    named in `stable_on`."""

    motions: Annotated[int, Field(ge=1, le=100_000)] = 320
    seed: Seed = 31_337
    generator: GeneratorConfig
    insignificant_drift_ratio: Annotated[float, Field(gt=0.0, le=0.1)] = 2.0e-4
    story_height: Annotated[float, Field(gt=0.0, le=1000.0)] = 3.0
    rest_duration: Annotated[float, Field(gt=0.0, le=3600.0)] = 60.0
    rest_runs: Annotated[int, Field(ge=1, le=1000)] = 16
    tolerance: Annotated[float, Field(ge=0.0, le=0.05)] = 0.01
    risk_bound: Annotated[float, Field(ge=0.0, le=0.5)] = 0.05
    confidence: Annotated[float, Field(ge=0.5, lt=1.0)] = 0.95
    # standard scenarios (by name) on which the closed loop linearised at rest must be stable too, where the
    # experiment's scenario set has them (semi-active dampers have no actuator dynamics)
    stable_on: Annotated[list[Annotated[str, Field(min_length=1, max_length=60)]], Field(max_length=20)] = []
    also: SafetyCheckConfig | None = None  # in YAML a file beside this one, whose check suite must pass too


def check_generator(standard: SafetyCheckConfig, experiment: Experiment) -> GeneratorConfig:
    """The generator of the check suite: the standard's; for a wind standard and an experiment trained under
    wind, the standard's speeds and durations on the experiment's own site, facade and sampling (reference
    height, roughness, drag coefficient, width, coherence, dt, cutoff: what belongs to the building)."""
    generator, own = standard.generator, experiment.excitation.generator
    if isinstance(generator, WindGeneratorConfig) and isinstance(own, WindGeneratorConfig):
        return own.model_copy(update={"speed": generator.speed, "duration": generator.duration})
    return generator


def load_safety_check(path: str | Path) -> SafetyCheckConfig:
    """The safety check's standard from a YAML file; its `also`, the name of another standard's file beside it
    (one that names no other), is read as that standard."""
    path = Path(path)
    raw = read_yaml(path)
    if not isinstance(raw, dict) or "also" not in raw:
        return read_model(path, SafetyCheckConfig, "'generator'")
    also = raw["also"]
    other = path.parent / also if isinstance(also, str) else None
    if other is None or not other.is_file() or "also" in _mapping(read_yaml(other)):
        raise ConfigError(
            f"{path}: also: expected the file name of a standard beside it that names no other, got {also!r}"
        )
    other = read_model(other, SafetyCheckConfig, "'generator'")
    try:
        return SafetyCheckConfig.model_validate(raw | {"also": other})
    except ValidationError as error:
        raise first_error(error, str(path), "", SafetyCheckConfig) from None


def _mapping(raw: object) -> dict:
    return raw if isinstance(raw, dict) else {}


def standard_scenarios(experiment: Experiment) -> Path:
    """The standard robustness scenarios, or with devices their own (no yielding stories; devices as built
    differing from their design; no actuator dynamics with semi-active dampers), or for a building given by
    matrices theirs (factors on the whole building only)."""
    if experiment.has_dampers:
        return DAMPER_SCENARIOS
    if experiment.devices:
        return DEVICE_SCENARIOS
    return MATRIX_SCENARIOS if isinstance(experiment.building, MatrixBuildingConfig) else STANDARD_SCENARIOS


def safety_standard(experiment: Experiment) -> Path:
    """The safety check's standard for an experiment: generated wind for one controlled against wind,
    generated ground motions otherwise."""
    return WIND_STANDARD if experiment.load_kind == "wind" else SAFETY_STANDARD
