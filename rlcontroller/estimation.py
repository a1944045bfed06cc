"""Steady-state Kalman filter of the building state from the noisy sensors.

Measurements y_k = C z_k + D a_{k-1} + v_k include the feed-through of the action held over the
step that ended at t_k (absolute accelerations). The ground acceleration is either process noise,
or, with `known_ground`, a measured input whose change over a step is the process noise, or
(`design_kalman_ground_model`) the output of a Kanai-Tajimi filter whose two states join the
estimate and whose output is measured. Everything is in action units a = u / force_limit at the
control step.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import control
import numpy as np
import scipy.linalg

from rlcontroller.config import SensorConfig, SimulationConfig
from rlcontroller.dynamics import StateSpace, StepMap, compose, exact_substep, sensor_matrices, state_space, step_map
from rlcontroller.structure import Building


@dataclass(frozen=True)
class GroundModel:
    """Kanai-Tajimi ground filter  x_f'' + 2 damping frequency x_f' + frequency^2 x_f = -w  (w white),
    a_g = -frequency^2 x_f - 2 damping frequency x_f'. The defaults are the firm-soil values of
    Kanai-Tajimi (Tajimi 1960), not fitted to any record."""

    frequency: float = 15.6  # rad/s
    damping: float = 0.6

    @property
    def output(self) -> np.ndarray:
        """a_g = output @ [x_f, x_f']."""
        return np.array([-(self.frequency**2), -2.0 * self.damping * self.frequency])

    def state_scale(self, ground_scale: float) -> np.ndarray:
        """Typical sizes of x_f (m) and x_f' (m/s) for a ground acceleration of `ground_scale`."""
        return np.array([ground_scale / self.frequency**2, ground_scale / self.frequency])


def ground_model_step(building: Building, control_dt: float, model: GroundModel) -> StepMap:
    """Exact control-step map of the state [z; x_f; x_f'] driven by the forces and the white noise
    w (held over the step; `ground_gain` holds its two FOH columns)."""
    system = state_space(building)
    size = system.a.shape[0]
    filter_a = np.array([[0.0, 1.0], model.output])
    augmented = StateSpace(
        a=np.block([[system.a, np.outer(system.b_ground, model.output)], [np.zeros((2, size)), filter_a]]),
        b_force=np.vstack([system.b_force, np.zeros((2, building.n_actuators))]),
        b_ground=np.concatenate([np.zeros(size), [0.0, -1.0]]),
    )
    return compose(exact_substep(augmented, control_dt), 1, control_dt)


@dataclass
class KalmanFilter:
    phi: np.ndarray
    action_gain: np.ndarray  # Gamma * force limits
    ground_gain: np.ndarray  # z response to a unit ground acceleration held over one step
    sensor_c: np.ndarray
    sensor_d: np.ndarray  # per unit action
    gain: np.ndarray  # L, measurement update
    known_ground: bool  # the previous ground reading is a known input of the prediction
    measures_ground: bool = False  # the current ground reading is one of the measurements
    estimate: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        self.estimate = np.zeros(self.phi.shape[0])
        self._started = False

    def update(
        self, readings: np.ndarray, held_action: np.ndarray, ground: float, previous_ground: float
    ) -> np.ndarray:
        """Predict over the last step (if any), correct with the new readings (and the ground reading
        `ground` at the same time, m/s^2); `previous_ground` is the one of the step before."""
        if self.measures_ground:
            readings = np.append(readings, ground)
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


def design_kalman_ground_model(
    building: Building,
    sensors: SensorConfig,
    simulation: SimulationConfig,
    model: GroundModel,
    ground_std: float = 1.0,
) -> KalmanFilter:
    """Filter of [z; x_f; x_f'] from the sensors plus the measured ground acceleration; w is scaled
    so that the modelled a_g has a stationary std of `ground_std` (m/s^2). Exact discretisation
    whatever the simulation method."""
    step = ground_model_step(building, simulation.control_dt, model)
    size = 2 * building.n_floors
    noise_gain = step.ground_gain.sum(axis=1)
    stationary = scipy.linalg.solve_discrete_lyapunov(
        step.phi[size:, size:], np.outer(noise_gain, noise_gain)[size:, size:]
    )
    intensity = ground_std**2 / float(model.output @ stationary @ model.output)
    c, d, scale, noise = sensor_matrices(building, sensors)
    sensor_c = np.vstack([np.pad(c, ((0, 0), (0, 2))), np.concatenate([np.zeros(size), model.output])])
    sensor_d = np.vstack([d * building.force_limits, np.zeros((1, building.n_actuators))])
    noise = np.maximum(np.append(noise, sensors.ground_noise_std), 1e-3 * np.append(scale, sensors.ground_scale))
    process = intensity * np.outer(noise_gain, noise_gain) + 1e-12 * np.eye(size + 2)
    return KalmanFilter(
        phi=step.phi,
        action_gain=step.force_gain * building.force_limits,
        ground_gain=np.zeros(size + 2),
        sensor_c=sensor_c,
        sensor_d=sensor_d,
        gain=kalman_gain(step.phi, sensor_c, process, np.diag(noise**2)),
        known_ground=False,
        measures_ground=True,
    )
