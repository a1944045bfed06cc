"""Steady-state Kalman filter of the building state from the noisy sensors, and the model-free
integration of the readings that some observations hold instead.

Measurements y_k = C z_k + D a_{k-1} + v_k include the feed-through of the action held over the
step that ended at t_k (absolute accelerations). The ground acceleration is either process noise,
or, with `known_ground`, a measured input whose change over a step is the process noise, or
(`design_kalman_ground_model`) the output of a Kanai-Tajimi filter (the plant's `ground_model`)
whose two states join the estimate and whose output is measured. Under wind
(`design_kalman_wind_model`) the fluctuating floor forces join the estimate instead (and the ground model
too, with `sensors.ground_model`). Everything is in action units
a = u / force_limit at the control step.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.linalg

from rlcontroller.control.riccati import kalman_gain
from rlcontroller.physics.dynamics import discrete_noise
from rlcontroller.physics.motions.wind import WindLoadModel
from rlcontroller.physics.observation import ObservationLayout
from rlcontroller.physics.plant import Plant


@dataclass(frozen=True)
class KalmanFilter:
    """The filter's matrices; the estimate is the caller's, so one filter serves a batch of buildings
    (leading axes of every argument of `update`)."""

    phi: np.ndarray
    action_gain: np.ndarray  # Gamma * force limits
    ground_gain: np.ndarray  # z response to a unit ground acceleration held over one step
    sensor_c: np.ndarray
    sensor_d: np.ndarray  # per unit action
    gain: np.ndarray  # L, measurement update
    known_ground: bool  # the previous ground reading is a known input of the prediction
    measures_ground: bool = False  # the current ground reading is one of the measurements

    @property
    def size(self) -> int:
        return self.phi.shape[0]

    @cached_property
    def update_matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Predict and correct folded into one affine map, (I - L C) applied once here instead of at
        every step: new = estimate @ A + held @ B + measured @ L' (+ previous ground * g)."""
        correction = np.eye(self.size) - self.gain @ self.sensor_c
        return (
            (correction @ self.phi).T,
            (correction @ self.action_gain - self.gain @ self.sensor_d).T,
            self.gain.T,
            correction @ self.ground_gain,
        )

    def on_observations(self, layout: ObservationLayout) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """`update` read straight from observations laid out by `layout`: new = estimate @ A +
        observation @ O (+ the previous observation's ground reading * g), the scales of the readings
        and of the ground folded in; O is zero but at the newest readings, ground reading and action."""
        free, action, measured, ground_gain = self.update_matrices
        observed = np.zeros((layout.size, self.size))
        n_readings = layout.readings.stop - layout.readings.start
        observed[layout.readings] = measured[:n_readings] * layout.reading_scale[:, None]
        if self.measures_ground:
            observed[layout.ground] = measured[n_readings] * layout.ground_scale
        observed[layout.action] = action
        return free, observed, ground_gain * layout.ground_scale if self.known_ground else None

    def update(
        self,
        estimate: np.ndarray,
        readings: np.ndarray,
        *,
        held_action: np.ndarray,
        ground: np.ndarray,
        previous_ground: np.ndarray,
    ) -> np.ndarray:
        """The estimate at the new readings: predict `estimate` over the last step, then correct with
        `readings` (and the ground reading `ground` at the same time, m/s^2); `previous_ground` is the
        one of the step before. Start from a zero estimate, zero action and zero previous ground: the
        prediction is then zero and the first update is the correction alone."""
        free, action, measured, ground_gain = self.update_matrices
        if self.measures_ground:
            readings = np.concatenate([readings, np.asarray(ground, dtype=float)[..., None]], axis=-1)
        new = estimate @ free + held_action @ action + readings @ measured
        if self.known_ground:
            new += np.asarray(previous_ground, dtype=float)[..., None] * ground_gain
        return new


def update_on_block(
    folded: tuple[np.ndarray, np.ndarray, np.ndarray | None],
    layout: ObservationLayout,
    estimate: np.ndarray,
    readings: np.ndarray,
    *,
    held_action: np.ndarray,
    previous_ground: np.ndarray | float,
) -> np.ndarray:
    """`KalmanFilter.update` on the newest block of readings as the observation holds them (scaled,
    the ground reading last), with `folded` = `filter.on_observations(layout)`; `previous_ground` is
    the block before's ground reading, scaled. Leading axes: one row per building."""
    free, observed, previous_ground_gain = folded
    new = estimate @ free + readings @ observed[: layout.block] + held_action @ observed[layout.action]
    if previous_ground_gain is not None:
        new += np.asarray(previous_ground)[..., None] * previous_ground_gain
    return new


