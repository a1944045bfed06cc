"""Typed, validated experiment configuration.

An experiment YAML names (or inlines) its parts: building, actuators, sensors, reward,
excitation, simulation and algorithm. A part given as a string is a path to its own YAML file,
relative to the experiment file, so one building can serve many experiments. Every model
rejects unknown keys, wrong types and impossible values; `load_experiment` turns the first
problem into a one-line `ConfigError` naming the file, the key path and what was expected.

All values are SI: kg, N/m, N, m, s, m/s^2. The defaults are the paper's five-story case, so
`Experiment()` is the embedded default experiment.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal

import yaml
from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    NonNegativeFloat,
    PositiveFloat,
    PositiveInt,
    PrivateAttr,
    TypeAdapter,
    ValidationError,
    model_validator,
)


class ConfigError(ValueError):
    """A user mistake in a configuration file; `str()` is the one-line message to print."""


def _ordered_range(value: tuple[float, float]) -> tuple[float, float]:
    if value[0] > value[1]:
        raise ValueError(f"expected [low, high] with low <= high, got {list(value)}")
    return value


Range = Annotated[tuple[NonNegativeFloat, NonNegativeFloat], AfterValidator(_ordered_range)]
IntRange = Annotated[tuple[Annotated[int, Field(ge=0)], Annotated[int, Field(ge=0)]], AfterValidator(_ordered_range)]

Quantity = Literal[
    "displacement",  # floor displacement relative to the ground (m), one per floor
    "velocity",  # relative floor velocity (m/s), one per floor
    "drift",  # inter-story drift x_i - x_{i-1} (m), one per story
    "absolute_acceleration",  # absolute floor acceleration (m/s^2), one per floor
    "story_shear",  # story shear V_i = sum_{j>=i} m_j a_j (N), one per story
    "base_shear",  # V_1 (N)
    "force",  # actuator force (N), one per actuator
]


class StrictModel(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class RayleighPair(StrictModel):
    mode: PositiveInt
    ratio: float = Field(gt=0.0, lt=1.0)


class DampingConfig(StrictModel):
    """Rayleigh damping from two (mode, ratio) pairs, or an explicit damping matrix (N*s/m)."""

    rayleigh: tuple[RayleighPair, RayleighPair] | None = None
    matrix: list[list[float]] | None = None

    @model_validator(mode="after")
    def _one_kind(self) -> DampingConfig:
        if (self.rayleigh is None) == (self.matrix is None):
            raise ValueError("give exactly one of 'rayleigh' (two mode/ratio pairs) or 'matrix'")
        if self.rayleigh is not None and self.rayleigh[0].mode == self.rayleigh[1].mode:
            raise ValueError("the two Rayleigh pairs must name different modes")
        return self


class BuildingConfig(StrictModel):
    """Floor masses (kg) and story stiffnesses (N/m), floor/story 1 first."""

    name: str = "paper five-story"
    masses: list[PositiveFloat] = Field([25.0e3, 20.0e3, 20.0e3, 18.0e3, 15.0e3], min_length=1)
    stiffnesses: list[PositiveFloat] = Field([5.0e6, 4.0e6, 4.0e6, 3.0e6, 3.0e6], min_length=1)
    damping: DampingConfig = DampingConfig(
        rayleigh=(RayleighPair(mode=1, ratio=0.01), RayleighPair(mode=5, ratio=0.05))
    )
    story_heights: list[PositiveFloat] | None = None

    @model_validator(mode="after")
    def _consistent(self) -> BuildingConfig:
        n = len(self.masses)
        if len(self.stiffnesses) != n:
            raise ValueError(f"'stiffnesses' has {len(self.stiffnesses)} values but 'masses' has {n}")
        if self.story_heights is not None and len(self.story_heights) != n:
            raise ValueError(f"'story_heights' has {len(self.story_heights)} values, expected {n}")
        if self.damping.rayleigh is not None:
            for pair in self.damping.rayleigh:
                if pair.mode > n:
                    raise ValueError(f"damping mode {pair.mode} does not exist: the building has {n} modes")
        if self.damping.matrix is not None:
            shape_ok = len(self.damping.matrix) == n and all(len(row) == n for row in self.damping.matrix)
            if not shape_ok:
                raise ValueError(f"damping 'matrix' must be {n} x {n}")
        return self


class ActuatorConfig(StrictModel):
    """An actuator on `story` with a force limit (N); inter-story mount pushes floors j and j-1."""

    story: PositiveInt
    force_limit: PositiveFloat = 1.0e5
    mount: Literal["inter_story", "floor"] = "inter_story"


def _paper_actuators() -> list[ActuatorConfig]:
    return [ActuatorConfig(story=story) for story in (1, 3, 5)]


class MeasurementConfig(StrictModel):
    """One sensor group: a quantity on some floors (all when omitted), its scale and noise.

    The observation holds (value + noise) / scale; `noise_std` is in the quantity's SI unit.
    """

    quantity: Quantity
    floors: list[PositiveInt] | None = None
    scale: PositiveFloat
    noise_std: NonNegativeFloat = 0.0


class SensorConfig(StrictModel):
    """Observation: the measurements and the ground acceleration over the last `history` control
    steps, plus the last action. With `state_estimate`, a steady-state Kalman estimate of the
    floor displacements and velocities computed from those same noisy readings (and the measured
    ground acceleration) is added, divided by `displacement_scale` (m) and `velocity_scale` (m/s).
    With `ground_model` that estimate also holds the two states of a Kanai-Tajimi ground filter
    (firm soil), i.e. a prediction of the coming ground motion, and a residual policy's prior is
    LQG + ground model."""

    history: PositiveInt = 5
    measurements: list[MeasurementConfig] = Field(
        default_factory=lambda: [MeasurementConfig(quantity="absolute_acceleration", scale=5.0, noise_std=0.05)],
        min_length=1,
    )
    ground_scale: PositiveFloat = 5.0
    ground_noise_std: NonNegativeFloat = 0.05
    state_estimate: bool = False
    ground_model: bool = False
    displacement_scale: PositiveFloat = 0.02
    velocity_scale: PositiveFloat = 0.2


class RewardTerm(StrictModel):
    """weight * sum over components of |quantity / scale|^power, subtracted from the reward.

    `force_change` is the change of each actuator force from the previous step (N). LQG is
    designed on the quadratic terms of linear quantities (power 2, not force_change) only.
    """

    quantity: Quantity | Literal["force_change"]
    weight: NonNegativeFloat
    scale: PositiveFloat
    power: float = Field(2.0, ge=2.0, le=16.0)

    @property
    def quadratic(self) -> bool:
        return self.power == 2.0 and self.quantity != "force_change"

    @property
    def label(self) -> str:
        return f"reward_{self.quantity}" + ("" if self.power == 2.0 else f"_p{self.power:g}")


class RewardConfig(StrictModel):
    terms: list[RewardTerm] = Field(
        default_factory=lambda: [
            RewardTerm(quantity="drift", weight=1.0, scale=0.01),
            RewardTerm(quantity="base_shear", weight=0.5, scale=5.0e5),
            RewardTerm(quantity="force", weight=1.0, scale=1.0e5),
        ],
        min_length=1,
    )


class NoiseImpulsesConfig(StrictModel):
    """The paper's training motions: white noise plus random half-sine impulses (m/s^2, s)."""

    kind: Literal["noise_impulses"] = "noise_impulses"
    dt: PositiveFloat = 0.02
    duration: Range = (10.0, 20.0)
    noise_std: Range = (0.2, 1.5)
    impulses: IntRange = (0, 4)
    impulse_amplitude: Range = (1.0, 5.0)
    impulse_duration: Range = (0.05, 0.5)


