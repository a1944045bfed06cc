"""A plant sampled at its control step: the one compiled object the simulator, the estimators and the
controllers take.

Like do-mpc's `Model.setup()` (the model compiled once; simulator, estimator and controller take it) and
python-control's `sample()` (a discrete system carrying its matrices and its dt), `Plant.sampled(r)` builds,
once per number r of load samples per control step, every discrete map of the plant; nothing else
discretises it:

- `step`: x_{k+1} = phi x_k + force_gain u_k + ground_gain a_g[k r : k r + r + 1] on the plant's state x, the
  actuators' lag and delay included (u in N);
- `structure`: the same on the building's own z = [x; v], without actuator dynamics: the building left alone;
- `load`: floor forces (N), linear between their samples, over a step on x (plants that take them);
- `ground_model`, and `wind_model` with its continuous `wind_system`: the building with its Kanai-Tajimi
  ground filter or its first-order model of the wind's floor forces (and the ground filter, with
  `sensors.ground_model`), over one control step (the designs of LQG, the Kalman filters and MPC);

and from these what a whole load does: `forcing` (its terms in every step), `simulate` (the building left
alone, from rest) and `response` (every time history, from states and held forces, on the plant's outputs
`Plant.outputs`). A plant with its own integrator (yielding stories, dampers, an FE model) has no linear
`step`; its `forcing` holds the floor loads' output terms only, and it steps itself.
"""

from __future__ import annotations

from dataclasses import replace
from functools import cached_property
from typing import Protocol

import numpy as np

from rlcontroller.config import Experiment
from rlcontroller.errors import MotionError
from rlcontroller.physics.dynamics import (
    LoadMap,
    StateSpace,
    StepMap,
    compose,
    exact_substep,
    ground_model_step,
    load_feedthrough,
    load_map,
    output_matrices,
    state_space,
    step_map,
    wind_model_system,
)
from rlcontroller.physics.motions.excitation import FLOOR_FORCES, LoadGrid
from rlcontroller.physics.motions.generators import GroundModel
from rlcontroller.physics.motions.wind import WindLoadModel
from rlcontroller.physics.response import Response, response
from rlcontroller.physics.structure import Building


class Sampleable(Protocol):
    """What sampling reads of a plant (`physics.plant.Plant` is one): its building and experiment, control
    step (s), state size, force limits (N), actuator lag (s) and delay (steps), whether it steps itself, its
    design's ground and wind models, and its outputs on its full state."""

    building: Building
    experiment: Experiment
    control_dt: float
    n_state: int
    n_linear: int
    force_limits: np.ndarray
    time_constant: float
    delay_steps: int
    semi_active: object | None
    end_stops: object | None
    integrator: object | None
    yielding: object | None
    ground_model: GroundModel
    wind: WindLoadModel | None

    @property
    def has_actuator_dynamics(self) -> bool: ...

    def outputs(self, quantity: str) -> tuple[np.ndarray, np.ndarray]: ...

    def load_outputs(self, quantity: str) -> np.ndarray: ...

    def cannot_take(self, kind: str) -> str | None: ...


