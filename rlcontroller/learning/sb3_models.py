"""stable-baselines3 models as controllers: the learner registry, the residual wrapper of training,
and the conversion of a trained model into the policy data of `control.policy_file`.

A residual policy's action is added to its prior's (LQG's) action, both clipped to [-1, 1]:
`control.controllers.residual_action` is that rule, used in training (the `ResidualAction`
wrapper) and in evaluation (`control.policy_controller.PolicyController`) alike.

Opening a stable-baselines3 zip unpickles its author's objects (it can run any code): this module
does it only for one's own runs (training, validation, `--resume`) and for `rlc convert
--trust-pickle`, never when a controller is evaluated, checked or exported.
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym

from rlcontroller.config import ConfigError, load_experiment
from rlcontroller.control.controllers import LQGPrior, residual_action
from rlcontroller.control.networks import Normalizer
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.control.policy_file import write_policy
from rlcontroller.learning.actor import actor_of
from rlcontroller.physics.plant import Plant


def algorithm_class(name: str, backend: str = "sb3") -> type:
    """The learner class called `name`: a stable-baselines3 one (SAC, PPO, ...), RandomSearch or DAgger, or
    with `backend` sbx, sbx-rl's."""
    if backend == "sbx":
        from rlcontroller.learning.jax_learners import jax_algorithm_class

        return jax_algorithm_class(name)
    if name == "DAgger":
        from rlcontroller.learning.imitation import DAgger

        return DAgger
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


def policy_controller(model, prior: LQGPrior | None, normalize=None, name: str = "RL") -> PolicyController:
    """The deterministic policy of a stable-baselines3 model (and its VecNormalize, if any) as numpy
    data: exactly what `write_policy` saves and `read_policy` reads back."""
    actor = actor_of(model)
    if actor is None:
        raise ConfigError(
            f"{type(model).__name__}: only MLP policies on flat observations can be saved as data"
        )
    normalizer = None
    if normalize is not None and normalize.norm_obs:
        statistics = normalize.obs_rms
        normalizer = Normalizer(
            statistics.mean.copy(), statistics.var.copy(), normalize.epsilon, normalize.clip_obs
        )
    steps, algorithm = int(model.num_timesteps), type(model).__name__
    return PolicyController(actor, normalizer, prior, name, steps=steps, algorithm=algorithm)


def convert(folder: Path) -> list[Path]:
    """Write the policy data of every stable-baselines3 model (best, final) in `folder`: this opens
    pickles, so only for folders whose author is trusted (`rlc convert --trust-pickle`)."""
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    from rlcontroller.learning.env import BuildingEnv

    plant = Plant(load_experiment(folder / "config.yaml", self_contained=True))
    experiment = plant.experiment
    prior = LQGPrior.design(plant) if experiment.algorithm.residual_lqg else None
    written = []
    for model_name in ("best", "final"):
        path = folder / f"{model_name}_model.zip"
        if not path.is_file():
            continue
        statistics = path.with_name(path.stem + ".vecnormalize.pkl")
        try:
            model = algorithm_class(experiment.algorithm.name).load(path, device="cpu")
            normalize = None
            if statistics.is_file():
                normalize = VecNormalize.load(str(statistics), DummyVecEnv([lambda: BuildingEnv(plant)]))
        except Exception as error:  # a damaged file: zip, pickle or torch errors of any kind
            detail = (str(error).splitlines() or [""])[0][:120] or type(error).__name__
            raise ConfigError(
                f"{path}: cannot load the saved model ({type(error).__name__}: {detail})"
            ) from None
        written.append(write_policy(policy_controller(model, prior, normalize), plant, folder, model_name))
    if not written:
        raise ConfigError(f"{folder}: no best_model.zip or final_model.zip to convert")
    return written