class KanaiTajimiConfig(StrictModel):
    """Kanai-Tajimi filtered white noise with a rise-plateau-decay envelope, scaled to a PGA."""

    kind: Literal["kanai_tajimi"] = "kanai_tajimi"
    dt: PositiveFloat = 0.02
    duration: Range = (15.0, 30.0)
    ground_frequency: Range = (8.0, 25.0)
    ground_damping: Range = (0.3, 0.7)
    pga: Range = (1.0, 6.0)
    rise_time: Range = (1.0, 3.0)
    strong_duration: Range = (4.0, 12.0)
    decay_rate: Range = (0.2, 0.6)


SourceConfig = Annotated[NoiseImpulsesConfig | KanaiTajimiConfig, Field(discriminator="kind")]


class MixtureComponent(StrictModel):
    weight: PositiveFloat
    generator: SourceConfig


class MixtureConfig(StrictModel):
    """Each motion comes from one component, drawn with probability proportional to its weight."""

    kind: Literal["mixture"] = "mixture"
    components: list[MixtureComponent] = Field(min_length=1)


GeneratorConfig = Annotated[NoiseImpulsesConfig | KanaiTajimiConfig | MixtureConfig, Field(discriminator="kind")]


class ExcitationConfig(StrictModel):
    """Training motions come from `generator`; validation motions are `validation_motions` draws
    of the same generator with the fixed `validation_seed`."""

    generator: GeneratorConfig = NoiseImpulsesConfig()
    validation_motions: PositiveInt = 8
    validation_seed: int = 10_000