class SampledPlant:
    """`plant` sampled at its control step with `substeps` load samples per step (module docstring); each
    map is built on first use and kept."""

    def __init__(self, plant: Sampleable, substeps: int) -> None:
        self.plant, self.substeps = plant, substeps
        self.control_dt, self.n_state = plant.control_dt, plant.n_state

    @cached_property
    def structure(self) -> StepMap:
        """The building's own control-step map on z (no actuator dynamics)."""
        plant = self.plant
        if plant.semi_active is not None:
            raise ValueError("a building with semi-active dampers has no linear step map")
        return step_map(plant.building, plant.experiment.simulation, self.substeps)

    @cached_property
    def step(self) -> StepMap:
        """The control-step map on x, with the actuators' lag (exact over each sub-step) and delay."""
        plant = self.plant
        if not plant.has_actuator_dynamics:
            return self.structure
        size, m = plant.building.n_states, plant.building.n_actuators
        if plant.time_constant > 0:  # [z; f] with tau f' = u - f
            system = state_space(plant.building)
            a = np.zeros((size + m, size + m))
            a[:size, :size] = system.a
            a[:size, size:] = system.b_force
            a[size:, size:] = -np.eye(m) / plant.time_constant
            lagged = StateSpace(
                a=a,
                b_force=np.vstack([np.zeros((size, m)), np.eye(m) / plant.time_constant]),
                b_ground=np.concatenate([system.b_ground, np.zeros(m)]),
            )
            core = compose(
                exact_substep(lagged, self.control_dt / self.substeps), self.substeps, self.control_dt
            )
        else:
            core = self.structure
        return _delayed(core, plant.delay_steps, m, plant.n_linear, lagged=plant.time_constant > 0)

    @cached_property
    def load(self) -> LoadMap:
        """Floor forces over a control step on x (actuator states do not feel them); linear plants only."""
        refusal = self.plant.cannot_take(FLOOR_FORCES)
        if refusal is not None:
            raise ValueError(refusal)
        gain = load_map(self.plant.building, self.control_dt, self.substeps).gain
        full = np.zeros((self.n_state, *gain.shape[1:]))
        full[: gain.shape[0]] = gain
        return LoadMap(gain=full)

    @cached_property
    def ground_model(self) -> StepMap:
        """The exact control-step map of the building and its Kanai-Tajimi ground model
        (`plant.ground_model`)."""
        return ground_model_step(self.plant.building, self.control_dt, self.plant.ground_model)

    @cached_property
    def wind_system(self) -> StateSpace:
        """The continuous system of the building and its design wind's floor forces (`plant.wind`), and with
        `sensors.ground_model` its Kanai-Tajimi ground model too: a building under wind will also shake."""
        plant = self.plant
        if plant.wind is None:
            raise ValueError("a wind model needs the experiment's excitation generator to be of kind wind")
        ground = plant.ground_model if plant.experiment.sensors.ground_model else None
        return wind_model_system(plant.building, plant.wind.time_constant, ground)

    @cached_property
    def wind_model(self) -> StepMap:
        """`wind_system` over one control step, exactly."""
        return compose(exact_substep(self.wind_system, self.control_dt), 1, self.control_dt)

    def forcing(self, grid: LoadGrid, c: np.ndarray, load_rows: np.ndarray) -> np.ndarray:
        """What the load adds to each control step beyond the plant's own transition: (n_steps, n_state +
        outputs), its terms in the state x and in outputs y = c x + load_rows F (F the floor forces). A
        plant with its own integrator takes the ground acceleration in its step, and the floor forces too
        (end-stops) or refuses them (`Plant.cannot_take`): only their direct terms in outputs are here."""
        n_steps, n_state = grid.n_steps, self.n_state
        forcing = np.zeros((n_steps, n_state + c.shape[0]))
        if self.plant.integrator is None:
            forcing[:, :n_state] = self.step.ground_terms(grid.ground)
        # end-stops take them in their step
        if grid.floor_forces is not None and self.plant.integrator is None:
            forcing[:, :n_state] += self.load_terms(grid)
            forcing[:, n_state:] = grid.floor_forces[grid.substeps :: grid.substeps][:n_steps] @ load_rows.T
        forcing[:, n_state:] += forcing[:, :n_state] @ c.T
        return forcing

    def transition(self, c: np.ndarray, d: np.ndarray) -> np.ndarray:
        """T with [x_{k+1} | y_{k+1}] = [x_k | action_k] @ T + forcing[k], for outputs y = c x + d u (u in N,
        the action times the force limits); linear plants."""
        step, force_limits = self.step, self.plant.force_limits
        force_gain = step.force_gain * force_limits
        return np.vstack(
            [
                np.hstack([step.phi.T, step.phi.T @ c.T]),
                np.hstack([force_gain.T, (c @ force_gain + d * force_limits).T]),
            ]
        )

    def load_terms(self, grid: LoadGrid) -> np.ndarray:
        """The floor forces' terms in x over every control step of `grid` (MotionError, one line, for forces
        on another number of floors than the building's)."""
        floors = self.plant.building.n_floors
        if grid.floor_forces.shape[1] != floors:
            raise MotionError(
                f"floor forces on {grid.floor_forces.shape[1]} floors, the building has {floors}"
            )
        return self.load.terms(grid.floor_forces)

    def simulate(self, grid: LoadGrid) -> Response:
        """The building left alone under the load of `grid` (this sampling's), from rest: its own map on its
        own state z and its own outputs (the actuators, at rest, play no part); linear plants."""
        step, building = self.structure, self.plant.building
        forcing = step.ground_terms(grid.ground)
        n_steps = forcing.shape[0]
        if grid.floor_forces is not None:
            forcing = forcing + self.load_terms(grid)[:, : building.n_states]
        states = np.zeros((n_steps + 1, building.n_states))
        phi_t = step.phi.T
        for k in range(n_steps):
            states[k + 1] = states[k] @ phi_t + forcing[k]
        held = np.zeros((n_steps + 1, building.n_actuators))
        time = np.arange(n_steps + 1) * self.control_dt
        ground = grid.ground[:: self.substeps][: n_steps + 1]
        floor_forces = (
            None if grid.floor_forces is None else grid.floor_forces[:: self.substeps][: n_steps + 1]
        )
        return response(
            lambda quantity: output_matrices(building, quantity),
            lambda quantity: load_feedthrough(building, quantity),
            states,
            held,
            time=time,
            ground=ground,
            floor_forces=floor_forces,
        )

    def response(
        self,
        states: np.ndarray,
        held_forces: np.ndarray,
        time: np.ndarray,
        *,
        ground: np.ndarray,
        floor_forces: np.ndarray | None = None,
    ) -> Response:
        """Time histories from the plant's states x (K+1, n_state), the forces (N) held just before each
        instant and the floor forces (N) at each instant, if any; for yielding plants also the story
        hysteretic forces (N: (1 - a) k d_y z for story springs)."""
        plant = self.plant
        hysteretic = None if plant.yielding is None else plant.yielding.story_force_map
        result = response(
            plant.outputs,
            plant.load_outputs,
            states,
            held_forces,
            time=time,
            ground=ground,
            floor_forces=floor_forces,
            story_force_map=hysteretic,
        )
        stops = plant.end_stops
        if stops is None:
            return result
        count, stopped = len(plant.building.devices), stops.devices.size
        peaks, contacts = (np.zeros((states.shape[0], count)) for _ in range(2))
        registers = states[:, plant.n_linear :]
        peaks[:, stops.devices] = registers[:, stopped : 2 * stopped]
        contacts[:, stops.devices] = registers[:, 2 * stopped :]
        return replace(result, stop_force=peaks, stop_contacts=contacts)


def _delayed(core: StepMap, delay: int, m: int, size: int, lagged: bool) -> StepMap:
    """`core` behind a delay of `delay` control steps: the commands wait in a buffer of the state (of
    `size` in all); without a lag a register keeps the force applied over the step."""
    if delay == 0:
        return core
    inner = core.phi.shape[0]
    phi = np.zeros((size, size))
    phi[:inner, :inner] = core.phi
    # the command of `delay` steps ago, applied now
    oldest = slice(inner + (delay - 1) * m, inner + delay * m)
    phi[:inner, oldest] = core.force_gain
    for j in range(1, delay):  # the buffer shifts by one step
        phi[inner + j * m : inner + (j + 1) * m, inner + (j - 1) * m : inner + j * m] = np.eye(m)
    if not lagged:
        phi[-m:, oldest] = np.eye(m)  # the register keeps the force applied over this step
    force_gain = np.zeros((size, m))
    force_gain[inner : inner + m] = np.eye(m)
    ground_gain = np.zeros((size, core.ground_gain.shape[1]))
    ground_gain[:inner] = core.ground_gain
    return StepMap(phi=phi, force_gain=force_gain, ground_gain=ground_gain, control_dt=core.control_dt)
