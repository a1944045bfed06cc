"""Typed, validated experiment configuration.

An experiment YAML names (or inlines) its parts: building, actuators, sensors, reward,
excitation, simulation and algorithm. A part given as a string is a path to its own YAML file,
relative to the experiment file, so one building can serve many experiments. Every model
rejects unknown keys, wrong types and impossible values; `load_experiment` turns the first
problem into a one-line `ConfigError` naming the file, the key path and what was expected.

All values are SI: kg, N/m, N, m, s, m/s^2. The defaults are the paper's five-story case, so
`Experiment()` is the embedded default experiment. Every number must be finite and inside a
physically sane bound (the `MAX_*` constants below); the message names the bound.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
import yaml
from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    PositiveInt,
    PrivateAttr,
    TypeAdapter,
    ValidationError,
    model_validator,
)


class ConfigError(ValueError):
    """A user mistake in a configuration file; `str()` is the one-line message to print."""


# Sane bounds: beyond them a value is a typo or a unit mistake, not a building.
MAX_FLOORS = 100
MAX_MASS = 1.0e9  # kg per floor
MAX_STIFFNESS = 1.0e12  # N/m per story
MAX_FORCE = 1.0e9  # N
MAX_GROUND_ACCELERATION = 100.0  # m/s^2, about 10 g
MIN_TIME_STEP, MAX_TIME_STEP = 1.0e-4, 1.0  # s
MAX_DURATION = 3600.0  # s, one motion
MAX_HISTORY = 500  # control steps in the observation
MAX_SEED = 2**32 - 1
MAX_TOTAL_STEPS = 10**9
MAX_ENVS = 256
Scale = Annotated[float, Field(ge=1.0e-9, le=1.0e12)]  # a quantity's scale, in its SI unit
NoiseStd = Annotated[float, Field(ge=0.0, le=1.0e6)]
Seed = Annotated[int, Field(ge=0, le=MAX_SEED)]
TimeStep = Annotated[float, Field(ge=MIN_TIME_STEP, le=MAX_TIME_STEP)]


def _ordered_range(value: tuple[float, float]) -> tuple[float, float]:
    if value[0] > value[1]:
        raise ValueError(f"expected [low, high] with low <= high, got {list(value)}")
    return value


def _range(low: float, high: float, low_open: bool = False) -> Any:
    bound = Annotated[float, Field(gt=low) if low_open else Field(ge=low), Field(le=high)]
    return Annotated[tuple[bound, bound], AfterValidator(_ordered_range)]


Range = _range(0.0, 1.0e6)
AccelerationRange = _range(0.0, MAX_GROUND_ACCELERATION)  # m/s^2
DurationRange = _range(0.0, MAX_DURATION, low_open=True)  # s
IntRange = Annotated[
    tuple[Annotated[int, Field(ge=0, le=1000)], Annotated[int, Field(ge=0, le=1000)]], AfterValidator(_ordered_range)
]

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
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


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
    masses: list[Annotated[float, Field(ge=1.0, le=MAX_MASS)]] = Field(
        [25.0e3, 20.0e3, 20.0e3, 18.0e3, 15.0e3], min_length=1, max_length=MAX_FLOORS
    )
    stiffnesses: list[Annotated[float, Field(ge=1.0, le=MAX_STIFFNESS)]] = Field(
        [5.0e6, 4.0e6, 4.0e6, 3.0e6, 3.0e6], min_length=1, max_length=MAX_FLOORS
    )
    damping: DampingConfig = DampingConfig(
        rayleigh=(RayleighPair(mode=1, ratio=0.01), RayleighPair(mode=5, ratio=0.05))
    )
    story_heights: list[Annotated[float, Field(gt=0.0, le=1000.0)]] | None = None

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
            _check_damping_matrix(np.array(self.damping.matrix, dtype=float))
        return self


def _check_damping_matrix(matrix: np.ndarray) -> None:
    """A damping matrix (N*s/m) must be symmetric and positive semi-definite (it dissipates energy)."""
    size = float(np.max(np.abs(matrix))) if matrix.size else 0.0
    if size > MAX_STIFFNESS:
        raise ValueError(f"damping 'matrix' has entries up to {size:g} N*s/m, expected at most {MAX_STIFFNESS:g}")
    if not np.allclose(matrix, matrix.T, rtol=1e-9, atol=1e-12 * max(size, 1.0)):
        raise ValueError("damping 'matrix' must be symmetric")
    lowest = float(np.min(np.linalg.eigvalsh(matrix)))
    if lowest < -1e-9 * max(size, 1.0):
        raise ValueError(f"damping 'matrix' must be positive semi-definite (an eigenvalue is {lowest:g})")


class ActuatorConfig(StrictModel):
    """An actuator on `story` with a force limit (N); inter-story mount pushes floors j and j-1."""

    story: PositiveInt
    force_limit: Annotated[float, Field(gt=0.0, le=MAX_FORCE)] = 1.0e5
    mount: Literal["inter_story", "floor"] = "inter_story"


def _first_repeat(values: list[Any]) -> tuple[int, int] | None:
    """The indices (first, second) of the first value listed twice, or None."""
    for index, value in enumerate(values):
        if value in values[:index]:
            return values.index(value), index
    return None


def _one_per_story(actuators: list[ActuatorConfig]) -> list[ActuatorConfig]:
    stories = [actuator.story for actuator in actuators]
    repeat = _first_repeat(stories)
    if repeat is not None:
        raise ValueError(f"story {stories[repeat[1]]} is listed twice (entries {repeat[0]} and {repeat[1]})")
    return actuators


def _unique(values: list[int]) -> list[int]:
    if len(set(values)) != len(values):
        raise ValueError(f"each number once, got {values}")
    return values


Actuators = Annotated[list[ActuatorConfig], Field(min_length=1), AfterValidator(_one_per_story)]


def _paper_actuators() -> list[ActuatorConfig]:
    return [ActuatorConfig(story=story) for story in (1, 3, 5)]


class MeasurementConfig(StrictModel):
    """One sensor group: a quantity on some floors (all when omitted), its scale and noise.

    The observation holds (value + noise) / scale; `noise_std` is in the quantity's SI unit.
    """

    quantity: Quantity
    floors: Annotated[list[PositiveInt], Field(min_length=1), AfterValidator(_unique)] | None = None
    scale: Scale
    noise_std: NoiseStd = 0.0


class SensorConfig(StrictModel):
    """Observation: the measurements and the ground acceleration over the last `history` control
    steps, plus the last `action_history` actions (newest first; with actuator delays the commands
    not yet applied). With `state_estimate`, a steady-state Kalman estimate of the floor
    displacements and velocities computed from those same noisy readings (and the measured
    ground acceleration) is added, divided by `displacement_scale` (m) and `velocity_scale` (m/s).
    With `ground_model` that estimate also holds the two states of a Kanai-Tajimi ground filter
    (firm soil), i.e. a prediction of the coming ground motion, and a residual policy's prior is
    LQG + ground model.

    `integration_cutoff` (Hz) is the model-free alternative to `state_estimate`: every reading
    (ground included) is integrated to a velocity and a displacement through a high-pass at that
    frequency, as structural health monitoring does (`control.estimation.integration_filter`),
    and those are added instead, divided by `velocity_scale` and `displacement_scale`."""

    history: Annotated[int, Field(ge=1, le=MAX_HISTORY)] = 5
    action_history: Annotated[int, Field(ge=1, le=MAX_HISTORY)] = 1
    measurements: list[MeasurementConfig] = Field(
        default_factory=lambda: [MeasurementConfig(quantity="absolute_acceleration", scale=5.0, noise_std=0.05)],
        min_length=1,
        max_length=50,
    )
    ground_scale: Scale = 5.0
    ground_noise_std: NoiseStd = 0.05
    state_estimate: bool = False
    ground_model: bool = False
    integration_cutoff: Annotated[float, Field(gt=0.0, le=10.0)] | None = None
    displacement_scale: Scale = 0.02
    velocity_scale: Scale = 0.2


class RewardTerm(StrictModel):
    """weight * sum over components of |quantity / scale|^power, subtracted from the reward.

    `force_change` is the change of each actuator force from the previous step (N). LQG is
    designed on the quadratic terms of linear quantities (power 2, not force_change) only.
    """

    quantity: Quantity | Literal["force_change"]
    weight: Annotated[float, Field(ge=0.0, le=1.0e6)]
    scale: Scale
    power: float = Field(2.0, ge=2.0, le=16.0)

    @property
    def quadratic(self) -> bool:
        return self.power == 2.0 and self.quantity != "force_change"

    @property
    def label(self) -> str:
        return f"reward_{self.quantity}" + ("" if self.power == 2.0 else f"_p{self.power:g}")


class RewardConfig(StrictModel):
    """The terms of the reward. With `per_motion`, each episode's terms are divided by the rms of its
    ground acceleration (in m/s^2) to each term's power: a linear building's reward then does not
    depend on the motion's intensity, so weak and strong motions count alike, as in J1-J4 (where the
    plain reward is dominated by the strongest motions and a learner may act on noise in weak ones).
    LQG's design is unchanged (every quadratic term is scaled alike)."""

    terms: list[RewardTerm] = Field(
        default_factory=lambda: [
            RewardTerm(quantity="drift", weight=1.0, scale=0.01),
            RewardTerm(quantity="base_shear", weight=0.5, scale=5.0e5),
            RewardTerm(quantity="force", weight=1.0, scale=1.0e5),
        ],
        min_length=1,
        max_length=50,
    )
    per_motion: bool = False

    @model_validator(mode="after")
    def _something_to_learn(self) -> RewardConfig:
        if all(term.weight == 0.0 for term in self.terms):
            raise ValueError("every weight is zero: the reward would be constant; give one term a positive weight")
        return self