class SimulationConfig(StrictModel):
    """Control step (s) and the discretisation: exact (ZOH force, FOH ground) or Newmark-beta."""

    control_dt: PositiveFloat = 0.02
    method: Literal["exact", "newmark"] = "exact"
    newmark_beta: float = Field(0.25, gt=0.0, le=0.5)
    newmark_gamma: float = Field(0.5, ge=0.5, le=1.0)


class PolicyConfig(StrictModel):
    """The MLP; `log_std_init` sets the initial exploration noise of Gaussian policies (log of std)."""

    net_arch: list[PositiveInt] = [128, 128, 128]
    activation: Literal["relu", "tanh", "elu", "leaky_relu", "gelu"] = "relu"
    log_std_init: float | None = None


class AlgorithmConfig(StrictModel):
    """The stable-baselines3 learner, its keyword arguments and the training schedule.

    `kwargs` go to the learner's constructor (learning_rate, batch_size, buffer_size, train_freq,
    gradient_steps, n_steps, ...); `policy` sets the MLP. `n_envs` environments run in a dummy
    (same process) or subprocess vector env. `normalize_observations` adds a VecNormalize whose
    statistics are checkpointed. With `residual_lqg` the policy's action is added to the action of
    LQG (+ measured ground) computed from the observation's state estimate (needs
    `sensors.state_estimate`): the agent learns a correction to LQG. `checkpoint_every` and
    `eval_every` count environment steps.
    """

    name: Literal["SAC", "PPO", "TD3", "DDPG", "A2C"] = "SAC"
    total_steps: PositiveInt = 1_500_000
    n_envs: PositiveInt = 1
    vec_env: Literal["dummy", "subproc"] = "dummy"
    policy: PolicyConfig = PolicyConfig()
    kwargs: dict[str, Any] = Field(default_factory=lambda: {"gamma": 0.999})
    normalize_observations: bool = False
    residual_lqg: bool = False
    torch_threads: PositiveInt = 1
    checkpoint_every: PositiveInt = 50_000
    eval_every: PositiveInt = 25_000


PARTS: dict[str, Any] = {
    "building": BuildingConfig,
    "actuators": list[ActuatorConfig],
    "sensors": SensorConfig,
    "reward": RewardConfig,
    "excitation": ExcitationConfig,
    "simulation": SimulationConfig,
    "algorithm": AlgorithmConfig,
}


class Experiment(StrictModel):
    """A whole experiment. `Experiment()` is the paper's five-story case."""

    name: str = "paper_sac"
    seed: int = 0
    building: BuildingConfig = BuildingConfig()
    actuators: list[ActuatorConfig] = Field(default_factory=_paper_actuators, min_length=1)
    sensors: SensorConfig = SensorConfig()
    reward: RewardConfig = RewardConfig()
    excitation: ExcitationConfig = ExcitationConfig()
    simulation: SimulationConfig = SimulationConfig()
    algorithm: AlgorithmConfig = AlgorithmConfig()
    _origins: dict[str, tuple[str, str]] = PrivateAttr(default_factory=dict)

    def origin(self, part: str) -> tuple[str, str]:
        """(file, key prefix) of a part, for error messages."""
        return self._origins.get(part, ("<default>", part))

    def to_yaml(self) -> str:
        return yaml.safe_dump(self.model_dump(mode="json"), sort_keys=False)


GENERATOR_KINDS = ("noise_impulses", "kanai_tajimi", "mixture")


def _format_location(location: tuple[Any, ...], prefix: str) -> str:
    text = prefix
    for item in location:
        if isinstance(item, int):
            text += f"[{item}]"
        elif item not in GENERATOR_KINDS:
            text += f".{item}" if text else str(item)
    return text or "(top level)"


