"""A building given as a linear state-space model (`config.state_space`): what the plant steps and the
controllers are designed on, in place of a `structure.Building`'s M, K, C.

The model is kept continuous, z' = A z + B_u u + B_g a_g, so that the control step's exact discretisation
(zero-order hold on the forces, first-order hold on the ground) applies to it as to any building; a discrete
model becomes the continuous one that reproduces it at its samples with its inputs held (`continuous`). Its
responses are the declared rows of y = C z + D u; one that is not declared is NaN (unavailable, never
invented), and the J it feeds is reported as such.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from rlcontroller.config import ActuatorConfig, StateSpaceBuildingConfig
from rlcontroller.physics.structure import actuator_matrix

PER_FLOOR = ("displacement", "velocity", "drift", "absolute_acceleration", "story_shear")


@dataclass(frozen=True)
class StateSpaceBuilding:
    """A building known by its state-space model: `a` (states x states, 1/s), `b_force` (per N of each
    actuator's force), `b_ground` (per m/s^2 of ground acceleration), the declared responses
    `responses[quantity] = (C_q, D_q)` (D_q per N), the actuators' force limits (N) and mounts."""

    a: np.ndarray
    b_force: np.ndarray
    b_ground: np.ndarray
    responses: dict[str, tuple[np.ndarray, np.ndarray]]
    actuator_matrix: np.ndarray  # Gamma over the floors, from the actuators' stories and mounts
    force_limits: np.ndarray
    physical: bool = False  # the state is [floor displacements; floor velocities]
    story_heights: np.ndarray | None = None
    devices: tuple = field(default=())  # a model holds no mass devices or dampers (refused at loading)
    dampers: tuple = field(default=())

    @property
    def n_states(self) -> int:
        return self.a.shape[0]

    @property
    def n_floors(self) -> int:
        return self.responses["drift"][0].shape[0]

    @property
    def n_dofs(self) -> int:
        """The floors, where the state is physical; an abstract state has no degrees of freedom."""
        if not self.physical:
            raise ValueError("a state-space model with an abstract state has no degrees of freedom")
        return self.n_floors

    @property
    def n_actuators(self) -> int:
        return self.b_force.shape[1]

    def poles(self) -> tuple[np.ndarray, np.ndarray]:
        """Natural frequencies (rad/s, ascending) and damping ratios of the oscillating poles."""
        poles = np.linalg.eigvals(self.a)
        poles = poles[poles.imag > 0.0]
        omega = np.abs(poles)
        order = np.argsort(omega)
        return omega[order], -poles.real[order] / omega[order]

    def periods(self) -> np.ndarray:
        """Natural periods (s), longest first."""
        return 2.0 * np.pi / self.poles()[0]

    def modal_damping_ratios(self) -> np.ndarray:
        return self.poles()[1]

    def outputs(self, quantity: str) -> tuple[np.ndarray, np.ndarray]:
        """(C, D) of a response on the state and the actuators' forces; NaN rows where not declared."""
        m = self.n_actuators
        if quantity in self.responses:
            return self.responses[quantity]
        if quantity == "base_shear":
            c, d = self.outputs("story_shear")
            return c[:1], d[:1]
        if quantity == "force":
            return np.zeros((m, self.n_states)), np.eye(m)
        if quantity in ("stroke", "stroke_velocity"):
            return np.zeros((0, self.n_states)), np.zeros((0, m))
        if quantity == "device_velocity":  # across each actuator: Gamma' v
            c, d = self.outputs("velocity")
            return self.actuator_matrix.T @ c, self.actuator_matrix.T @ d
        if quantity in PER_FLOOR:
            return np.full((self.n_floors, self.n_states), np.nan), np.full((self.n_floors, m), np.nan)
        raise ValueError(f"unknown quantity {quantity!r}")


def continuous(a: np.ndarray, b: np.ndarray, sample_time: float) -> tuple[np.ndarray, np.ndarray]:
    """The continuous (A, B) whose zero-order-hold discretisation at `sample_time` is the discrete (a, b):
    the matrix logarithm of [[a, b], [0, I]] over the sample time (the inverse of
    `dynamics.exact_substep`)."""
    n, inputs = b.shape
    augmented = np.block([[a, b], [np.zeros((inputs, n)), np.eye(inputs)]])
    logarithm = scipy.linalg.logm(augmented) / sample_time
    return np.real(logarithm[:n, :n]), np.real(logarithm[:n, n:])


def from_state_space(config: StateSpaceBuildingConfig, actuators: list[ActuatorConfig]) -> StateSpaceBuilding:
    """The building of a validated state-space part, its actuators' columns in the order of `actuators`."""
    a = np.asarray(config.state_matrix, dtype=float)
    b = np.asarray(config.input_matrix, dtype=float)
    c = np.asarray(config.output_matrix, dtype=float)
    d = np.asarray(config.feedthrough_matrix, dtype=float)
    if config.sample_time is not None:
        a, b = continuous(a, b, config.sample_time)
    columns = config.inputs.actuators
    responses = {name: (c[rows], d[rows][:, columns]) for name, rows in config.outputs.declared().items()}
    heights = None if config.story_heights is None else np.asarray(config.story_heights, dtype=float)
    return StateSpaceBuilding(
        a=a,
        b_force=b[:, columns],
        b_ground=b[:, config.inputs.ground],
        responses=responses,
        actuator_matrix=actuator_matrix(config.n_floors, actuators),
        force_limits=np.array([actuator.force_limit for actuator in actuators], dtype=float),
        physical=config.state == "physical",
        story_heights=heights,
    )


def state_space_outputs(n_floors: int) -> dict[str, list[int]]:
    """The `outputs` declaration of `dynamics.state_space_arrays`' rows."""
    return {name: list(range(i * n_floors, (i + 1) * n_floors)) for i, name in enumerate(PER_FLOOR)}
