"""A building given as a linear state-space model: a published benchmark model, a model from another program,
or one identified from measurements (`rlc identify`).

    z' = A z + B w,   y = C z + D w     (continuous), or
    z[k+1] = A z[k] + B w[k],  y[k] = C z[k] + D w[k]   (discrete, sample time `sample_time`, inputs held),

in SI units. The inputs w are the actuators' forces (N) and the ground acceleration (m/s^2), named by their
columns of B (`inputs`); the outputs y are the responses named by their rows of C (`outputs`): floor
displacements and velocities relative to the ground (m, m/s), story drifts (m), absolute floor accelerations
(m/s^2), story shears (N), floor 1 first, each as many rows as the building has floors. Drift is required (J1
and the safety check are taken on it); a criterion whose response is not declared is reported as unavailable.
With `state: physical` the state is [floor displacements; floor velocities] (what a Kalman state estimate in
the observation and a dissipative supervisor read); any other realisation is `abstract`. Written in a building
part as `state_space: FILE.npz` (arrays A, B, C, D, and dt for a discrete model) with `inputs` and `outputs`;
`rlc info` prints it resolved.
"""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import Field, NonNegativeInt, model_validator

from rlcontroller.bounds import MAX_FLOORS
from rlcontroller.config.base import StrictModel, first_repeat
from rlcontroller.config.building import BuildingConfig, MatrixBuildingConfig, StructuralSystem

MAX_STATES = 4 * MAX_FLOORS
Matrix = list[list[float]]
Rows = Annotated[list[NonNegativeInt], Field(min_length=1, max_length=MAX_FLOORS)]
DECLARABLE = ("displacement", "velocity", "drift", "absolute_acceleration", "story_shear")


class StateSpaceInputs(StrictModel):
    """Which columns of B (from 0) are the actuators' forces, in the order of the experiment's `actuators`,
    and which one is the ground acceleration."""

    actuators: Annotated[list[NonNegativeInt], Field(max_length=MAX_FLOORS)] = []
    ground: NonNegativeInt


class StateSpaceOutputs(StrictModel):
    """The rows of C and D (from 0) of each response, floor (or story) 1 first."""

    displacement: Rows | None = None
    velocity: Rows | None = None
    drift: Rows
    absolute_acceleration: Rows | None = None
    story_shear: Rows | None = None

    def declared(self) -> dict[str, list[int]]:
        return {name: getattr(self, name) for name in DECLARABLE if getattr(self, name) is not None}


class StateSpaceBuildingConfig(StrictModel):
    """A building as a linear state-space model (module docstring); SI units, `sample_time` in s (None:
    continuous)."""

    name: str = "building from a state-space model"
    source: str = ""  # the file the model came from
    state_matrix: Matrix
    input_matrix: Matrix
    output_matrix: Matrix
    feedthrough_matrix: Matrix
    sample_time: Annotated[float, Field(gt=0.0, le=1.0)] | None = None
    inputs: StateSpaceInputs
    outputs: StateSpaceOutputs
    state: Literal["abstract", "physical"] = "abstract"
    story_heights: list[Annotated[float, Field(gt=0.0, le=1000.0)]] | None = None
    system: StructuralSystem = "steel_moment_frame"

    @property
    def n_floors(self) -> int:
        return len(self.outputs.drift)

    @model_validator(mode="after")
    def _consistent(self) -> StateSpaceBuildingConfig:
        a = _matrix(self.state_matrix, "state_matrix (A)")
        n_states = a.shape[0]
        if a.shape != (n_states, n_states):
            raise ValueError(f"state_matrix (A) must be square, got {a.shape[0]} x {a.shape[1]}")
        if not 1 <= n_states <= MAX_STATES:
            raise ValueError(f"state_matrix (A): {n_states} states, expected 1..{MAX_STATES}")
        b = _matrix(self.input_matrix, "input_matrix (B)")
        c = _matrix(self.output_matrix, "output_matrix (C)")
        d = _matrix(self.feedthrough_matrix, "feedthrough_matrix (D)")
        if b.shape[0] != n_states:
            raise ValueError(f"input_matrix (B) has {b.shape[0]} rows, expected {n_states} like A")
        if c.shape[1] != n_states:
            raise ValueError(f"output_matrix (C) has {c.shape[1]} columns, expected {n_states} like A")
        if d.shape != (c.shape[0], b.shape[1]):
            raise ValueError(
                f"feedthrough_matrix (D) is {d.shape[0]} x {d.shape[1]}, expected {c.shape[0]} x {b.shape[1]}"
            )
        columns = [*self.inputs.actuators, self.inputs.ground]
        _indices(columns, b.shape[1], "inputs", "column of B")
        declared = self.outputs.declared()
        _indices([row for rows in declared.values() for row in rows], c.shape[0], "outputs", "row of C")
        n = self.n_floors
        for name, rows in declared.items():
            if len(rows) != n:
                raise ValueError(
                    f"outputs.{name}: {len(rows)} rows, expected {n} (one per floor, like drift)"
                )
            ground_feedthrough = float(np.max(np.abs(d[rows, self.inputs.ground])))
            if ground_feedthrough != 0.0:
                raise ValueError(
                    f"outputs.{name}: D's ground column is {ground_feedthrough:g}, expected 0 (responses "
                    "relative to the ground and absolute accelerations of a structure do not feel the "
                    "ground directly)"
                )
        if self.state == "physical" and n_states != 2 * n:
            raise ValueError(
                f"state: physical needs 2 x {n} states ([displacements; velocities]), got {n_states}"
            )
        if self.story_heights is not None and len(self.story_heights) != n:
            raise ValueError(f"'story_heights' has {len(self.story_heights)} values, expected {n}")
        _check_stable(a, self.sample_time)
        return self


def _matrix(rows: Matrix, name: str) -> np.ndarray:
    matrix = np.asarray(rows, dtype=float)
    if matrix.ndim != 2 or 0 in matrix.shape:
        raise ValueError(f"{name} must be a matrix, got shape {matrix.shape}")
    if not np.all(np.isfinite(matrix)):
        raise ValueError(f"{name} has a value that is not finite")
    return matrix


def _indices(indices: list[int], count: int, where: str, what: str) -> None:
    for index in indices:
        if index >= count:
            raise ValueError(f"{where}: {index} is not a {what}, expected 0..{count - 1}")
    repeat = first_repeat(indices)
    if repeat is not None:
        raise ValueError(f"{where}: {what} {indices[repeat[1]]} is named twice")


def _check_stable(a: np.ndarray, sample_time: float | None) -> None:
    """The bare building must come to rest: open-loop poles in the left half-plane (continuous) or
    inside the unit circle (discrete), and a discrete model must have a continuous equivalent (no pole on
    the negative real axis) for the control step's exact discretisation."""
    poles = np.linalg.eigvals(a)
    if sample_time is None:
        worst = float(np.max(poles.real))
        if worst >= 0.0:
            raise ValueError(f"state_matrix (A) has an unstable or undamped pole (real part {worst:g} >= 0)")
        return
    worst = float(np.max(np.abs(poles)))
    if worst >= 1.0:
        raise ValueError(f"state_matrix (A) has an unstable discrete pole (|z| = {worst:g} >= 1)")
    if np.any((np.abs(poles.imag) < 1e-12) & (poles.real <= 0.0)):
        raise ValueError(
            "state_matrix (A) has a pole on the negative real axis: no continuous model holds it between "
            "samples"
        )


BuildingPart = BuildingConfig | MatrixBuildingConfig | StateSpaceBuildingConfig