def input_noise(plant: Plant, action_gain: np.ndarray) -> np.ndarray:
    """The fictitious process noise of `sensors.input_noise` (loop transfer recovery): that standard
    deviation of each action (a fraction of its force limit) per step, through `action_gain`."""
    level = plant.experiment.sensors.input_noise
    return level**2 * (action_gain @ action_gain.T)


def design_kalman(plant: Plant, known_ground: bool = False, ground_std: float = 1.0) -> KalmanFilter:
    """Filter for the plant's sensors; `ground_std` (m/s^2) is the ground's process-noise level per
    step (halved when the ground is measured: only its change over the step is unknown). The
    sensors' noise_std is the measurement noise, floored at 1e-3 of each sensor's scale."""
    step, building, sensors = plant.sampled().step, plant.building, plant.sensors
    ground_gain = step.ground_gain.sum(axis=1)
    c, d = sensors.c, sensors.d
    measurement = np.diag(np.maximum(sensors.noise_std, 1e-3 * sensors.scale) ** 2)
    process_std = ground_std * (0.5 if known_ground else 1.0)
    action_gain = step.force_gain * building.force_limits
    process = process_std**2 * np.outer(ground_gain, ground_gain) + 1e-12 * np.eye(step.phi.shape[0])
    process += input_noise(plant, action_gain)
    return KalmanFilter(
        phi=step.phi,
        action_gain=action_gain,
        ground_gain=ground_gain,
        sensor_c=c,
        sensor_d=d * building.force_limits,
        gain=kalman_gain(step.phi, c, process, measurement),
        known_ground=known_ground,
    )


def design_kalman_ground_model(plant: Plant, ground_std: float = 1.0) -> KalmanFilter:
    """Filter of [z; x_f; x_f'] (the plant's Kanai-Tajimi ground model) from the sensors plus the
    measured ground acceleration; w is scaled so that the modelled a_g has a stationary std of
    `ground_std` (m/s^2). Exact discretisation whatever the simulation method."""
    step, building, model = plant.sampled().ground_model, plant.building, plant.ground_model
    config = plant.experiment.sensors
    size = building.n_states
    noise_gain = step.ground_gain.sum(axis=1)
    stationary = scipy.linalg.solve_discrete_lyapunov(
        step.phi[size:, size:], np.outer(noise_gain, noise_gain)[size:, size:]
    )
    intensity = ground_std**2 / float(model.output @ stationary @ model.output)
    sensors = plant.sensors
    sensor_c = np.vstack(
        [np.pad(sensors.c, ((0, 0), (0, 2))), np.concatenate([np.zeros(size), model.output])]
    )
    sensor_d = np.vstack([sensors.d * building.force_limits, np.zeros((1, building.n_actuators))])
    noise = np.maximum(
        np.append(sensors.noise_std, config.ground_noise_std),
        1e-3 * np.append(sensors.scale, config.ground_scale),
    )
    action_gain = step.force_gain * building.force_limits
    process = intensity * np.outer(noise_gain, noise_gain) + 1e-12 * np.eye(size + 2)
    process += input_noise(plant, action_gain)
    return KalmanFilter(
        phi=step.phi,
        action_gain=action_gain,
        ground_gain=np.zeros(size + 2),
        sensor_c=sensor_c,
        sensor_d=sensor_d,
        gain=kalman_gain(step.phi, sensor_c, process, np.diag(noise**2)),
        known_ground=False,
        measures_ground=True,
    )


