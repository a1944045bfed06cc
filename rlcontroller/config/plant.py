"""The simulated plant: integration, how it differs from the design model (damage, actuator dynamics,
sensor faults, yielding) and how training randomises it."""

from __future__ import annotations

from typing import Annotated, ClassVar, Literal

import numpy as np
from pydantic import (
    AfterValidator,
    Field,
    PositiveInt,
    model_validator,
)

from rlcontroller.config.base import Factor, IntRange, StrictModel, TimeStep, unique
from rlcontroller.config.building import StructuralSystem
from rlcontroller.config.state_space import BuildingPart


class SimulationConfig(StrictModel):
    """Control step (s) and the discretisation: exact (ZOH force, FOH ground) or Newmark-beta."""

    control_dt: TimeStep = 0.02
    method: Literal["exact", "newmark"] = "exact"
    newmark_beta: float = Field(0.25, gt=0.0, le=0.5)
    newmark_gamma: float = Field(0.5, ge=0.5, le=1.0)


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
    dead_floors: Annotated[list[PositiveInt], AfterValidator(unique)] = []


Drift = Annotated[float, Field(gt=0.0, le=10.0)]  # m
Rotation = Annotated[float, Field(gt=0.0, le=1.0)]  # rad


class HysteresisConfig(StrictModel):
    """Yielding stories (Bouc-Wen, `physics.hysteresis`): story spring force F = a k d + (1 - a) k d_y z with
    z' = (d'/d_y) [1 - |z|^n (beta sgn(d' z) + gamma)], beta + gamma = 1 (|z| -> 1 at yield).
    `yield_drift` d_y (m), `post_yield_ratio` a (1: linear; negative: the story loses strength past yield, as
    gravity's P-Delta makes a frame do), `exponent` n (sharper yielding for larger n), `beta` and `gamma` the
    loop's shape: each a scalar or one value per story. `collapse_drift` (m, per story or one): a story past
    it has collapsed, and the building stays as it lies for the rest of the motion (needed with a negative a,
    whose drift would otherwise run away). `substeps` RK4 steps per ground-sample interval.

    `model: fishbone` (`physics.fishbone`) makes each floor's beams yield instead of each story: an elastic
    column line (`column_stiffness` EI per story, N m^2), the beams' rotational springs (`beam_stiffness` per
    floor, N m/rad) and the base's (`base_stiffness`, N m/rad), the floors' weights on a leaning column; the
    per-story lists then give each floor's beam hinge (its `yield_rotation`, rad, in place of a yield drift),
    and `yield_drift` stays the stories' (m: ductility, collapse)."""

    model: Literal["bouc_wen", "fishbone"] = "bouc_wen"
    yield_drift: Annotated[float, Field(gt=0.0, le=1.0)] | list[Annotated[float, Field(gt=0.0, le=1.0)]]
    post_yield_ratio: (
        Annotated[float, Field(ge=-0.5, le=1.0)] | list[Annotated[float, Field(ge=-0.5, le=1.0)]]
    ) = 0.1
    exponent: Annotated[float, Field(ge=1.0, le=20.0)] | list[Annotated[float, Field(ge=1.0, le=20.0)]] = 2.0
    beta: Annotated[float, Field(ge=0.0, le=1.0)] | list[Annotated[float, Field(ge=0.0, le=1.0)]] = 0.5
    gamma: Annotated[float, Field(ge=-1.0, le=1.0)] | list[Annotated[float, Field(ge=-1.0, le=1.0)]] = 0.5
    collapse_drift: Drift | list[Drift] | None = None
    substeps: int = Field(4, ge=1, le=100)
    yield_rotation: Rotation | list[Rotation] | None = None
    column_stiffness: list[Annotated[float, Field(gt=0.0)]] | None = None
    beam_stiffness: list[Annotated[float, Field(ge=0.0)]] | None = None
    base_stiffness: Annotated[float, Field(gt=0.0)] | None = None

    FISHBONE: ClassVar[tuple[str, ...]] = (
        "yield_rotation",
        "column_stiffness",
        "beam_stiffness",
        "base_stiffness",
    )
    PER_STORY: ClassVar[tuple[str, ...]] = (
        "yield_drift",
        "post_yield_ratio",
        "exponent",
        "beta",
        "gamma",
        "collapse_drift",
        "yield_rotation",
        "column_stiffness",
        "beam_stiffness",
    )

    @model_validator(mode="after")
    def _yields_at_one(self) -> HysteresisConfig:
        lengths = {len(v) for key in self.PER_STORY if isinstance(v := getattr(self, key), list)}
        if len(lengths) > 1:
            raise ValueError(f"the per-story lists must be of one length, got {sorted(lengths)}")
        if np.min(self.post_yield_ratio) < 0.0 and self.collapse_drift is None:
            raise ValueError(
                "a negative post_yield_ratio (a story losing strength) needs a collapse_drift (m)"
            )
        if self.collapse_drift is not None and np.any(
            np.asarray(self.collapse_drift) <= np.asarray(self.yield_drift)
        ):
            raise ValueError("collapse_drift must exceed yield_drift in every story")
        given = [key for key in self.FISHBONE if getattr(self, key) is not None]
        if self.model == "fishbone" and len(given) < len(self.FISHBONE):
            missing = ", ".join(key for key in self.FISHBONE if key not in given)
            raise ValueError(f"model fishbone needs {missing}")
        if self.model == "bouc_wen" and given:
            raise ValueError(
                f"{', '.join(given)}: only for model fishbone (yielding beams), not bouc_wen (stories)"
            )
        total = np.asarray(self.beta, dtype=float) + np.asarray(self.gamma, dtype=float)
        if np.max(np.abs(total - 1.0)) > 1e-9:
            raise ValueError(
                f"beta + gamma must be 1 (so |z| -> 1 at yield), got {np.round(total, 12).tolist()}"
            )
        return self