class NoiseImpulsesConfig(StrictModel):
    """The paper's training motions: white noise plus random half-sine impulses (m/s^2, s)."""

    kind: Literal["noise_impulses"] = "noise_impulses"
    dt: TimeStep = 0.02
    duration: DurationRange = (10.0, 20.0)
    noise_std: AccelerationRange = (0.2, 1.5)
    impulses: IntRange = (0, 4)
    impulse_amplitude: AccelerationRange = (1.0, 5.0)
    impulse_duration: DurationRange = (0.05, 0.5)


class KanaiTajimiConfig(StrictModel):
    """Kanai-Tajimi filtered white noise with a rise-plateau-decay envelope, scaled to a PGA."""

    kind: Literal["kanai_tajimi"] = "kanai_tajimi"
    dt: TimeStep = 0.02
    duration: DurationRange = (15.0, 30.0)
    ground_frequency: _range(0.0, 1000.0, low_open=True) = (8.0, 25.0)  # rad/s
    ground_damping: _range(0.0, 10.0, low_open=True) = (0.3, 0.7)
    pga: AccelerationRange = (1.0, 6.0)
    pga_log: bool = False  # draw the PGA log-uniformly in `pga` (suites spanning weak to strong motions)
    rise_time: DurationRange = (1.0, 3.0)
    strong_duration: Range = (4.0, 12.0)
    decay_rate: Range = (0.2, 0.6)

    @model_validator(mode="after")
    def _positive_for_log(self) -> KanaiTajimiConfig:
        if self.pga_log and self.pga[0] <= 0.0:
            raise ValueError("pga_log needs pga low > 0")
        return self


