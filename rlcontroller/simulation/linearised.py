"""The closed loop linearised at rest: a policy's state-transition matrix on a plant, and its spectral radius
(the safety check's stability criterion, on the design model and on the scenarios its standard judges, and
what `select_by: standard` asks of a checkpoint)."""

from __future__ import annotations

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


def closed_loop_matrix(plant: Plant, controller: PolicyController, step: float = 1e-4) -> np.ndarray:
    """A with s_{k+1} = A s_k for the closed loop linearised at rest without ground motion, noise or
    supervisor (`control.supervisor`: its trigger keeps a policy off at rest, its dissipative rule is
    not differentiable there), s = [plant state x; observation] (the observation holds the sensor
    history, the filter's estimate and the last actions, so it is the controller's whole state). Central
    differences of one batched control step from +/- `step` along each coordinate (exact for a linear
    policy)."""
    if plant.experiment.supervisor is not None:
        plant = Plant(plant.experiment.model_copy(update={"supervisor": None}))
    n_x, n_o = plant.n_state, plant.layout.size
    size = n_x + n_o
    batch = BuildingBatch(plant, 2 * size)
    still = Load("at rest", plant.control_dt, np.zeros(3), synthetic=True)
    for member in range(2 * size):
        batch.start(member, _Silent(), still)
    basis = np.vstack([np.eye(size), -np.eye(size)]) * step
    batch.plant_states()[:] = basis[:, :n_x]
    batch.observations[:] = basis[:, n_x:]
    batch.read_back_estimates()
    controller.reset()
    observations, _, _ = batch.step(controller.act(batch.observations.copy()))
    after = np.hstack([batch.plant_states(), observations])
    return ((after[:size] - after[size:]) / (2.0 * step)).T


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
