"""The batched training vector env: every training building in one `BuildingBatch`.

A stable-baselines3 `VecEnv` with the observations, rewards, resets and plant draws of a
`DummyVecEnv` of `n_envs` `BuildingEnv(plant, randomize=True)` (each wrapped as a residual on
the prior when there is one), env i seeded with seed + i, but stepped in one numpy call per step
instead of one Python `step()` per env. An episode ends at the end of its motion (truncation);
the env restarts at once and the info holds `terminal_observation` and `TimeLimit.truncated`.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from stable_baselines3.common.vec_env import VecEnv

from rlcontroller.control.controllers import LQGPrior, residual_action
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.batch import BuildingBatch


class BatchedVecEnv(VecEnv):
    """`n_envs` buildings of `plant` stepped as one; `prior` makes the actions residuals on it."""

    def __init__(self, plant: Plant, n_envs: int, prior: LQGPrior | None = None) -> None:
        self.plant = plant
        self.batch = BuildingBatch(plant, n_envs, randomize=True)
        self.prior = prior
        self.render_mode = None
        self._generators: list[np.random.Generator | None] = [None] * n_envs
        self._actions = np.zeros((n_envs, plant.building.n_actuators))
        observation_space = gym.spaces.Box(-np.inf, np.inf, shape=(plant.layout.size,), dtype=np.float32)
        action_space = gym.spaces.Box(-1.0, 1.0, shape=(plant.building.n_actuators,), dtype=np.float32)
        super().__init__(n_envs, observation_space, action_space)

    def _start(self, env: int) -> None:
        if self._seeds[env] is not None or self._generators[env] is None:
            self._generators[env] = seeding.np_random(self._seeds[env])[0]
        self.batch.start(env, self._generators[env])
        self.reset_infos[env] = {"steps": int(self.batch.steps[env])}

    def reset(self) -> np.ndarray:
        for env in range(self.num_envs):
            self._start(env)
        self._reset_seeds()
        self._reset_options()
        return self.batch.observations.copy()

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self):
        actions = self._actions
        if self.prior is not None:
            actions = residual_action(actions, self.prior(self.batch.observations))
        observations, rewards, ended = self.batch.step(actions)
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        for env in np.flatnonzero(ended):
            infos[env] = {"terminal_observation": observations[env].copy(), "TimeLimit.truncated": True}
            self._start(env)
        return self.batch.observations.copy(), rewards.astype(np.float32), ended.copy(), infos

    def close(self) -> None:
        pass

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        value = getattr(self, attr_name) if attr_name == "render_mode" else getattr(self.batch, attr_name)
        return [value] * len(self._get_indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        raise AttributeError(f"BatchedVecEnv: the buildings' {attr_name!r} cannot be set one by one")

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs) -> list[Any]:
        raise AttributeError(f"BatchedVecEnv: no per-building method {method_name!r}")

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper], indices=None) -> list[bool]:
        return [False] * len(self._get_indices(indices))