class NearFaultConfig(StrictModel):
    """A near-fault motion: a Kanai-Tajimi background (`background`, its PGA ignored) plus a
    Mavroeidis-Papageorgiou (2003) velocity pulse of period `pulse_period` (s), `pulse_cycles`
    (their gamma, > 1) and a random phase, whose peak acceleration is `pulse_ratio` times the
    background's; the sum is scaled to a random PGA (m/s^2)."""

    kind: Literal["near_fault"] = "near_fault"
    dt: TimeStep = 0.02
    background: KanaiTajimiConfig = KanaiTajimiConfig()
    pulse_period: _range(0.0, 100.0, low_open=True) = (0.5, 4.0)
    pulse_cycles: _range(1.0, 20.0, low_open=True) = (1.5, 3.0)
    pulse_ratio: _range(0.0, 100.0, low_open=True) = (1.0, 3.0)
    pga: AccelerationRange = (1.0, 6.0)
    pga_log: bool = False

    @model_validator(mode="after")
    def _consistent(self) -> NearFaultConfig:
        if self.background.dt != self.dt:
            raise ValueError("background.dt must equal dt")
        if self.pga_log and self.pga[0] <= 0.0:
            raise ValueError("pga_log needs pga low > 0")
        return self


SourceConfig = Annotated[NoiseImpulsesConfig | KanaiTajimiConfig | NearFaultConfig, Field(discriminator="kind")]


class MixtureComponent(StrictModel):
    weight: Annotated[float, Field(gt=0.0, le=1.0e6)]
    generator: SourceConfig


class MixtureConfig(StrictModel):
    """Each motion comes from one component, drawn with probability proportional to its weight."""

    kind: Literal["mixture"] = "mixture"
    components: list[MixtureComponent] = Field(min_length=1, max_length=50)


GeneratorConfig = Annotated[
    NoiseImpulsesConfig | KanaiTajimiConfig | NearFaultConfig | MixtureConfig, Field(discriminator="kind")
]


class ExcitationConfig(StrictModel):
    """Training motions come from `generator`; validation motions are `validation_motions` draws
    of `validation_generator` (default: the same generator) with the fixed `validation_seed`."""

    generator: GeneratorConfig = NoiseImpulsesConfig()
    validation_generator: GeneratorConfig | None = None
    validation_motions: Annotated[int, Field(ge=1, le=1000)] = 8
    validation_seed: Seed = 10_000

    @property
    def validation(self) -> GeneratorConfig:
        """The generator of the validation motions."""
        return self.validation_generator or self.generator

    def sources(self) -> list[NoiseImpulsesConfig | KanaiTajimiConfig | NearFaultConfig]:
        """The generators motions can come from (the components of mixtures), validation included."""
        sources = []
        for generator in (self.generator, self.validation_generator):
            if isinstance(generator, MixtureConfig):
                sources += [component.generator for component in generator.components]
            elif generator is not None:
                sources.append(generator)
        return sources


class SimulationConfig(StrictModel):
    """Control step (s) and the discretisation: exact (ZOH force, FOH ground) or Newmark-beta."""

    control_dt: TimeStep = 0.02
    method: Literal["exact", "newmark"] = "exact"
    newmark_beta: float = Field(0.25, gt=0.0, le=0.5)
    newmark_gamma: float = Field(0.5, ge=0.5, le=1.0)


