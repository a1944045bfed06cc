"""The closed loop linearised at rest: a policy's state-transition matrix on a plant, and its spectral radius
(the safety check's stability criterion, on the design model and on the scenarios its standard judges, and
what `select_by: standard` asks of a checkpoint)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rlcontroller.config import Scenario
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.physics.motions.excitation import Load
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.batch import BuildingBatch


class _Silent:
    """A random generator that draws zeros: the noise-free closed loop."""

    def standard_normal(self, size) -> np.ndarray:
        return np.zeros(size)


def _started(plant: Plant, states: np.ndarray, grounds: list[float] | None = None, steps: int = 1):
    """A noise-free batch of `plant` without its supervisor, one member per row of `states` (s = [plant
    state; observation]) started there, under a ground acceleration held at `grounds[i]` m/s^2 (0 without)
    for `steps` control steps; and the plant it steps."""
    if plant.experiment.supervisor is not None:
        plant = Plant(plant.experiment.model_copy(update={"supervisor": None}))
    count, n_x = states.shape[0], plant.n_state
    batch = BuildingBatch(plant, count)
    for member, ground in enumerate(grounds or [0.0] * count):
        held = Load("held", plant.control_dt, np.full(steps + 2, ground), synthetic=True)
        batch.start(member, _Silent(), held)
    batch.plant_states()[:] = states[:, :n_x]
    batch.observations[:] = states[:, n_x:]
    batch.read_back_estimates()
    return batch


def _state(batch: BuildingBatch, observations: np.ndarray) -> np.ndarray:
    return np.hstack([batch.plant_states(), observations]).astype(float)


def closed_loop_matrix(plant: Plant, controller: PolicyController, step: float = 1e-4) -> np.ndarray:
    """A with s_{k+1} = A s_k for the closed loop linearised at rest without ground motion, noise or
    supervisor (`control.supervisor`: its trigger keeps a policy off at rest, its dissipative rule is
    not differentiable there), s = [plant state x; observation] (the observation holds the sensor
    history, the filter's estimate and the last actions, so it is the controller's whole state). Central
    differences of one batched control step from +/- `step` along each coordinate (exact for a linear
    policy)."""
    size = plant.n_state + plant.layout.size
    batch = _started(plant, np.vstack([np.eye(size), -np.eye(size)]) * step)
    controller.reset()
    observations, _, _ = batch.step(controller.act(batch.observations.copy()))
    after = _state(batch, observations)
    return ((after[:size] - after[size:]) / (2.0 * step)).T


@dataclass(frozen=True)
class OpenLoop:
    """s_{k+1} = state s_k + action a_k + ground g_k: one noise-free control step of a linear plant without
    supervisor, s = [plant state; observation], a the action in [-1, 1], g the ground acceleration (m/s^2)
    held over the step."""

    state: np.ndarray  # (n, n)
    action: np.ndarray  # (n, m)
    ground: np.ndarray  # (n,)
    n_plant: int
    dt: float  # the control step (s)


def open_loop(plant: Plant) -> OpenLoop:
    """`plant`'s control step as matrices (exact for a linear plant: unit steps from zero, one batch)."""
    size, m = plant.n_state + plant.layout.size, plant.building.n_actuators
    states = np.zeros((size + m + 1, size))
    states[:size] = np.eye(size)
    actions = np.vstack([np.zeros((size, m)), np.eye(m), np.zeros((1, m))])
    batch = _started(plant, states, grounds=[0.0] * (size + m) + [1.0])
    after = _state(batch, batch.step(actions)[0])
    return OpenLoop(after[:size].T, after[size : size + m].T, after[-1], plant.n_state, plant.control_dt)


def spectral_radius(plant: Plant, controller: PolicyController) -> float:
    return float(np.max(np.abs(np.linalg.eigvals(closed_loop_matrix(plant, controller)))))


def scenario_plant(plant: Plant, scenario: Scenario) -> Plant | None:
    """The linear plant of a standard scenario (`plant`'s experiment with the scenario's plant part), or None
    where the scenario yields (no linearisation at rest speaks for it)."""
    if scenario.plant is not None and scenario.plant.hysteresis is not None:
        return None
    return Plant(plant.experiment.model_copy(update={"plant": scenario.plant}))


def judged_plants(plant: Plant) -> list[Plant]:
    """The plants of the standard scenarios the safety check's standard judges stability on (`stable_on`:
    an actuator lag, one step of delay) that the experiment's scenario set has and that are linear, built as
    the check builds them."""
    from rlcontroller.config import load_safety_check, load_scenarios
    from rlcontroller.config.scenarios import safety_standard, standard_scenarios

    experiment = plant.experiment
    names = load_safety_check(safety_standard(experiment)).stable_on
    scenarios = load_scenarios(standard_scenarios(experiment), experiment)
    judged = [scenario_plant(plant, scenario) for scenario in scenarios if scenario.name in names]
    return [judged_plant for judged_plant in judged if judged_plant is not None]


def robust_spectral_radius(plant: Plant, controller: PolicyController, judged: list[Plant]) -> float:
    """The largest spectral radius of the closed loop on the design model and on each of the `judged` plants
    (`judged_plants`): what the safety check's stability criterion asks to be below 1."""
    return max([spectral_radius(plant.design, controller)] + [spectral_radius(p, controller) for p in judged])


def boundary_runs(plant: Plant, controller: PolicyController, starts: np.ndarray, steps: int) -> np.ndarray:
    """The closed loop's states (steps + 1, starts, n) from each start s = [plant state; observation],
    noise-free, without ground motion or supervisor: the controller as it acts, stepped by the simulator."""
    batch = _started(plant, starts, steps=steps)
    controller.reset()
    states = [_state(batch, batch.observations)]
    for _ in range(steps):
        observations, _, _ = batch.step(controller.act(batch.observations.copy()))
        states.append(_state(batch, observations))
    return np.stack(states)
