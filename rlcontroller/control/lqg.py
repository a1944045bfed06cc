"""LQG with the same cost as the reward: the LQR of `lqr` and a steady-state Kalman filter.

The Kalman filter (`estimation`) estimates z from the same noisy sensors the agent sees, with the
feed-through of the held force. Three variants: the ground acceleration unknown (process noise),
measured and used as a known input, or measured and predicted through a Kanai-Tajimi ground model
in the state (`design_lqg_ground_model`); under wind, the fluctuating floor forces modelled in the
state (`design_lqg_wind_model`). Gains act in action units a = u / force_limit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rlcontroller.config import RewardConfig
from rlcontroller.control.estimation import (
    KalmanFilter,
    design_kalman,
    design_kalman_ground_model,
    design_kalman_wind_model,
)
from rlcontroller.control.lqr import lqr_gain, preview_kernel, quadratic_cost
from rlcontroller.physics.plant import Plant


@dataclass
class LQGDesign:
    """LQR gains in action units a = u / force_limit, and the Kalman filter."""

    feedback: np.ndarray  # K
    feedforward: np.ndarray  # K_g on the measured ground acceleration (known-input variant), else zero
    filter: KalmanFilter

    def closed_loop_eigenvalues(self) -> np.ndarray:
        return np.linalg.eigvals(self.filter.phi - self.filter.action_gain @ self.feedback)


def design_lqg(
    plant: Plant,
    known_ground: bool = False,
    ground_std: float = 1.0,
    reward: RewardConfig | None = None,
) -> LQGDesign:
    """LQG for the plant's building, sensors and reward (or another `reward` for sweeps).

    With `known_ground` the measured ground acceleration enters the filter and, through the
    optimal one-step feed-forward, the control law.
    """
    building, step = plant.building, plant.sampled().step
    cost = quadratic_cost(plant, reward or plant.experiment.reward, step)
    feedback, _ = lqr_gain(step, cost, building.force_limits)
    kalman = design_kalman(plant, known_ground, ground_std)
    feedforward = np.zeros(building.n_actuators)
    if known_ground:  # the ground held over the coming step: the first preview kernel
        feedforward = preview_kernel(cost, step, building.force_limits, 1)[0] @ kalman.ground_gain
    return LQGDesign(feedback=feedback, feedforward=feedforward, filter=kalman)


def design_lqg_ground_model(
    plant: Plant, ground_std: float = 1.0, reward: RewardConfig | None = None
) -> LQGDesign:
    """LQG whose model includes a Kanai-Tajimi filter for the (measured) ground acceleration.

    The Kalman filter estimates the building and filter states from the floor sensors plus the
    ground reading; the LQR on the augmented state (the reward's cost, or `reward`'s) acts on the
    predicted ground.
    """
    building, step = plant.building, plant.sampled().ground_model
    cost = quadratic_cost(plant, reward or plant.experiment.reward, step)
    feedback, _ = lqr_gain(step, cost, building.force_limits)
    kalman = design_kalman_ground_model(plant, ground_std)
    return LQGDesign(feedback=feedback, feedforward=np.zeros(building.n_actuators), filter=kalman)


def design_lqg_wind_model(plant: Plant, reward: RewardConfig | None = None) -> LQGDesign:
    """LQG whose model includes the fluctuating floor forces of the experiment's design wind
    (`Plant.wind`): the Kalman filter estimates building and forces from the floor sensors, and the
    LQR on the augmented state (the reward's cost, or `reward`'s for sweeps; the forces felt at once
    by the absolute accelerations) acts on them."""
    model = plant.wind
    if model is None:
        raise ValueError("LQG + wind model needs the experiment's excitation generator to be of kind wind")
    building, step = plant.building, plant.sampled().wind_model
    cost = quadratic_cost(plant, reward or plant.experiment.reward, step, floor_loads=True)
    feedback, _ = lqr_gain(step, cost, building.force_limits)
    kalman = design_kalman_wind_model(plant, model)
    return LQGDesign(feedback=feedback, feedforward=np.zeros(building.n_actuators), filter=kalman)
