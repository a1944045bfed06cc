"""Gymnasium environment: a shear building under one ground motion per episode.

Observation (float32, scaled to order one): H blocks, newest first, then the last actions:
    [readings(t_k), a_g(t_k), readings(t_{k-1}), a_g(t_{k-1}), ..., (estimate), last actions]
where readings are the configured sensors divided by their scales (with noise), a_g is the
ground acceleration divided by `ground_scale`, and the last action has m values in [-1, 1].
With `sensors.state_estimate` a Kalman estimate of [x; x'] from those same readings (scaled)
comes before the last action, followed, with `sensors.ground_model`, by the two estimated states
of a Kanai-Tajimi ground filter; with `sensors.integration_cutoff` the model-free integrated
readings (`control.estimation.integration_filter`) sit there instead. With `sensors.twin` the fail-safe
twin's estimate and running story peaks follow the estimate (`control.twin`). Before the motion starts
the history is zero.

Action: one value per actuator in [-1, 1], clipped, passed through the experiment's supervisor if
it has one (`control.supervisor`: a trigger level, dissipative forces only), times the actuator's
force limit (N); the force is held constant over the control step. The observation's last action
is the one applied.

Reward: -sum over terms of weight * sum over components (quantity / scale)^2, the quantities
taken at the end of the step with the force just applied (with `reward.per_motion` each term is
divided by the episode's rms ground acceleration to its power). `info` holds each term's value
(`reward_<quantity>`, not divided) and the step's drift (m), absolute_acceleration (m/s^2), base_shear (N),
force (N) and time (s).

Termination: never (the building is stable); the episode is truncated when the ground motion
ends. The motion is drawn from the configured generator, or from `motions` given to the
constructor, or passed as `reset(options={"motion": Load})`.

Plant: the env simulates the experiment's plant (its `plant` part, if any); the state estimate
is designed on the design model, as every controller is. With `randomize=True` (training and
validation) and a `plant_randomization` part, each reset draws a new plant from the env's seed.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from rlcontroller.config import Experiment, load_experiment
from rlcontroller.control.controllers import Controller
from rlcontroller.control.estimation import observation_filter, update_on_block
from rlcontroller.control.supervisor import supervisor
from rlcontroller.control.twin import FailSafeTwin
from rlcontroller.physics.fe.build import reduced_building
from rlcontroller.physics.motions.excitation import Load, LoadGrid, on_control_grid
from rlcontroller.physics.motions.loads import generate
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.response import Response
from rlcontroller.physics.variations import draw_plant
from rlcontroller.simulation.outputs import noisy_readings, step_outputs


class BuildingEnv(gym.Env):
    metadata = {"render_modes": []}

    def __init__(
        self,
        config: Plant | Experiment | str | Path | None = None,
        motions: list[Load] | None = None,
        render_mode: str | None = None,
        randomize: bool = False,
    ) -> None:
        if isinstance(config, Plant):
            plant = config
        elif isinstance(config, Experiment):
            plant = Plant(config)
        else:
            plant = Plant(
                Experiment() if config is None else load_experiment(config, reduce=reduced_building)
            )
        experiment = self.experiment = plant.experiment
        self.motions = motions
        self.render_mode = render_mode

        m = plant.building.n_actuators
        self.history = experiment.sensors.history
        self.force_limits = plant.force_limits
        self.control_dt = plant.control_dt
        self._randomization = experiment.plant_randomization if randomize else None
        self._use_plant(plant)
        self.layout = layout = plant.layout
        self.kalman = observation_filter(plant)  # the agent's own estimate, designed like LQG's
        if self.kalman is not None:
            self._filter_matrices = self.kalman.on_observations(self.layout)
        self.supervisor = supervisor(plant, 1)
        self.twin = FailSafeTwin(plant, 1) if experiment.sensors.twin else None
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, shape=(layout.size,), dtype=np.float32)
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=(m,), dtype=np.float32)
        self._observation = np.zeros(layout.size, dtype=np.float32)
        self._held_force = np.zeros(m)
        self._k = 0
        self._n_steps = 0
        self.motion: Load | None = None

    def _use_plant(self, plant: Plant) -> None:
        """Simulate `plant` from the next step on: its output matrices, sensor noise and bias, state."""
        self.plant, self.building = plant, plant.building
        self._outputs = step_outputs(plant)
        self._n_sensors = plant.sensors.c.shape[0]
        self._n_state = plant.n_state
        self._state_action = np.zeros(plant.n_state + self.building.n_actuators)  # [x | clipped action]

    @property
    def state(self) -> np.ndarray:
        """Current building state z = [x; x'] (m, m/s), without actuator states."""
        return self._state_action[: self.building.n_states].copy()

    @property
    def plant_state(self) -> np.ndarray:
        """The plant's whole state x (with actuator or hysteretic states)."""
        return self._state_action[: self._n_state].copy()

    @property
    def command(self) -> np.ndarray:
        """The command (N) of the step that ended now: the clipped action times the force limits."""
        return self._state_action[self._n_state :] * self.force_limits

    @property
    def held_force(self) -> np.ndarray:
        """The force (N) delivered at the current time: held over the step that ended now."""
        return self._held_force.copy()

    def _draw_motion(self) -> Load:
        if self.motions:
            return self.motions[int(self.np_random.integers(len(self.motions)))]
        return generate(self.experiment.excitation.generator, self.np_random, self.building)

    def _prepare(self, grid: LoadGrid) -> None:
        """[x_{k+1} | outputs_{k+1}] = [x_k | action_k] @ transition + forcing[k], u = action * limit; with
        the plant's own integrator x_{k+1} comes from it and the outputs are linear in x_{k+1} and u."""
        self._n_steps = grid.n_steps
        self.sampled = self.plant.sampled(grid.substeps)
        self._forcing = self.sampled.forcing(grid, self._outputs.c, self._outputs.load)
        if self.plant.integrator is None:
            self._transition = self.sampled.transition(self._outputs.c, self._outputs.d)
            self._advance = self._advance_linear
        else:
            self._windows, self._load_windows = grid.step_windows()
            self._output_ct = self._outputs.c.T.copy()
            self._output_dt = (self._outputs.d * self.force_limits).T.copy()
            self._advance = self._advance_nonlinear

    def _advance_linear(self, k: int, clipped: np.ndarray) -> np.ndarray:
        outputs = self._state_action @ self._transition
        outputs += self._forcing[k]
        return outputs

    def _advance_nonlinear(self, k: int, clipped: np.ndarray) -> np.ndarray:
        state = self._state_action[: self._n_state]
        if self._load_windows is None:
            state = self.plant.integrator.step(state, clipped, self._windows[k], self.control_dt)
        else:  # floor forces: a plant that takes them in its own step (end-stops)
            state = self.plant.integrator.step(
                state, clipped, self._windows[k], self.control_dt, floor_forces=self._load_windows[k]
            )
        return np.concatenate([state, state @ self._output_ct + clipped @ self._output_dt]) + self._forcing[k]

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        if self._randomization is not None:
            drawn = draw_plant(self._randomization, self.experiment.plant, self.np_random)
            self._use_plant(Plant(self.experiment.model_copy(update={"plant": drawn})))
        motion = (options or {}).get("motion") or self._draw_motion()
        self.motion = motion
        grid = on_control_grid(motion, self.control_dt)
        self._prepare(grid)
        self.floor_forces = grid.forces_at_steps
        self.ground_samples = grid.ground_at_steps
        self._term_factors = self._outputs.term_factors(self.ground_samples)
        readings = noisy_readings(self.plant, self.ground_samples, self.np_random)
        self._forcing[:, self._n_state :][:, self._outputs.readings] += readings[1:]
        self._k = 0
        self._state_action[:] = 0.0
        self._held_force[:] = 0.0
        self._previous_action = np.zeros(self.building.n_actuators)
        if self.supervisor is not None:
            self.supervisor.reset()
        self.layout.start(self._observation[None], readings[:1])
        if self.twin is not None:
            self.twin.reset()
        if self.kalman is not None:
            self._estimate = np.zeros(self.kalman.size)
            self._previous_ground = 0.0
            self._update_estimate(readings[0], self._previous_action)
        return self._observation.copy(), {"motion": motion.name, "steps": self._n_steps}

    def _update_estimate(self, readings: np.ndarray, held_action: np.ndarray) -> None:
        """The Kalman estimate at the new scaled readings (ground last), into the observation."""
        self._estimate = update_on_block(
            self._filter_matrices,
            self.layout,
            self._estimate,
            readings,
            held_action=held_action,
            previous_ground=self._previous_ground,
        )
        self._previous_ground = readings[-1]
        self._observation[self.layout.estimate] = self.layout.scaled_estimate(self._estimate)
        if self.twin is not None:
            self._observation[self.layout.twin] = self.layout.scaled_twin(
                *self.twin.observe(self._estimate[None])
            )[0]

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        k = self._k
        if k >= self._n_steps:
            raise RuntimeError("step() called after the episode ended; call reset()")
        state_action, n_state, rows = self._state_action, self._n_state, self._outputs
        clipped = state_action[n_state:]
        clipped[:] = action
        np.minimum(clipped, 1.0, out=clipped)
        np.maximum(clipped, -1.0, out=clipped)
        if self.supervisor is not None:
            self.supervisor(self._observation[None], clipped[None])
        if self.twin is not None:
            self.twin.advance(clipped[None])
        new = self._advance(k, clipped)
        state_action[:n_state] = new[:n_state]
        outputs = new[n_state:]
        self._k = k = k + 1

        observation = self._observation
        self.layout.advance(observation[None], outputs[rows.readings][None], clipped[None])
        if self.kalman is not None:
            self._update_estimate(outputs[rows.readings], clipped)

        terms = rows.reward_terms(outputs[rows.reward], clipped, self._previous_action)
        self._previous_action[:] = clipped
        info: dict[str, Any] = dict(zip(rows.reward_names, terms.tolist(), strict=True))
        info["drift"] = outputs[rows.drift]
        info["absolute_acceleration"] = outputs[rows.acceleration]
        info["base_shear"] = outputs[rows.base_shear]
        self._held_force[:] = outputs[rows.force]
        info["force"] = self._held_force.copy()
        info["time"] = k * self.control_dt
        return observation.copy(), -float(terms @ self._term_factors), False, k >= self._n_steps, info


def rollout(env: BuildingEnv, motion: Load, controller: Controller, seed: int = 0) -> tuple[Response, float]:
    """Run `controller` on `motion` in `env` (sensor noise seeded by `seed`).

    Returns the whole response (from the plant's own outputs) and the episode's total reward.
    """
    observation, info = env.reset(seed=seed, options={"motion": motion})
    controller.reset()
    n_steps = info["steps"]
    states = np.zeros((n_steps + 1, env.plant.n_state))
    commands = np.zeros((n_steps + 1, env.building.n_actuators))
    total_reward = 0.0
    for k in range(1, n_steps + 1):
        observation, reward, _, _, _ = env.step(controller.act(observation))
        total_reward += reward
        states[k] = env.plant_state
        commands[k] = env.command
    time = np.arange(n_steps + 1) * env.control_dt
    return env.sampled.response(
        states, commands, time, ground=env.ground_samples, floor_forces=env.floor_forces
    ), total_reward