class PolicyConfig(StrictModel):
    """The MLP; `net_arch` are the hidden layers of actor and critic, `actor_arch` (if given) the
    actor's own ([]: a linear actor, the action mean a linear map of the observation);
    `log_std_init` sets the initial exploration noise of Gaussian policies (log of std); `odd`
    makes the action odd in the observation, a(-o) = -a(o) and a(0) = 0 (PPO and A2C)."""

    net_arch: list[Annotated[int, Field(ge=1, le=4096)]] = Field([128, 128, 128], min_length=1, max_length=16)
    actor_arch: list[Annotated[int, Field(ge=1, le=4096)]] | None = Field(None, max_length=16)
    activation: Literal["relu", "tanh", "elu", "leaky_relu", "gelu"] = "relu"
    log_std_init: Annotated[float, Field(ge=-20.0, le=5.0)] | None = None
    odd: bool = False


class SearchRange(StrictModel):
    """One tuned setting of `rlc tune`: a number in [low, high] (log-uniform with `log: true`, whole
    numbers with `integer: true`), or one of `choices` (any YAML values, lists included)."""

    low: float | None = Field(default=None, ge=-1.0e12, le=1.0e12)
    high: float | None = Field(default=None, ge=-1.0e12, le=1.0e12)
    log: bool = False
    integer: bool = False
    choices: list[Any] | None = Field(default=None, min_length=1, max_length=1000)

    @model_validator(mode="after")
    def _one_kind(self) -> SearchRange:
        if self.choices is not None:
            if self.low is not None or self.high is not None:
                raise ValueError("give either choices or low and high, not both")
            return self
        if self.low is None or self.high is None:
            raise ValueError("expected low and high (or choices)")
        if self.low >= self.high:
            raise ValueError(f"expected low < high, got low {self.low:g}, high {self.high:g}")
        if self.log and self.low <= 0.0:
            raise ValueError("a log range needs low > 0")
        if self.integer and not (self.low.is_integer() and self.high.is_integer()):
            raise ValueError("an integer range needs whole-number bounds")
        return self


class AlgorithmConfig(StrictModel):
    """The learner (a stable-baselines3 one, or `RandomSearch`: random search with common random
    numbers on a linear odd policy, `rlcontroller.learning.random_search`), its keyword arguments
    and the training schedule.

    `kwargs` go to the learner's constructor (learning_rate, batch_size, buffer_size, train_freq,
    gradient_steps, n_steps, ...); `policy` sets the MLP. `n_envs` environments run as one batch
    (`vec_env: batched`, the default: `simulation.batch` stepped as one), or in a dummy (same
    process) or subprocess vector env. `normalize_observations` and `normalize_rewards` add a
    VecNormalize whose statistics are checkpointed. With `residual_lqg` the policy's action is added
    to the action of LQG (+ measured ground, or + ground model with `sensors.ground_model`) computed
    from the observation's state estimate (needs `sensors.state_estimate`): the agent learns a
    correction to LQG. `checkpoint_every` and
    `eval_every` count environment steps; `best_model` is the validation with the highest reward, or
    with `select_by: J1` the lowest mean J1 (every validation motion counts alike, weak or strong,
    where the reward is dominated by the strongest). `search` is `rlc tune`'s search space: dotted paths into
    the experiment (`algorithm.kwargs.learning_rate`, `algorithm.policy.net_arch`,
    `reward.terms.0.weight`, ...) and their ranges; training ignores it.
    """

    name: Literal["SAC", "PPO", "TD3", "DDPG", "A2C", "RandomSearch"] = "SAC"
    total_steps: Annotated[int, Field(ge=1, le=MAX_TOTAL_STEPS)] = 1_500_000
    n_envs: Annotated[int, Field(ge=1, le=MAX_ENVS)] = 1
    vec_env: Literal["batched", "dummy", "subproc"] = "batched"
    policy: PolicyConfig = PolicyConfig()
    kwargs: dict[str, Any] = Field(default_factory=lambda: {"gamma": 0.999})
    normalize_observations: bool = False
    normalize_rewards: bool = False  # scale rewards by a running std of the return (training only)
    residual_lqg: bool = False
    torch_threads: Annotated[int, Field(ge=1, le=256)] = 1
    checkpoint_every: Annotated[int, Field(ge=1, le=MAX_TOTAL_STEPS)] = 50_000
    eval_every: Annotated[int, Field(ge=1, le=MAX_TOTAL_STEPS)] = 25_000
    select_by: Literal["reward", "J1"] = "reward"
    search: dict[str, SearchRange] = Field(default_factory=dict, max_length=100)


Factor = Annotated[float, Field(ge=0.05, le=20.0)]