def _first_error(error: ValidationError, file: str, prefix: str) -> ConfigError:
    detail = error.errors(include_url=False)[0]
    key = _format_location(tuple(detail["loc"]), prefix)
    message = detail["msg"].removeprefix("Value error, ")
    if detail["type"] == "extra_forbidden":
        message = "unknown key"
    elif detail["type"] != "value_error" and not isinstance(detail.get("input"), dict | type(None)):
        message += f" (got {detail['input']!r})"
    return ConfigError(f"{file}: {key}: {message}")


def read_yaml(path: Path) -> Any:
    """Read a YAML file; a missing file or a syntax error becomes a one-line ConfigError."""
    try:
        text = path.read_text()
    except OSError as error:
        raise ConfigError(f"{path}: cannot read the file ({error.strerror})") from None
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        where = f"{path}:{mark.line + 1}" if mark is not None else str(path)
        problem = getattr(error, "problem", None) or str(error).splitlines()[0]
        raise ConfigError(f"{where}: invalid YAML: {problem}") from None


def _display(path: Path) -> str:
    return str(path.relative_to(Path.cwd())) if path.is_relative_to(Path.cwd()) else str(path)


def load_experiment(path: str | Path) -> Experiment:
    """Load an experiment YAML and the part files it names; raise ConfigError on any problem."""
    path = Path(path)
    raw = read_yaml(path)
    raw = {} if raw is None else raw
    if not isinstance(raw, dict):
        raise ConfigError(f"{path}: expected a mapping of experiment keys, got {type(raw).__name__}")
    origins: dict[str, tuple[str, str]] = {}
    for part in PARTS:
        value = raw.get(part)
        if isinstance(value, str):
            part_path = (path.parent / value).resolve()
            if not part_path.is_file():
                raise ConfigError(f"{path}: {part}: file not found: {value} (relative to {path.parent})")
            raw[part] = read_yaml(part_path)
            origins[part] = (_display(part_path), "")
        else:
            origins[part] = (str(path), part)
    return build_experiment(raw, origins, str(path))


def build_experiment(
    raw: dict[str, Any], origins: dict[str, tuple[str, str]] | None = None, file: str = "<config>"
) -> Experiment:
    """Validate a raw mapping whose parts are inlined. `origins` maps a part to the file it came
    from and the key prefix to show in messages (empty when the part has a file of its own)."""
    origins = origins or {}
    for part, model in PARTS.items():
        if part in raw:
            part_file, prefix = origins.get(part, (file, part))
            try:
                TypeAdapter(model).validate_python(raw[part])
            except ValidationError as error:
                raise _first_error(error, part_file, prefix) from None
    try:
        experiment = Experiment.model_validate(raw)
    except ValidationError as error:
        raise _first_error(error, file, "") from None
    experiment._origins.update(origins)
    _check_cross_references(experiment)
    return experiment


def _check_cross_references(experiment: Experiment) -> None:
    if experiment.algorithm.residual_lqg and not experiment.sensors.state_estimate:
        file, prefix = experiment.origin("algorithm")
        raise ConfigError(f"{file}: {prefix + '.' if prefix else ''}residual_lqg: needs sensors.state_estimate: true")
    if experiment.sensors.ground_model and not experiment.sensors.state_estimate:
        file, prefix = experiment.origin("sensors")
        raise ConfigError(f"{file}: {prefix + '.' if prefix else ''}ground_model: needs state_estimate: true")
    n_floors = len(experiment.building.masses)
    file, prefix = experiment.origin("actuators")
    for index, actuator in enumerate(experiment.actuators):
        if actuator.story > n_floors:
            raise ConfigError(
                f"{file}: {prefix}[{index}].story: story {actuator.story} does not exist, expected 1..{n_floors}"
            )
    file, prefix = experiment.origin("sensors")
    for index, measurement in enumerate(experiment.sensors.measurements):
        key = _format_location(("measurements", index, "floors"), prefix)
        count = len(experiment.actuators) if measurement.quantity == "force" else n_floors
        for floor in measurement.floors or []:
            if floor > count:
                what = "actuator" if measurement.quantity == "force" else "floor"
                raise ConfigError(f"{file}: {key}: {what} {floor} does not exist, expected 1..{count}")