def design_kalman_wind_model(plant: Plant, model: WindLoadModel, ground_std: float = 1.0) -> KalmanFilter:
    """Filter of [z; f] (the fluctuating floor forces of `model`, a first-order process each) from the
    sensors, which feel f directly where they read absolute accelerations; with `sensors.ground_model`, of [z;
    f; x_g; x_g'] from the sensors and the ground reading, the Kanai-Tajimi filter's white noise scaled so
    that its ground acceleration has a stationary std of `ground_std` (m/s^2), as in
    `design_kalman_ground_model`. The process noise is discretised exactly (`dynamics.discrete_noise`)."""
    building, sensors, config = plant.building, plant.sensors, plant.experiment.sensors
    sampled = plant.sampled()
    system, step = sampled.wind_system, sampled.wind_model
    size, floors = 2 * building.n_dofs, building.n_floors
    intensity = np.zeros_like(system.a)
    intensity[size : size + floors, size : size + floors] = 2.0 * model.covariance / model.time_constant
    sensor_c = np.hstack([sensors.c, sensors.load])
    noise = np.maximum(sensors.noise_std, 1e-3 * sensors.scale)
    if config.ground_model:
        ground = plant.ground_model.output
        unit = scipy.linalg.solve_continuous_lyapunov(system.a[-2:, -2:], -np.diag([0.0, 1.0]))
        intensity[-1, -1] = ground_std**2 / float(ground @ unit @ ground)
        sensor_c = np.vstack(
            [np.pad(sensor_c, ((0, 0), (0, 2))), np.concatenate([np.zeros(size + floors), ground])]
        )
        noise = np.append(noise, max(config.ground_noise_std, 1e-3 * config.ground_scale))
    action_gain = step.force_gain * building.force_limits
    process = discrete_noise(system.a, intensity, step.phi) + 1e-12 * np.eye(step.phi.shape[0])
    process += input_noise(plant, action_gain)
    sensor_d = np.pad(
        sensors.d * building.force_limits, ((0, sensor_c.shape[0] - sensors.d.shape[0]), (0, 0))
    )
    return KalmanFilter(
        phi=step.phi,
        action_gain=action_gain,
        ground_gain=np.zeros(step.phi.shape[0]),
        sensor_c=sensor_c,
        sensor_d=sensor_d,
        gain=kalman_gain(step.phi, sensor_c, process, np.diag(noise**2)),
        known_ground=False,
        measures_ground=config.ground_model,
    )


def integration_filter(cutoff: float, control_dt: float, channels: int, n_actuators: int) -> KalmanFilter:
    """Model-free integration of `channels` accelerations (the readings, then the ground reading)
    to velocities and displacements, with no model of the building: per channel the states
    [h, d, v] of

        H(s) = 1 / (s + w),   D(s) = s / (s + w)^3,   V(s) = s^2 / (s + w)^3   (times A(s)),

    w = 2 pi `cutoff` (Hz). Above the cutoff h and v tend to the velocity (m/s) and d to the
    displacement (m); the three poles at -w remove a constant bias and the drift of integrated
    noise. Discretised by backward Euler (s -> (1 - 1/z) / dt), so the newest reading counts.
    The states are ordered [h of every channel, d of every channel, v of every channel]. In the
    Kalman filter's form: no prediction from the model, the "gain" feeds the readings in."""
    w = 2.0 * np.pi * cutoff
    a = np.array([[-w, 0.0, 0.0], [0.0, 0.0, 1.0], [-w, -w * w, -2.0 * w]])
    b = np.array([1.0, 0.0, 1.0])
    step = np.linalg.inv(np.eye(3) - control_dt * a)
    identity = np.eye(channels)
    size = 3 * channels
    return KalmanFilter(
        phi=np.kron(step, identity),
        action_gain=np.zeros((size, n_actuators)),
        ground_gain=np.zeros(size),
        sensor_c=np.zeros((channels, size)),
        sensor_d=np.zeros((channels, n_actuators)),
        gain=np.kron((control_dt * step @ b)[:, None], identity),
        known_ground=False,
        measures_ground=True,
    )


def observation_filter(plant: Plant) -> KalmanFilter | None:
    """The filter of the observation's own estimate: with `sensors.state_estimate` the Kalman filter
    designed on the design model as every controller is (the wind-model filter in an experiment
    trained under wind, with the ground model too if `sensors.ground_model`; the ground-model filter with
    `sensors.ground_model`, else the one with the
    measured ground as a known input); with
    `sensors.integration_cutoff` the model-free `integration_filter`; else None."""
    sensors = plant.experiment.sensors
    if sensors.integration_cutoff is not None:
        channels = plant.sensors.c.shape[0] + 1
        return integration_filter(
            sensors.integration_cutoff, plant.control_dt, channels, plant.building.n_actuators
        )
    if not sensors.state_estimate:
        return None
    design = plant.design
    if design.wind is not None:
        return design_kalman_wind_model(design, design.wind)
    return (
        design_kalman_ground_model(design)
        if sensors.ground_model
        else design_kalman(design, known_ground=True)
    )
