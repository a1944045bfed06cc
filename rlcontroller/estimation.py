"""Steady-state Kalman filter of the building state from the noisy sensors.

Measurements y_k = C z_k + D a_{k-1} + v_k include the feed-through of the action held over the
step that ended at t_k (absolute accelerations); the ground acceleration is process noise, or,
with `known_ground`, a measured input whose change over a step is the process noise. Everything
is in action units a = u / force_limit at the control step (exact discretisation).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import control
import numpy as np

from rlcontroller.config import SensorConfig, SimulationConfig
from rlcontroller.dynamics import sensor_matrices, step_map
from rlcontroller.structure import Building


@dataclass
class KalmanFilter:
    phi: np.ndarray
    action_gain: np.ndarray  # Gamma * force limits
    ground_gain: np.ndarray  # z response to a unit ground acceleration held over one step
    sensor_c: np.ndarray
    sensor_d: np.ndarray  # per unit action
    gain: np.ndarray  # L, measurement update
    known_ground: bool
    estimate: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        self.estimate = np.zeros(self.phi.shape[0])
        self._started = False

    def update(self, readings: np.ndarray, held_action: np.ndarray, previous_ground: float) -> np.ndarray:
        """Predict over the last step (if any), correct with the new readings; the estimate of z."""
        if self._started:
            self.estimate = self.phi @ self.estimate + self.action_gain @ held_action
            if self.known_ground:
                self.estimate += self.ground_gain * previous_ground
        self._started = True
        innovation = readings - self.sensor_c @ self.estimate - self.sensor_d @ held_action
        self.estimate = self.estimate + self.gain @ innovation
        return self.estimate


def kalman_gain(phi: np.ndarray, c: np.ndarray, process: np.ndarray, measurement: np.ndarray) -> np.ndarray:
    """Steady-state measurement-update gain L for x+ = phi x + w (cov process), y = c x + v (cov measurement)."""
    prior, _, _ = control.dare(phi.T, c.T, process, measurement, method="scipy")
    return prior @ c.T @ np.linalg.inv(c @ prior @ c.T + measurement)


def design_kalman(
    building: Building,
    sensors: SensorConfig,
    simulation: SimulationConfig,
    known_ground: bool = False,
    ground_std: float = 1.0,
) -> KalmanFilter:
    """Filter for `sensors`; `ground_std` (m/s^2) is the ground's process-noise level per step
    (halved when the ground is measured: only its change over the step is unknown). The sensors'
    noise_std is the measurement noise, floored at 1e-3 of each sensor's scale."""
    step = step_map(building, simulation, substeps=1)
    ground_gain = step.ground_gain.sum(axis=1)
    c, d, scale, noise = sensor_matrices(building, sensors)
    measurement = np.diag(np.maximum(noise, 1e-3 * scale) ** 2)
    process_std = ground_std * (0.5 if known_ground else 1.0)
    process = process_std**2 * np.outer(ground_gain, ground_gain) + 1e-12 * np.eye(step.phi.shape[0])
    return KalmanFilter(
        phi=step.phi,
        action_gain=step.force_gain * building.force_limits,
        ground_gain=ground_gain,
        sensor_c=c,
        sensor_d=d * building.force_limits,
        gain=kalman_gain(step.phi, c, process, measurement),
        known_ground=known_ground,
    )
