"""The building (masses, stiffnesses, damping, story heights), its actuators and its sensors."""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import (
    AfterValidator,
    Field,
    PositiveInt,
    model_validator,
)

from rlcontroller.bounds import MAX_FLOORS, MAX_FORCE, MAX_HISTORY, MAX_MASS, MAX_STIFFNESS
from rlcontroller.config.base import (
    NoiseStd,
    Quantity,
    Scale,
    StrictModel,
    first_repeat,
    unique,
)
from rlcontroller.devices import DeviceConfig

# The lateral system, for the performance levels of FEMA 356 Table C1-3 (`evaluation.standard.DRIFT_LIMITS`).
StructuralSystem = Literal["steel_moment_frame", "concrete_moment_frame", "concrete_wall"]


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
    system: StructuralSystem = "steel_moment_frame"

    @property
    def n_floors(self) -> int:
        return len(self.masses)

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
        raise ValueError(
            f"damping 'matrix' has entries up to {size:g} N*s/m, expected at most {MAX_STIFFNESS:g}"
        )
    if not np.allclose(matrix, matrix.T, rtol=1e-9, atol=1e-12 * max(size, 1.0)):
        raise ValueError("damping 'matrix' must be symmetric")
    lowest = float(np.min(np.linalg.eigvalsh(matrix)))
    if lowest < -1e-9 * max(size, 1.0):
        raise ValueError(f"damping 'matrix' must be positive semi-definite (an eigenvalue is {lowest:g})")


Matrix = list[list[float]]
MASS_UNITS = {"kg": 1.0, "t": 1.0e3}
FORCE_UNITS = {"N": 1.0, "kN": 1.0e3, "MN": 1.0e6}
LENGTH_UNITS = {"m": 1.0, "mm": 1.0e-3, "cm": 1.0e-2}


class MatrixBuildingConfig(StrictModel):
    """A building given by its matrices, one translational degree of freedom per floor (floor 1 first,
    the ground fixed): mass (kg), stiffness (N/m) and damping (N*s/m, or `modal_damping` ratios, one
    per mode from the first, the last repeated for the higher modes), with the story heights (m).
    Written in a building part as `matrices: FILE.npz` (arrays M, K and C or modal_damping) and
    `units: {mass, force, length}`; `rlc info` prints it resolved, in SI (`config.matrices`)."""

    name: str = "building from matrices"
    source: str = ""  # the file the matrices came from
    mass_matrix: Matrix
    stiffness_matrix: Matrix
    damping_matrix: Matrix | None = None
    modal_damping: list[Annotated[float, Field(ge=0.0, lt=1.0)]] | None = None
    story_heights: list[Annotated[float, Field(gt=0.0, le=1000.0)]]
    system: StructuralSystem = "steel_moment_frame"

    @property
    def masses(self) -> list[float]:
        """The floor masses: the diagonal of M (kg)."""
        return [row[i] for i, row in enumerate(self.mass_matrix)]

    @property
    def n_floors(self) -> int:
        return len(self.mass_matrix)

    @model_validator(mode="after")
    def _consistent(self) -> MatrixBuildingConfig:
        check_matrices(self)
        return self


def check_matrices(building) -> None:
    """Square matrices of one size, finite, symmetric; M positive definite, K positive definite with
    the ground fixed, C positive semi-definite; exactly one of a damping matrix and modal ratios."""
    mass = _square(building.mass_matrix, "mass_matrix")
    n = mass.shape[0]
    if n > MAX_FLOORS:
        raise ValueError(f"mass_matrix: {n} degrees of freedom, expected at most {MAX_FLOORS}")
    stiffness = _square(building.stiffness_matrix, "stiffness_matrix", n)
    if (building.damping_matrix is None) == (building.modal_damping is None):
        raise ValueError("give exactly one of damping_matrix (C) and modal_damping")
    matrices = [("mass_matrix", mass, True), ("stiffness_matrix", stiffness, True)]
    if building.damping_matrix is not None:
        matrices.append(("damping_matrix", _square(building.damping_matrix, "damping_matrix", n), False))
    for name, matrix, definite in matrices:
        size = float(np.max(np.abs(matrix))) or 1.0
        if not np.allclose(matrix, matrix.T, rtol=1e-9, atol=1e-12 * size):
            raise ValueError(f"{name} must be symmetric")
        lowest = float(np.min(np.linalg.eigvalsh(0.5 * (matrix + matrix.T))))
        if lowest <= 1e-9 * size if definite else lowest < -1e-9 * size:
            kind = "positive definite" if definite else "positive semi-definite"
            raise ValueError(f"{name} must be {kind} (an eigenvalue is {lowest:g})")
    if len(building.story_heights) != n:
        raise ValueError(f"'story_heights' has {len(building.story_heights)} values, expected {n}")


