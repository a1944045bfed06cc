"""The closed loop linearised at rest: a policy's state-transition matrix on a plant, and its spectral radius
(the safety check's stability criterion, and what `select_by: standard` asks of a checkpoint)."""

from __future__ import annotations

import numpy as np

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
    history, the filter's estimate and the last actions, so it is the controller's whole state). Central differences of
    one batched control step from +/- `step` along each coordinate (exact for a linear policy)."""
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