class DamageConfig(StrictModel):
    """A story that lost stiffness: `stiffness` is the relative change, -0.4 = 40 % less."""

    story: PositiveInt
    stiffness: float = Field(ge=-0.95, le=0.0)


class ActuatorDynamicsConfig(StrictModel):
    """The delivered force follows the command through a pure delay of `delay_steps` control steps,
    then a first-order lag with `time_constant` (s; 0: none)."""

    time_constant: float = Field(0.0, ge=0.0, le=1.0)
    delay_steps: int = Field(0, ge=0, le=50)


class SensorBias(StrictModel):
    floor: PositiveInt
    value: float = Field(ge=-1.0e6, le=1.0e6)  # in the reading's SI unit


class SensorFaultConfig(StrictModel):
    """Noise std times `noise_factor`; a constant `bias` on some floors' readings; `dead_floors`
    whose readings are zero. A floor is the reading's floor (its story for drifts)."""

    noise_factor: float = Field(1.0, ge=0.0, le=1.0e3)
    bias: list[SensorBias] = []
    dead_floors: Annotated[list[PositiveInt], AfterValidator(_unique)] = []


class HysteresisConfig(StrictModel):
    """Yielding stories (Bouc-Wen): story force F = a k d + (1 - a) k d_y z with
    z' = (d'/d_y) [1 - |z|^n (beta sgn(d' z) + gamma)], beta + gamma = 1 (|z| -> 1 at yield).
    `yield_drift` d_y (m, scalar or per story), `post_yield_ratio` a (1: linear), `exponent` n
    (sharper yielding for larger n); `substeps` RK4 steps per ground-sample interval."""

    model: Literal["bouc_wen"] = "bouc_wen"
    yield_drift: Annotated[float, Field(gt=0.0, le=1.0)] | list[Annotated[float, Field(gt=0.0, le=1.0)]]
    post_yield_ratio: float = Field(0.1, ge=0.0, le=1.0)
    exponent: float = Field(2.0, ge=1.0, le=20.0)
    beta: float = Field(0.5, ge=0.0, le=1.0)
    gamma: float = Field(0.5, ge=-1.0, le=1.0)
    substeps: int = Field(4, ge=1, le=100)

    @model_validator(mode="after")
    def _yields_at_one(self) -> HysteresisConfig:
        if abs(self.beta + self.gamma - 1.0) > 1e-9:
            raise ValueError(f"beta + gamma must be 1 (so |z| -> 1 at yield), got {self.beta + self.gamma:g}")
        return self


class PlantConfig(StrictModel):
    """How the simulated building differs from the design model (the experiment's building,
    actuators and sensors, on which every controller is designed). Factors are a scalar or one
    per story; `damping` scales the damping ratios (a damping matrix is scaled as a whole)."""

    stiffness: Factor | list[Factor] = 1.0
    mass: Factor | list[Factor] = 1.0
    damping: Factor = 1.0
    damage: list[DamageConfig] = []
    actuators: ActuatorDynamicsConfig = ActuatorDynamicsConfig()
    sensors: SensorFaultConfig = SensorFaultConfig()
    hysteresis: HysteresisConfig | None = None  # None: linear stories


class SupervisorConfig(StrictModel):
    """The control system's supervisory layer: what stands between every controller's action and
    the actuators (`control.supervisor`). The same for every controller of the experiment."""

    trigger: AccelerationRange | None = None  # m/s^2: [off below, full authority from], on the peak ground reading
    dissipative: bool = False  # pass only forces that take energy out of the building (estimated velocities)


class RandomRange(StrictModel):
    """A value drawn per episode, uniformly in [low, high], or log-uniformly with `log: true`."""

    low: float = Field(ge=0.0, le=1.0e3)
    high: float = Field(ge=0.0, le=1.0e3)
    log: bool = False

    @model_validator(mode="after")
    def _ordered(self) -> RandomRange:
        if self.low > self.high:
            raise ValueError(f"expected low <= high, got low {self.low:g}, high {self.high:g}")
        if self.log and self.low <= 0.0:
            raise ValueError("a log-uniform range needs low > 0")
        return self


class PlantRandomization(StrictModel):
    """Domain randomisation for training: each episode's plant is the experiment's `plant` part (or
    the design model) with these fields drawn anew from the env's seed. Factors are scalars on every
    story; `delay_steps` is a whole number drawn uniformly in [low, high]. Validation draws with the
    validation motions' fixed seeds, so learning curves stay comparable; evaluation never draws."""

    stiffness: RandomRange | None = None
    mass: RandomRange | None = None
    damping: RandomRange | None = None
    time_constant: RandomRange | None = None  # s
    delay_steps: IntRange | None = None
    noise_factor: RandomRange | None = None


