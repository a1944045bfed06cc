"""Saved policies: loading a run's model, the residual on a prior, and the policy as a controller.

A residual policy's action is added to its prior's (LQG's) action, both clipped to [-1, 1]:
`control.controllers.residual_action` is that rule, used in training (the `ResidualAction`
wrapper) and in evaluation (`PolicyController`) alike.
"""

from __future__ import annotations

import functools
from pathlib import Path

import gymnasium as gym
import numpy as np

from rlcontroller.config import ConfigError, load_experiment
from rlcontroller.control.controllers import LQGPrior, residual_action
from rlcontroller.learning.actor import actor_of
from rlcontroller.learning.env import BuildingEnv
from rlcontroller.physics.plant import Plant


def algorithm_class(name: str) -> type:
    """The learner class called `name`: a stable-baselines3 one (SAC, PPO, ...) or RandomSearch."""
    if name == "RandomSearch":
        from rlcontroller.learning.random_search import RandomSearch

        return RandomSearch
    import stable_baselines3

    return getattr(stable_baselines3, name)


class ResidualAction(gym.ActionWrapper):
    """The agent's action is added to a prior controller's action computed from the observation."""

    def __init__(self, env: gym.Env, prior) -> None:
        super().__init__(env)
        self.prior = prior
        self._observation = None

    def reset(self, **kwargs):
        observation, info = self.env.reset(**kwargs)
        self._observation = observation
        return observation, info

    def step(self, action):
        observation, reward, terminated, truncated, info = self.env.step(self.action(action))
        self._observation = observation
        return observation, reward, terminated, truncated, info

    def action(self, action):
        return residual_action(action, self.prior(self._observation))


class PolicyController:
    """A trained stable-baselines3 policy as a controller: deterministic actions in [-1, 1], for one
    observation or a batch (one forward pass).

    `normalize` is the run's observation normaliser (a VecNormalize), if it used one; `prior`
    maps an observation to the action the policy's output is added to (residual policies);
    `source` names the saved model file, for reports.
    """

    def __init__(self, model, normalize=None, name: str = "RL", prior=None, source: str = "") -> None:
        self.model = model
        self.normalize = normalize
        self.name = name
        self.prior = prior
        self.source = source
        self.actor = actor_of(model)

    @classmethod
    def load(cls, model_path: Path, name: str = "RL") -> PolicyController:
        model, normalize, prior = load_policy(model_path)
        return cls(model, normalize, name, prior, source=str(model_path))

    def reset(self) -> None:
        pass

    def act(self, observation: np.ndarray) -> np.ndarray:
        raw = observation
        if self.normalize is not None:
            observation = self.normalize.normalize_obs(observation)
        action = self._deterministic(observation)
        if self.prior is None:
            return np.clip(action, -1.0, 1.0)
        return residual_action(action, self.prior(raw))

    def _deterministic(self, observation: np.ndarray) -> np.ndarray:
        """The policy's deterministic action: through its actor's layers in numpy when it is a plain
        MLP (the same numbers as `predict` to float32 rounding, without torch's per-call overhead),
        else through `predict`."""
        if self.actor is not None:
            return self.actor(observation)
        return self.model.predict(observation, deterministic=True)[0]


def load_policy(model_path: Path):
    """A saved model of a run folder, its observation normaliser and its prior (or None), on the CPU."""
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    model_path = Path(model_path)
    plant = Plant(load_experiment(model_path.parent / "config.yaml"))
    experiment = plant.experiment
    statistics = model_path.with_name(model_path.stem + ".vecnormalize.pkl")
    normalize = None
    path = model_path
    try:
        model = algorithm_class(experiment.algorithm.name).load(model_path, device="cpu")
        if statistics.is_file():
            path = statistics
            normalize = VecNormalize.load(str(statistics), DummyVecEnv([functools.partial(BuildingEnv, plant)]))
            normalize.training = False
    except Exception as error:  # a damaged file: zip, pickle or torch errors of any kind
        detail = (str(error).splitlines() or [""])[0][:120] or type(error).__name__
        raise ConfigError(f"{path}: cannot load the saved model ({type(error).__name__}: {detail})") from None
    prior = LQGPrior(plant) if experiment.algorithm.residual_lqg else None
    return model, normalize, prior
