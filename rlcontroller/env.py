"""Gymnasium environment: a shear building under one ground motion per episode.

Observation (float32, scaled to order one): H blocks, newest first, then the last action:
    [readings(t_k), a_g(t_k), readings(t_{k-1}), a_g(t_{k-1}), ..., (estimate), last action]
where readings are the configured sensors divided by their scales (with noise), a_g is the
ground acceleration divided by `ground_scale`, and the last action has m values in [-1, 1].
With `sensors.state_estimate` a Kalman estimate of [x; x'] from those same readings (scaled)
comes before the last action, followed, with `sensors.ground_model`, by the two estimated states
of a Kanai-Tajimi ground filter. Before the motion starts the history is zero.

Action: one value per actuator in [-1, 1], clipped, times the actuator's force limit (N);
the force is held constant over the control step.

Reward: -sum over terms of weight * sum over components (quantity / scale)^2, the quantities
taken at the end of the step with the force just applied. `info` holds each term's value
(`reward_<quantity>`) and the step's drift (m), absolute_acceleration (m/s^2), base_shear (N),
force (N) and time (s).

Termination: never (the building is stable); the episode is truncated when the ground motion
ends. The motion is drawn from the configured generator, or from `motions` given to the
constructor, or passed as `reset(options={"motion": GroundMotion})`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from rlcontroller.config import Experiment, load_experiment
from rlcontroller.dynamics import StepMap, output_matrices, reward_matrices, sensor_matrices, step_map
from rlcontroller.estimation import GroundModel, design_kalman, design_kalman_ground_model
from rlcontroller.excitation import GroundMotion, for_control_step, generate
from rlcontroller.structure import build


@dataclass(frozen=True)
class ObservationLayout:
    """Where the newest readings, ground reading, state estimate and last action sit in an
    observation, and the scales that turn them back into SI units."""

    readings: slice
    ground: int
    estimate: slice  # empty without `sensors.state_estimate`
    action: slice
    reading_scale: np.ndarray
    ground_scale: float
    estimate_scale: np.ndarray


class BuildingEnv(gym.Env):
    metadata = {"render_modes": []}

    def __init__(
        self,
        config: Experiment | str | Path | None = None,
        motions: list[GroundMotion] | None = None,
        render_mode: str | None = None,
    ) -> None:
        if config is None:
            config = Experiment()
        elif not isinstance(config, Experiment):
            config = load_experiment(config)
        self.experiment = config
        self.building = build(config.building, config.actuators)
        self.motions = motions
        self.render_mode = render_mode
        self._maps: dict[int, StepMap] = {}

        n = self.building.n_floors
        m = self.building.n_actuators
        self.history = config.sensors.history
        self.force_limits = self.building.force_limits
        self.control_dt = config.simulation.control_dt
        sensor_c, sensor_d, sensor_scale, sensor_noise = sensor_matrices(self.building, config.sensors)
        # Reward rows: terms on linear outputs first, then force-change terms (one row per actuator).
        linear_terms = [t for t in config.reward.terms if t.quantity != "force_change"]
        change_terms = [t for t in config.reward.terms if t.quantity == "force_change"]
        reward_c, reward_d, reward_factor, reward_slices = reward_matrices(self.building, linear_terms)
        self._reward_names = [term.label for term in linear_terms + change_terms]
        starts = [rows.start for rows in reward_slices] + [reward_c.shape[0] + i * m for i in range(len(change_terms))]
        self._reward_starts = np.array(starts, dtype=int)
        self._change_factor = (
            np.concatenate([self.building.force_limits * t.weight ** (1 / t.power) / t.scale for t in change_terms])
            if change_terms
            else None
        )
        self._change_terms = len(change_terms)
        row_powers = [
            np.full(rows.stop - rows.start, t.power) for t, rows in zip(linear_terms, reward_slices, strict=True)
        ]
        row_powers += [np.full(m, t.power) for t in change_terms]
        self._row_power = np.concatenate(row_powers)
        self._all_quadratic = bool(np.all(self._row_power == 2.0))
        drift_c, drift_d = output_matrices(self.building, "drift")
        acceleration_c, acceleration_d = output_matrices(self.building, "absolute_acceleration")
        shear_c, shear_d = output_matrices(self.building, "base_shear")
        # Every output of a step is one matrix product of the new state z and the force u:
        # [scaled readings | ground reading | weight^(1/power)/scale * reward quantities | drift | acceleration |
        # base shear]; the ground reading row is zero here and comes in through the forcing.
        no_state, no_force = np.zeros((1, 2 * n)), np.zeros((1, m))
        self._output_c = np.vstack(
            [
                sensor_c / sensor_scale[:, None],
                no_state,
                reward_c * reward_factor[:, None],
                drift_c,
                acceleration_c,
                shear_c,
            ]
        )
        self._output_d = np.vstack(
            [
                sensor_d / sensor_scale[:, None],
                no_force,
                reward_d * reward_factor[:, None],
                drift_d,
                acceleration_d,
                shear_d,
            ]
        )
        self._n_sensors = p = sensor_c.shape[0]
        r = reward_c.shape[0]
        # Output columns after the state: readings, ground reading, reward rows, drift, acceleration, shear.
        first = 2 * n
        self._reading_slice = slice(first, first + p + 1)
        self._reward_slice = slice(first + p + 1, first + p + 1 + r)
        self._drift_slice = slice(first + p + 1 + r, first + p + 1 + r + n)
        self._acceleration_slice = slice(first + p + 1 + r + n, first + p + 1 + r + 2 * n)
        self._base_shear_index = first + p + 1 + r + 2 * n
        self._noise_scaled = sensor_noise / sensor_scale
        self._ground_noise = config.sensors.ground_noise_std

        # Observation layout: H blocks of (p readings, 1 ground reading), the state estimate if
        # configured, then the last action.
        self._block = p + 1
        self._estimate_start = self.history * self._block
        self.kalman = None
        estimate_scale = np.zeros(0)
        sensors = config.sensors
        if sensors.state_estimate:
            estimate_scale = np.array([sensors.displacement_scale] * n + [sensors.velocity_scale] * n)
            if sensors.ground_model:
                model = GroundModel()
                self.kalman = design_kalman_ground_model(self.building, sensors, config.simulation, model)
                estimate_scale = np.append(estimate_scale, model.state_scale(sensors.ground_scale))
            else:
                self.kalman = design_kalman(self.building, sensors, config.simulation, known_ground=True)
        self._action_start = self._estimate_start + estimate_scale.size
        self.layout = ObservationLayout(
            readings=slice(0, p),
            ground=p,
            estimate=slice(self._estimate_start, self._action_start),
            action=slice(self._action_start, self._action_start + m),
            reading_scale=sensor_scale,
            ground_scale=config.sensors.ground_scale,
            estimate_scale=estimate_scale,
        )
        observation_size = self._action_start + m
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, shape=(observation_size,), dtype=np.float32)
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=(m,), dtype=np.float32)
        self._observation = np.zeros(observation_size, dtype=np.float32)
        self._n_state = 2 * n
        self._state_action = np.zeros(2 * n + m)  # [z | clipped action]
        self._k = 0
        self._n_steps = 0
        self.motion: GroundMotion | None = None

    def step_map(self, substeps: int) -> StepMap:
        """The control-step map for `substeps` ground samples per step (cached)."""
        if substeps not in self._maps:
            self._maps[substeps] = step_map(self.building, self.experiment.simulation, substeps)
        return self._maps[substeps]

    @property
    def state(self) -> np.ndarray:
        """Current state z = [x; x'] (m, m/s)."""
        return self._state_action[: self._n_state].copy()

    @property
    def held_force(self) -> np.ndarray:
        """The force (N) held over the step that ended at the current time."""
        return self._state_action[self._n_state :] * self.force_limits

    def _draw_motion(self) -> GroundMotion:
        if self.motions:
            return self.motions[int(self.np_random.integers(len(self.motions)))]
        return generate(self.experiment.excitation.generator, self.np_random)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        motion = (options or {}).get("motion") or self._draw_motion()
        self.motion = motion
        samples, substeps = for_control_step(motion, self.control_dt)
        step = self.step_map(substeps)
        ground_terms = step.ground_terms(samples)
        self._n_steps = ground_terms.shape[0]
        # [z_{k+1} | outputs_{k+1}] = [z_k | action_k] @ transition + forcing[k], u = action * limit
        force_gain = step.force_gain * self.force_limits
        self._transition = np.vstack(
            [
                np.hstack([step.phi.T, step.phi.T @ self._output_c.T]),
                np.hstack([force_gain.T, (self._output_c @ force_gain + self._output_d * self.force_limits).T]),
            ]
        )
        self._forcing = np.hstack([ground_terms, ground_terms @ self._output_c.T])
        p, rng = self._n_sensors, self.np_random
        ground = samples[::substeps][: self._n_steps + 1]
        self.ground_samples = ground
        readings = np.empty((self._n_steps + 1, p + 1))
        readings[:, :p] = rng.standard_normal((self._n_steps + 1, p)) * self._noise_scaled
        readings[:, p] = (ground + self._ground_noise * rng.standard_normal(ground.size)) / self.layout.ground_scale
        self._forcing[:, self._reading_slice] += readings[1:]
        self._k = 0
        self._state_action[:] = 0.0
        self._previous_action = np.zeros(self.building.n_actuators)
        self._observation[:] = 0.0
        self._observation[: p + 1] = readings[0]
        if self.kalman is not None:
            self.kalman.reset()
            ground = readings[0, p] * self.layout.ground_scale
            estimate = self.kalman.update(
                readings[0, :p] * self.layout.reading_scale, np.zeros(self.building.n_actuators), ground, 0.0
            )
            self._previous_ground = ground
            self._observation[self._estimate_start : self._action_start] = estimate / self.layout.estimate_scale
        return self._observation.copy(), {"motion": motion.name, "steps": self._n_steps}

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        k = self._k
        if k >= self._n_steps:
            raise RuntimeError("step() called after the episode ended; call reset()")
        state_action, n_state = self._state_action, self._n_state
        clipped = state_action[n_state:]
        clipped[:] = action
        np.minimum(clipped, 1.0, out=clipped)
        np.maximum(clipped, -1.0, out=clipped)
        outputs = state_action @ self._transition
        outputs += self._forcing[k]
        state_action[:n_state] = outputs[:n_state]
        self._k = k = k + 1

        observation, block, last = self._observation, self._block, self._action_start
        observation[block:last] = observation[: last - block]
        observation[:block] = outputs[self._reading_slice]
        if self.kalman is not None:
            readings = outputs[self._reading_slice]
            ground = readings[-1] * self.layout.ground_scale
            estimate = self.kalman.update(
                readings[:-1] * self.layout.reading_scale, clipped, ground, self._previous_ground
            )
            self._previous_ground = ground
            observation[self._estimate_start : last] = estimate / self.layout.estimate_scale
        observation[last:] = clipped

        weighted = outputs[self._reward_slice]
        if self._change_factor is not None:
            change = np.tile(clipped - self._previous_action, self._change_terms) * self._change_factor
            weighted = np.concatenate([weighted, change])
        self._previous_action[:] = clipped
        values = weighted * weighted if self._all_quadratic else np.abs(weighted) ** self._row_power
        terms = np.add.reduceat(values, self._reward_starts).tolist()
        info: dict[str, Any] = dict(zip(self._reward_names, terms, strict=True))
        info["drift"] = outputs[self._drift_slice]
        info["absolute_acceleration"] = outputs[self._acceleration_slice]
        info["base_shear"] = outputs[self._base_shear_index]
        info["force"] = clipped * self.force_limits
        info["time"] = k * self.control_dt
        return observation.copy(), -sum(terms), False, k >= self._n_steps, info