PARTS: dict[str, Any] = {
    "building": BuildingConfig,
    "actuators": Actuators,
    "sensors": SensorConfig,
    "reward": RewardConfig,
    "excitation": ExcitationConfig,
    "simulation": SimulationConfig,
    "algorithm": AlgorithmConfig,
    "plant": PlantConfig,
    "plant_randomization": PlantRandomization,
    "supervisor": SupervisorConfig,
}
OPTIONAL_PARTS = ("plant", "plant_randomization", "supervisor")  # may be null: see the fields of Experiment


class Experiment(StrictModel):
    """A whole experiment. `Experiment()` is the paper's five-story case."""

    name: Annotated[str, Field(min_length=1, max_length=100, pattern=r"^[A-Za-z0-9_.+-]+$")] = "paper_sac"
    seed: Seed = 0
    building: BuildingConfig = BuildingConfig()
    actuators: Actuators = Field(default_factory=_paper_actuators)
    sensors: SensorConfig = SensorConfig()
    reward: RewardConfig = RewardConfig()
    excitation: ExcitationConfig = ExcitationConfig()
    simulation: SimulationConfig = SimulationConfig()
    algorithm: AlgorithmConfig = AlgorithmConfig()
    plant: PlantConfig | None = None  # None: the simulated building is the design model
    plant_randomization: PlantRandomization | None = None  # training and validation only
    supervisor: SupervisorConfig | None = None  # None: actions go to the actuators as they are
    _origins: dict[str, tuple[str, str]] = PrivateAttr(default_factory=dict)

    def origin(self, part: str) -> tuple[str, str]:
        """(file, key prefix) of a part, for error messages."""
        return self._origins.get(part, ("<default>", part))

    def to_yaml(self) -> str:
        return yaml.safe_dump(self.model_dump(mode="json"), sort_keys=False)


GENERATOR_KINDS = ("noise_impulses", "kanai_tajimi", "near_fault", "mixture")
MAX_NESTING = 50  # levels of YAML nesting; deeper is not a configuration


def location(file: str, prefix: str, key: str = "") -> str:
    """'file: prefix.key' as every configuration message starts."""
    path = ".".join(part for part in (prefix, key) if part)
    return f"{file}: {path}" if path else file


def _format_location(location: tuple[Any, ...], prefix: str) -> str:
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


def _first_error(error: ValidationError, file: str, prefix: str) -> ConfigError:
    detail = error.errors(include_url=False)[0]
    key = _format_location(tuple(detail["loc"]), prefix)
    message = detail["msg"].removeprefix("Value error, ")
    if detail["type"] == "extra_forbidden":
        message = "unknown key"
    elif detail["type"] != "value_error" and not isinstance(detail.get("input"), dict | type(None)):
        message += f" (got {_short(detail['input'])})"
    return ConfigError(f"{file}: {key}: {message}")


def _depth(value: Any) -> int:
    """Nesting depth of lists and mappings, without recursion."""
    deepest, stack = 0, [(value, 1)]
    while stack:
        item, level = stack.pop()
        if isinstance(item, dict | list):
            deepest = max(deepest, level)
            if level <= MAX_NESTING:
                stack.extend((child, level + 1) for child in (item.values() if isinstance(item, dict) else item))
    return deepest


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
        raise ConfigError(f"{path}: not a text (UTF-8) file: byte {error.start} is {text_byte(error)}") from None
    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        where = f"{path}:{mark.line + 1}" if mark is not None else str(path)
        problem = getattr(error, "problem", None) or str(error).splitlines()[0]
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


def _check_part_type(part: str, value: Any, where: str) -> None:
    expected = list if part == "actuators" else dict
    if not isinstance(value, expected):
        what = "a list of actuators" if expected is list else f"a mapping of {part} keys"
        got = "text" if isinstance(value, str) else type(value).__name__
        raise ConfigError(f"{where}: expected {what}, got {got}")


def load_experiment(path: str | Path) -> Experiment:
    """Load an experiment YAML and the part files it names; raise ConfigError on any problem."""
    path = Path(path)
    raw = read_yaml(path)
    if not isinstance(raw, dict):
        raise ConfigError(f"{path}: expected a mapping of experiment keys, got {type(raw).__name__}")
    origins: dict[str, tuple[str, str]] = {}
    for part in PARTS:
        value = raw.get(part)
        if isinstance(value, str):
            part_path = (path.parent / value).resolve()
            if not part_path.exists():
                raise ConfigError(f"{path}: {part}: file not found: {value} (relative to {path.parent})")
            raw[part] = read_yaml(part_path)
            origins[part] = (display_path(part_path), "")
            _check_part_type(part, raw[part], display_path(part_path))
        else:
            origins[part] = (str(path), part)
            if part in raw and not (part in OPTIONAL_PARTS and value is None):
                _check_part_type(part, value, f"{path}: {part}")
    return build_experiment(raw, origins, str(path))