class DeviceFactors(StrictModel):
    """The devices as built differ from their design: every mass device's frequency times
    `frequency` (the spring times its square: detuning) and its dashpot times `damping`; every
    semi-active damper's force times `force` (an MR damper's capacity, a variable damper's range)."""

    frequency: Factor = 1.0
    damping: Factor = 1.0
    force: Factor = 1.0


class OpenSeesConfig(StrictModel):
    """An OpenSees finite-element model as the plant (`physics.fe.build`, `physics.fe.integrator`): the Python
    file that builds it (code: run only when the user names it; absolute once loaded), the function in it, and
    the longest analysis step (s; Newmark average acceleration, on every ground sample: 2.5 ms keeps the
    five-story model within 0.1 % of the exact integration, 10 ms is 0.5 % off). `train_on`: what `rlc train`
    learns on — the reduced design model (the default: fast) or the FE model itself (slow: one model per
    process). `system`: the frame's lateral system (the safety check's performance levels)."""

    model: str = Field(min_length=1)
    function: str = Field("build_model", pattern=r"^[A-Za-z_][A-Za-z0-9_]*$")
    analysis_dt: float = Field(0.0025, gt=0.0, le=0.1)
    train_on: Literal["reduced", "fe"] = "reduced"
    system: StructuralSystem = "steel_moment_frame"  # its lateral system: the design model (reduced) takes it


class PlantConfig(StrictModel):
    """How the simulated building differs from the design model (the experiment's building,
    actuators and sensors, on which every controller is designed). Factors are a scalar or one
    per story; `damping` scales the damping ratios (a damping matrix is scaled as a whole). `building`: the
    simulated building itself where it is not the design model (a building known only from measurements is
    designed on its identified model, the experiment's `building`, and simulated as what it is); the factors
    then change it."""

    building: BuildingPart | None = None
    stiffness: Factor | list[Factor] = 1.0
    mass: Factor | list[Factor] = 1.0
    damping: Factor = 1.0
    damage: list[DamageConfig] = []
    actuators: ActuatorDynamicsConfig = ActuatorDynamicsConfig()
    sensors: SensorFaultConfig = SensorFaultConfig()
    hysteresis: HysteresisConfig | None = None  # None: linear stories
    devices: DeviceFactors = DeviceFactors()
    opensees: OpenSeesConfig | None = None  # None: rlc's own plant of the design model

    @model_validator(mode="after")
    def _fe_model_alone(self) -> PlantConfig:
        if self.opensees is not None:
            defaults = {
                key: info.get_default(call_default_factory=True)
                for key, info in type(self).model_fields.items()
            }
            changed = [
                key
                for key in defaults
                if key not in ("opensees", "sensors") and getattr(self, key) != defaults[key]
            ]
            if changed:
                raise ValueError(
                    f"opensees: an FE model is the plant as it is: model {', '.join(changed)} in its file "
                    "instead"
                )
        return self


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
    device_frequency: RandomRange | None = None  # every mass device's frequency factor (detuning)
    # a factor on every yielding story's yield drift (plant.hysteresis)
    yield_drift: RandomRange | None = None


RANDOMIZED_FIELDS = {
    "stiffness": "stiffness",
    "mass": "mass",
    "damping": "damping",
    "time_constant": "actuators.time_constant",
    "delay_steps": "actuators.delay_steps",
    "noise_factor": "sensors.noise_factor",
    "device_frequency": "devices.frequency",
    "yield_drift": "hysteresis.yield_drift",  # a factor on the plant's own
}
FACTORS_ON_THE_PLANT = ("yield_drift",)  # drawn as factors on the base plant's values, not the values


def randomized_plant(base: PlantConfig | None, values: dict[str, float]) -> PlantConfig:
    """`base` (or the design model's empty plant part) with the drawn `values` put in (those of
    FACTORS_ON_THE_PLANT multiply the base's)."""
    plant = (base or PlantConfig()).model_dump()
    for key, value in values.items():
        *path, leaf = RANDOMIZED_FIELDS[key].split(".")
        target = plant
        for step in path:
            target = target[step]
        if key in FACTORS_ON_THE_PLANT:
            target[leaf] = (np.asarray(target[leaf], dtype=float) * value).tolist()
            if key == "yield_drift" and target["model"] == "fishbone":  # its beams yield: their rotations too
                target["yield_rotation"] = (
                    np.asarray(target["yield_rotation"], dtype=float) * value
                ).tolist()
        else:
            target[leaf] = value
    return PlantConfig.model_validate(plant)
