"""State space of the building and its one-step linear maps.

State z = [x; x'] (m, m/s):  z' = A z + B_u u + B_g a_g,
A = [[0, I], [-M^-1 K, -M^-1 C]],  B_u = [0; M^-1 Gamma],  B_g = [0; -1].

Over one control step of length dt the actuator forces u_k are held constant (zero-order
hold) and the ground acceleration is piecewise linear between its samples (first-order hold).
Both discretisations reduce a step to the same precomputed linear map

    z_{k+1} = phi z_k + force_gain u_k + ground_gain a_g[k r : k r + r + 1],

where r is the number of ground-motion samples per control step (sub-steps; a record sampled
finer than the control step is never decimated). The exact map comes from a matrix
exponential; Newmark-beta uses the held force at both ends of every sub-step.

Outputs at time t_k are computed with the force held over the step that ends at t_k, so an
absolute acceleration sensor never sees a force that has not been applied yet.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
from numpy.lib.stride_tricks import sliding_window_view

from rlcontroller.config import SimulationConfig
from rlcontroller.physics.motions.generators import GroundModel
from rlcontroller.physics.response import QUANTITIES, Response, response
from rlcontroller.physics.state_space import PER_FLOOR, StateSpaceBuilding
from rlcontroller.physics.structure import Building


@dataclass(frozen=True)
class StateSpace:
    """Continuous-time matrices of the building (SI units)."""

    a: np.ndarray
    b_force: np.ndarray
    b_ground: np.ndarray


def state_space(building: Building | StateSpaceBuilding) -> StateSpace:
    if isinstance(building, StateSpaceBuilding):
        return StateSpace(a=building.a, b_force=building.b_force, b_ground=building.b_ground)
    n = building.n_dofs
    inverse = np.linalg.inv(building.mass)
    a = np.block(
        [[np.zeros((n, n)), np.eye(n)], [-inverse @ building.stiffness, -inverse @ building.damping]]
    )
    b_force = np.vstack([np.zeros((n, building.n_actuators)), inverse @ building.actuator_matrix])
    b_ground = np.concatenate([np.zeros(n), -np.ones(n)])
    return StateSpace(a=a, b_force=b_force, b_ground=b_ground)


@dataclass(frozen=True)
class SubstepMap:
    """z1 = phi z0 + force_gain u + ground_start a_g0 + ground_end a_g1 over one sub-step."""

    phi: np.ndarray
    force_gain: np.ndarray
    ground_start: np.ndarray
    ground_end: np.ndarray


def exact_substep(system: StateSpace, dt: float) -> SubstepMap:
    """Exact discretisation: zero-order hold on u, first-order hold on a_g (augmented expm)."""
    n_state = system.a.shape[0]
    n_force = system.b_force.shape[1]
    size = n_state + n_force + 2
    augmented = np.zeros((size, size))
    augmented[:n_state, :n_state] = system.a
    augmented[:n_state, n_state : n_state + n_force] = system.b_force
    augmented[:n_state, n_state + n_force] = system.b_ground
    augmented[n_state + n_force, n_state + n_force + 1] = 1.0  # d a_g / dt = slope
    exponential = scipy.linalg.expm(augmented * dt)
    ground = exponential[:n_state, n_state + n_force]
    slope = exponential[:n_state, n_state + n_force + 1]
    return SubstepMap(
        phi=exponential[:n_state, :n_state],
        force_gain=exponential[:n_state, n_state : n_state + n_force],
        ground_start=ground - slope / dt,
        ground_end=slope / dt,
    )


def newmark_substep(building: Building, dt: float, beta: float = 0.25, gamma: float = 0.5) -> SubstepMap:
    """Newmark-beta as a linear map on [x; x'], the start acceleration taken from equilibrium.

    The load is p = -M 1 a_g + Gamma u with the same held u at both ends of the step.
    """
    n = building.n_dofs
    mass, damping, stiffness = building.mass, building.damping, building.stiffness
    identity, zero = np.eye(n), np.zeros((n, n))
    # Each quantity is a matrix acting on w = [x0, v0, p0, p1].
    x0 = np.hstack([identity, zero, zero, zero])
    v0 = np.hstack([zero, identity, zero, zero])
    p0 = np.hstack([zero, zero, identity, zero])
    p1 = np.hstack([zero, zero, zero, identity])
    a0 = np.linalg.solve(mass, p0 - damping @ v0 - stiffness @ x0)
    effective = mass + gamma * dt * damping + beta * dt**2 * stiffness
    a1 = np.linalg.solve(
        effective,
        p1 - damping @ (v0 + dt * (1 - gamma) * a0) - stiffness @ (x0 + dt * v0 + dt**2 * (0.5 - beta) * a0),
    )
    x1 = x0 + dt * v0 + dt**2 * ((0.5 - beta) * a0 + beta * a1)
    v1 = v0 + dt * ((1 - gamma) * a0 + gamma * a1)
    step = np.vstack([x1, v1])
    load_start, load_end = step[:, 2 * n : 3 * n], step[:, 3 * n :]
    inertia = -mass @ np.ones(n)
    return SubstepMap(
        phi=step[:, : 2 * n],
        force_gain=(load_start + load_end) @ building.actuator_matrix,
        ground_start=load_start @ inertia,
        ground_end=load_end @ inertia,
    )


@dataclass(frozen=True)
class StepMap:
    """One control step: z_{k+1} = phi z_k + force_gain u_k + ground_gain @ a_g[k r : k r + r + 1]."""

    phi: np.ndarray
    force_gain: np.ndarray
    ground_gain: np.ndarray
    control_dt: float

    @property
    def substeps(self) -> int:
        return self.ground_gain.shape[1] - 1

    def ground_terms(self, ground: np.ndarray) -> np.ndarray:
        """Ground contribution of every control step, shape (steps, 2n), for samples at dt/r."""
        r = self.substeps
        windows = sliding_window_view(ground, r + 1)[::r]
        return windows @ self.ground_gain.T


def compose(substep: SubstepMap, substeps: int, control_dt: float) -> StepMap:
    """Chain `substeps` identical sub-steps into one control-step map (the force is held)."""
    n_state = substep.phi.shape[0]
    phi = np.eye(n_state)
    force_gain = np.zeros_like(substep.force_gain)
    ground_gain = np.zeros((n_state, substeps + 1))
    for i in range(substeps):
        force_gain = substep.phi @ force_gain + substep.force_gain
        ground_gain = substep.phi @ ground_gain
        ground_gain[:, i] += substep.ground_start
        ground_gain[:, i + 1] += substep.ground_end
        phi = substep.phi @ phi
    return StepMap(phi=phi, force_gain=force_gain, ground_gain=ground_gain, control_dt=control_dt)


def step_map(building: Building, simulation: SimulationConfig, substeps: int = 1) -> StepMap:
    """The control-step map for the configured method, with `substeps` ground samples per step."""
    dt = simulation.control_dt / substeps
    if simulation.method == "newmark":
        substep = newmark_substep(building, dt, simulation.newmark_beta, simulation.newmark_gamma)
    else:
        substep = exact_substep(state_space(building), dt)
    return compose(substep, substeps, simulation.control_dt)


def ground_model_step(building: Building, control_dt: float, model: GroundModel) -> StepMap:
    """Exact control-step map of the state [z; x_f; x_f'] of the building and a Kanai-Tajimi ground
    filter, driven by the forces and the filter's white noise w (held over the step; `ground_gain`
    holds its two first-order-hold columns)."""
    system = state_space(building)
    size = system.a.shape[0]
    filter_a = np.array([[0.0, 1.0], model.output])
    augmented = StateSpace(
        a=np.block([[system.a, np.outer(system.b_ground, model.output)], [np.zeros((2, size)), filter_a]]),
        b_force=np.vstack([system.b_force, np.zeros((2, building.n_actuators))]),
        b_ground=np.concatenate([np.zeros(size), [0.0, -1.0]]),
    )
    return compose(exact_substep(augmented, control_dt), 1, control_dt)


def wind_model_system(
    building: Building, time_constant: float, ground: GroundModel | None = None
) -> StateSpace:
    """The continuous system of [z; f] (with `ground`, [z; f; x_g; x_g']): the building, a first-order model
    of the fluctuating floor forces f (N), f' = -f / time_constant + w (`physics.motions.wind.load_model`),
    and the ground filter shaking its base, driven by the actuator forces (the noises enter through
    `discrete_noise`)."""
    system = state_space(building)
    size, floors = system.a.shape[0], building.n_floors
    inputs = np.vstack([np.zeros((building.n_dofs, floors)), np.linalg.inv(building.mass)[:, :floors]])
    a = np.block([[system.a, inputs], [np.zeros((floors, size)), -np.eye(floors) / time_constant]])
    if ground is not None:
        shaking = np.zeros((size + floors, 2))
        shaking[:size] = np.outer(system.b_ground, ground.output)
        a = np.block([[a, shaking], [np.zeros((2, size + floors)), np.array([[0.0, 1.0], ground.output])]])
    extra = a.shape[0] - size
    b_force = np.vstack([system.b_force, np.zeros((extra, building.n_actuators))])
    return StateSpace(a=a, b_force=b_force, b_ground=np.zeros(size + extra))


def discrete_noise(a: np.ndarray, intensity: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """The covariance gained over one step (phi = e^(a dt)) by a stable x' = a x + w, w white of
    spectral intensity `intensity`: P - phi P phi', P the stationary covariance (a P + P a' +
    intensity = 0). Exact, and unlike Van Loan's exponential it stays finite for stiff buildings."""
    stationary = scipy.linalg.solve_continuous_lyapunov(a, -intensity)
    covariance = stationary - phi @ stationary @ phi.T
    return 0.5 * (covariance + covariance.T)


@dataclass(frozen=True)
class LoadMap:
    """Floor forces F (N), linear between their samples, over one control step of r sub-steps:
    z_{k+1} gains sum_j gain[:, j, :] @ F[k r + j], j = 0..r (exact discretisation)."""

    gain: np.ndarray  # (2 n_dofs, r + 1, floors)

    def terms(self, forces: np.ndarray) -> np.ndarray:
        """The floor forces' contribution to every control step, (steps, 2 n_dofs), for samples (..,
        floors)."""
        r = self.gain.shape[1] - 1
        windows = sliding_window_view(forces, r + 1, axis=0)[::r]  # (steps, floors, r + 1)
        return np.einsum("sfj,ijf->si", windows, self.gain)


def load_map(building: Building, control_dt: float, substeps: int = 1) -> LoadMap:
    """The exact `LoadMap` of forces on the floors (not on mass devices), r = `substeps`."""
    system = state_space(building)
    n, floors = building.n_dofs, building.n_floors
    size = 2 * n
    dt = control_dt / substeps
    inputs = np.vstack([np.zeros((n, floors)), np.linalg.inv(building.mass)[:, :floors]])
    augmented = np.zeros((size + 2 * floors, size + 2 * floors))
    augmented[:size, :size] = system.a
    augmented[:size, size : size + floors] = inputs
    augmented[size : size + floors, size + floors :] = np.eye(floors)  # dF/dt = slope
    exponential = scipy.linalg.expm(augmented * dt)
    phi = exponential[:size, :size]
    value, slope = exponential[:size, size : size + floors], exponential[:size, size + floors :]
    start, end = value - slope / dt, slope / dt
    gain = np.zeros((size, substeps + 1, floors))
    for i in range(substeps):  # chain the sub-steps: earlier contributions pass through phi
        gain = np.einsum("ab,bjf->ajf", phi, gain)
        gain[:, i] += start
        gain[:, i + 1] += end
    return LoadMap(gain=gain)


def load_feedthrough(building: Building, quantity: str) -> np.ndarray:
    """How floor forces (N) enter a quantity directly, (rows, floors): absolute accelerations only
    (a = M^-1 (... + F)); story shears are the restoring forces and do not feel them. A state-space
    model takes no floor forces (`Plant.cannot_take`)."""
    c, _ = output_matrices(building, quantity)
    floors = building.n_floors
    if quantity != "absolute_acceleration" or isinstance(building, StateSpaceBuilding):
        return np.zeros((c.shape[0], floors))
    return np.linalg.inv(building.mass)[:floors, :floors]


def output_matrices(building: Building, quantity: str) -> tuple[np.ndarray, np.ndarray]:
    """(C_q, D_q) with quantity = C_q z + D_q u, for z = [x; x'] over the degrees of freedom and the
    commanded forces u: a `Quantity`, or `stroke_velocity` (per mass device) and `device_velocity`
    (the velocity across each commanded device, Gamma' x', whose product with u is its power). A
    state-space model's are its declared rows (`StateSpaceBuilding.outputs`)."""
    if isinstance(building, StateSpaceBuilding):
        return building.outputs(quantity)
    n, floors, m = building.n_dofs, building.n_floors, building.n_actuators
    zero_state, zero_force = np.zeros((floors, n)), np.zeros((floors, m))
    drift_matrix = building.drift_matrix()
    # V_i = sum of m_j a_j over the degrees of freedom on floor i and above (devices on their floor)
    shear_sum = (building.dof_floors[None, :] >= np.arange(1, floors + 1)[:, None]).astype(float)
    if quantity == "displacement":
        return np.hstack([np.eye(n)[:floors], zero_state]), zero_force
    if quantity == "velocity":
        return np.hstack([zero_state, np.eye(n)[:floors]]), zero_force
    if quantity == "drift":
        return np.hstack([drift_matrix, zero_state]), zero_force
    if quantity == "absolute_acceleration":
        mass_inverse = np.linalg.inv(building.mass)
        c = np.hstack([-mass_inverse @ building.stiffness, -mass_inverse @ building.damping])
        return c[:floors], (mass_inverse @ building.actuator_matrix)[:floors]
    if quantity in ("story_shear", "base_shear"):
        c = shear_sum @ np.hstack([-building.stiffness, -building.damping])
        d = shear_sum @ building.actuator_matrix
        return (c, d) if quantity == "story_shear" else (c[:1], d[:1])
    if quantity == "force":
        return np.zeros((m, 2 * n)), np.eye(m)
    strokes = building.stroke_matrix()
    if quantity == "stroke":
        return np.hstack([strokes, np.zeros_like(strokes)]), np.zeros((strokes.shape[0], m))
    if quantity == "stroke_velocity":
        return np.hstack([np.zeros_like(strokes), strokes]), np.zeros((strokes.shape[0], m))
    if quantity == "device_velocity":
        return np.hstack([np.zeros((m, n)), building.actuator_matrix.T]), np.zeros((m, m))
    raise ValueError(f"unknown quantity {quantity!r}, expected one of {QUANTITIES}")


def state_space_arrays(building: Building) -> dict[str, np.ndarray]:
    """A shear or matrix building (floors only) as a state-space model file's arrays: A, B (its actuators'
    columns, then the ground's), C and D (displacements, velocities, drifts, absolute accelerations, story
    shears, n rows each), on the physical state [x; x']. `state_space.state_space_outputs` declares them."""
    system = state_space(building)
    rows = [output_matrices(building, quantity) for quantity in PER_FLOOR]
    c = np.vstack([row[0] for row in rows])
    d = np.vstack([row[1] for row in rows])
    return {
        "A": system.a,
        "B": np.column_stack([system.b_force, system.b_ground]),
        "C": c,
        "D": np.column_stack([d, np.zeros(c.shape[0])]),
    }


def simulate(
    building: Building,
    step: StepMap,
    ground: np.ndarray,
    *,
    forces: np.ndarray | None = None,
    floor_forces: np.ndarray | None = None,
) -> Response:
    """Whole-record open-loop simulation from rest.

    `ground` holds a_g (m/s^2) at the sub-step interval control_dt / substeps; `forces` (K, m)
    are held over each control step (zero when None); `floor_forces` (N, same samples x floors), if
    any, load the floors (exactly discretised whatever the method). K = (len(ground) - 1) // substeps.
    """
    ground_terms = step.ground_terms(ground)
    n_steps = ground_terms.shape[0]
    if forces is None:
        forces = np.zeros((n_steps, building.n_actuators))
    forcing = ground_terms + forces @ step.force_gain.T
    if floor_forces is not None:
        forcing = forcing + load_map(building, step.control_dt, step.substeps).terms(floor_forces)
    states = np.zeros((n_steps + 1, step.phi.shape[0]))
    phi_t = step.phi.T
    for k in range(n_steps):
        states[k + 1] = states[k] @ phi_t + forcing[k]
    held = np.vstack([np.zeros((1, building.n_actuators)), forces])
    samples = ground[:: step.substeps][: n_steps + 1]
    time = np.arange(n_steps + 1) * step.control_dt
    at_steps = None if floor_forces is None else floor_forces[:: step.substeps][: n_steps + 1]
    return response(
        lambda quantity: output_matrices(building, quantity),
        lambda quantity: load_feedthrough(building, quantity),
        states,
        held,
        time=time,
        ground=samples,
        floor_forces=at_steps,
    )