def build_experiment(
    raw: dict[str, Any], origins: dict[str, tuple[str, str]] | None = None, file: str = "<config>"
) -> Experiment:
    """Validate a raw mapping whose parts are inlined. `origins` maps a part to the file it came
    from and the key prefix to show in messages (empty when the part has a file of its own)."""
    origins = origins or {}
    for part, model in PARTS.items():
        if part in raw and not (part in OPTIONAL_PARTS and raw[part] is None):
            part_file, prefix = origins.get(part, (file, part))
            try:
                TypeAdapter(model).validate_python(raw[part])
            except ValidationError as error:
                raise _first_error(error, part_file, prefix) from None
    try:
        experiment = Experiment.model_validate(raw)
    except ValidationError as error:
        raise _first_error(error, file, "") from None
    experiment._origins.update({part: origins.get(part, (file, part)) for part in PARTS})
    _check_cross_references(experiment)
    return experiment


def _check_cross_references(experiment: Experiment) -> None:
    if experiment.algorithm.residual_lqg and not experiment.sensors.state_estimate:
        raise ConfigError(
            f"{location(*experiment.origin('algorithm'), 'residual_lqg')}: needs sensors.state_estimate: true"
        )
    supervisor = experiment.supervisor
    if supervisor is not None and supervisor.dissipative and not experiment.sensors.state_estimate:
        where = location(*experiment.origin("supervisor"), "dissipative")
        raise ConfigError(f"{where}: needs sensors.state_estimate: true (the velocities it judges by)")
    if experiment.sensors.ground_model and not experiment.sensors.state_estimate:
        raise ConfigError(f"{location(*experiment.origin('sensors'), 'ground_model')}: needs state_estimate: true")
    cutoff = experiment.sensors.integration_cutoff
    if cutoff is not None:
        where = location(*experiment.origin("sensors"), "integration_cutoff")
        if experiment.sensors.state_estimate:
            raise ConfigError(f"{where}: the observation holds either integrated readings or state_estimate, not both")
        nyquist = 0.5 / experiment.simulation.control_dt
        if cutoff >= 0.5 * nyquist:
            raise ConfigError(
                f"{where}: {cutoff:g} Hz, expected below half the Nyquist frequency ({0.5 * nyquist:g} Hz)"
            )
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
    _check_time_steps(experiment)
    if experiment.plant is not None:
        check_plant(experiment.plant, experiment, *experiment.origin("plant"))
    if experiment.plant_randomization is not None:
        _check_randomization(experiment)


def _check_time_steps(experiment: Experiment) -> None:
    """The control step must hold a whole number of generated samples, and every generated motion
    at least one control step: otherwise what is simulated is not what was configured."""
    control_dt = experiment.simulation.control_dt
    file, prefix = experiment.origin("excitation")
    for source in experiment.excitation.sources():
        ratio = control_dt / source.dt
        if abs(ratio - round(ratio)) > 1e-6 * ratio or round(ratio) < 1:
            where = location(*experiment.origin("simulation"), "control_dt")
            raise ConfigError(
                f"{where}: {control_dt:g} s is not a whole multiple of the {source.kind} generator's "
                f"dt = {source.dt:g} s; choose control_dt = r * dt"
            )
        if source.duration[0] < control_dt:
            raise ConfigError(
                f"{location(file, prefix, 'generator.duration')}: {source.duration[0]:g} s is shorter than one "
                f"control step ({control_dt:g} s)"
            )


def check_plant(plant: PlantConfig, experiment: Experiment, file: str, prefix: str) -> None:
    """Per-story lists and floor numbers of a plant part must fit the building."""
    n_floors = len(experiment.building.masses)
    for key in ("stiffness", "mass"):
        value = getattr(plant, key)
        if isinstance(value, list) and len(value) != n_floors:
            raise ConfigError(f"{location(file, prefix, key)}: {len(value)} factors, expected 1 or {n_floors}")
    stories = [(f"damage[{i}].story", d.story) for i, d in enumerate(plant.damage)]
    stories += [(f"sensors.bias[{i}].floor", b.floor) for i, b in enumerate(plant.sensors.bias)]
    stories += [("sensors.dead_floors", floor) for floor in plant.sensors.dead_floors]
    for key, number in stories:
        if number > n_floors:
            raise ConfigError(f"{location(file, prefix, key)}: {number} does not exist, expected 1..{n_floors}")
    if plant.hysteresis is not None:
        drift = plant.hysteresis.yield_drift
        if isinstance(drift, list) and len(drift) != n_floors:
            where = location(file, prefix, "hysteresis.yield_drift")
            raise ConfigError(f"{where}: {len(drift)} values, expected 1 or {n_floors}")
        if plant.actuators.time_constant > 0 or plant.actuators.delay_steps > 0:
            where = location(file, prefix, "hysteresis")
            raise ConfigError(f"{where}: yielding stories with actuator dynamics are not supported yet; use one")
    if plant.actuators.time_constant > 0 and experiment.simulation.method != "exact":
        raise ConfigError(f"{location(file, prefix, 'actuators.time_constant')}: an actuator lag needs method: exact")