def _square(rows, name: str, size: int | None = None) -> np.ndarray:
    matrix = np.asarray(rows, dtype=float)
    if matrix.ndim != 2 or matrix.shape[0] != matrix.shape[1] or matrix.shape[0] == 0:
        raise ValueError(f"{name} must be a square matrix, got shape {matrix.shape}")
    if size is not None and matrix.shape[0] != size:
        raise ValueError(
            f"{name} is {matrix.shape[0]} x {matrix.shape[0]}, expected {size} x {size} like mass_matrix"
        )
    if not np.all(np.isfinite(matrix)):
        raise ValueError(f"{name} has a value that is not finite")
    return matrix


class ActuatorConfig(StrictModel):
    """An actuator on `story` with a force limit (N); inter-story mount pushes floors j and j-1."""

    story: PositiveInt
    force_limit: Annotated[float, Field(gt=0.0, le=MAX_FORCE)] = 1.0e5
    mount: Literal["inter_story", "floor"] = "inter_story"


def _one_per_story(actuators: list[ActuatorConfig]) -> list[ActuatorConfig]:
    stories = [actuator.story for actuator in actuators]
    repeat = first_repeat(stories)
    if repeat is not None:
        raise ValueError(f"story {stories[repeat[1]]} is listed twice (entries {repeat[0]} and {repeat[1]})")
    return actuators


# may be empty when there are devices
Actuators = Annotated[list[ActuatorConfig], AfterValidator(_one_per_story)]


Devices = Annotated[list[DeviceConfig], Field(max_length=MAX_FLOORS)]


def paper_actuators() -> list[ActuatorConfig]:
    return [ActuatorConfig(story=story) for story in (1, 3, 5)]


class MeasurementConfig(StrictModel):
    """One sensor group: a quantity on some floors (all when omitted), its scale and noise.

    The observation holds (value + noise) / scale; `noise_std` is in the quantity's SI unit.
    """

    quantity: Quantity
    floors: Annotated[list[PositiveInt], Field(min_length=1), AfterValidator(unique)] | None = None
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
    and those are added instead, divided by `velocity_scale` and `displacement_scale`.

    With `twin` (needs `state_estimate`) the observation also holds the fail-safe twin
    (`control.twin`): the Kalman estimate of the building failed safe on the same motion, scaled as the
    estimate is, and each story's running peak drift under it so far (m, divided by `displacement_scale`):
    what each story would do with the devices failed safe, for a learner to aim below.

    `input_noise` robustifies every Kalman filter designed for the experiment (the observation's and
    LQG's): fictitious process noise at the actuators' inputs, of this standard deviation per step as a
    fraction of each force limit (loop transfer recovery, Doyle and Stein 1979, IEEE TAC 24(4)). The
    filter then trusts the model's response to the forces less, and LQG keeps more of LQR's stability
    margins when the building differs from the design model (a detuned device)."""

    history: Annotated[int, Field(ge=1, le=MAX_HISTORY)] = 5
    action_history: Annotated[int, Field(ge=1, le=MAX_HISTORY)] = 1
    measurements: list[MeasurementConfig] = Field(
        default_factory=lambda: [
            MeasurementConfig(quantity="absolute_acceleration", scale=5.0, noise_std=0.05)
        ],
        min_length=1,
        max_length=50,
    )
    ground_scale: Scale = 5.0
    ground_noise_std: NoiseStd = 0.05
    state_estimate: bool = False
    ground_model: bool = False
    twin: bool = False
    integration_cutoff: Annotated[float, Field(gt=0.0, le=10.0)] | None = None
    input_noise: Annotated[float, Field(ge=0.0, le=10.0)] = 0.0
    displacement_scale: Scale = 0.02
    velocity_scale: Scale = 0.2