class Scenario(StrictModel):
    """A named plant: how the simulated building differs from the design model (none: nominal)."""

    name: Annotated[str, Field(min_length=1, max_length=60)]
    plant: PlantConfig | None = None


def _unique_names(scenarios: list[Scenario]) -> list[Scenario]:
    names = [scenario.name for scenario in scenarios]
    repeat = _first_repeat(names)
    if repeat is not None:
        raise ValueError(f"scenario name {names[repeat[1]]!r} is used twice")
    return scenarios


class ScenarioFile(StrictModel):
    scenarios: Annotated[list[Scenario], Field(min_length=1, max_length=200), AfterValidator(_unique_names)]


def load_scenarios(path: str | Path, experiment: Experiment) -> list[Scenario]:
    """The named scenarios of a YAML file, checked against the experiment's building."""
    path = Path(path)
    raw = read_yaml(path)
    if not isinstance(raw, dict):
        raise ConfigError(f"{path}: expected a mapping with 'scenarios', got {type(raw).__name__}")
    try:
        scenarios = ScenarioFile.model_validate(raw).scenarios
    except ValidationError as error:
        raise _first_error(error, str(path), "") from None
    for index, scenario in enumerate(scenarios):
        if scenario.plant is not None:
            check_plant(scenario.plant, experiment, str(path), f"scenarios[{index}].plant")
    return scenarios


class SafetyCheckConfig(StrictModel):
    """The safety check's standard (`evaluation.safety`): a suite of `motions` generated motions drawn
    with its own `seed`, the drift below which a motion is insignificant (a ratio of the story
    height; `story_height` (m) where the building gives none), and the at-rest test: `rest_runs`
    noise realisations of `rest_duration` (s) without ground motion."""

    motions: Annotated[int, Field(ge=1, le=100_000)] = 320
    seed: Seed = 31_337
    generator: GeneratorConfig
    insignificant_drift_ratio: Annotated[float, Field(gt=0.0, le=0.1)] = 2.0e-4
    story_height: Annotated[float, Field(gt=0.0, le=1000.0)] = 3.0
    rest_duration: Annotated[float, Field(gt=0.0, le=3600.0)] = 60.0
    rest_runs: Annotated[int, Field(ge=1, le=1000)] = 16


def load_safety_check(path: str | Path) -> SafetyCheckConfig:
    """The safety check's standard from a YAML file."""
    path = Path(path)
    raw = read_yaml(path)
    if not isinstance(raw, dict):
        raise ConfigError(f"{path}: expected a mapping with 'generator', got {type(raw).__name__}")
    try:
        return SafetyCheckConfig.model_validate(raw)
    except ValidationError as error:
        raise _first_error(error, str(path), "") from None


RANDOMIZED_FIELDS = {
    "stiffness": "stiffness",
    "mass": "mass",
    "damping": "damping",
    "time_constant": "actuators.time_constant",
    "delay_steps": "actuators.delay_steps",
    "noise_factor": "sensors.noise_factor",
}


def randomized_plant(base: PlantConfig | None, values: dict[str, float]) -> PlantConfig:
    """`base` (or the design model's empty plant part) with the drawn `values` put in."""
    plant = (base or PlantConfig()).model_dump()
    for key, value in values.items():
        *path, leaf = RANDOMIZED_FIELDS[key].split(".")
        target = plant
        for step in path:
            target = target[step]
        target[leaf] = value
    return PlantConfig.model_validate(plant)


def _check_randomization(experiment: Experiment) -> None:
    """Both ends of every range must make a valid plant for this experiment."""
    randomization = experiment.plant_randomization
    file, prefix = experiment.origin("plant_randomization")
    for key in RANDOMIZED_FIELDS:
        bounds = getattr(randomization, key)
        if bounds is None:
            continue
        ends = bounds if isinstance(bounds, tuple) else (bounds.low, bounds.high)
        for end in ends:
            try:
                check_plant(randomized_plant(experiment.plant, {key: end}), experiment, file, prefix)
            except ValidationError as error:
                detail = error.errors(include_url=False)[0]["msg"]
                raise ConfigError(f"{location(file, prefix, key)}: {end:g} gives no valid plant: {detail}") from None


def check_seed(seed: int, where: str = "--seed") -> int:
    """A seed must be a whole number in [0, 2^32 - 1] (what numpy and torch accept)."""
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= MAX_SEED:
        raise ConfigError(f"{where}: expected a whole number in [0, {MAX_SEED}], got {seed!r}")
    return seed


def finite(value: float, where: str, low: float = 0.0, high: float = math.inf, low_open: bool = True) -> float:
    """A finite number in (low, high] (or [low, high] with low_open=False), else a ConfigError."""
    ok = math.isfinite(value) and (value > low if low_open else value >= low) and value <= high
    if not ok:
        bracket = "(" if low_open else "["
        raise ConfigError(f"{where}: expected a finite number in {bracket}{low:g}, {high:g}], got {value!r}")
    return value


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
