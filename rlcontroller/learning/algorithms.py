"""The stable-baselines3 learners: the training vector env and the model.

`algorithm.kwargs` of an experiment go to the learner's constructor; they were checked when the
experiment was loaded (`config.learner_checks.check_algorithm`).
"""

from __future__ import annotations

import functools
import inspect
from pathlib import Path

import gymnasium as gym

from rlcontroller.config import AlgorithmConfig, ConfigError, Experiment, location
from rlcontroller.control.controllers import LQGPrior
from rlcontroller.learning.env import BuildingEnv
from rlcontroller.learning.sb3_models import ResidualAction, algorithm_class
from rlcontroller.learning.vec_env import BatchedVecEnv
from rlcontroller.physics.plant import Plant

ACTIVATIONS = {"relu": "ReLU", "tanh": "Tanh", "elu": "ELU", "leaky_relu": "LeakyReLU", "gelu": "GELU"}


def make_env(plant: Plant, prior: LQGPrior | None) -> gym.Env:
    """One training env on the plant (randomised per episode if configured), wrapped as a residual on
    the prior if there is one."""
    env = BuildingEnv(plant, randomize=True)
    return env if prior is None else ResidualAction(env, prior)


def make_vec_env(plant: Plant, seed: int):
    """The training vector env with episode statistics: `n_envs` buildings stepped as one batch
    (`vec_env: batched`), or BuildingEnvs in a DummyVecEnv or SubprocVecEnv."""
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecMonitor, VecNormalize

    experiment = plant.experiment
    prior = LQGPrior.design(plant) if experiment.algorithm.residual_lqg else None
    factories = [functools.partial(make_env, plant, prior) for _ in range(experiment.algorithm.n_envs)]
    if experiment.algorithm.vec_env == "batched":
        vec_env = BatchedVecEnv(plant, experiment.algorithm.n_envs, prior)
    elif experiment.algorithm.vec_env == "subproc" and len(factories) > 1:
        vec_env = SubprocVecEnv(factories)
    else:
        vec_env = DummyVecEnv(factories)
    vec_env.seed(seed)
    vec_env = VecMonitor(vec_env)
    algorithm = experiment.algorithm
    if algorithm.normalize_observations or algorithm.normalize_rewards:
        vec_env = VecNormalize(
            vec_env,
            norm_obs=algorithm.normalize_observations,
            norm_reward=algorithm.normalize_rewards,
            gamma=_gamma(experiment),
        )
    return vec_env


def _gamma(experiment: Experiment) -> float:
    """The learner's discount (the return whose spread scales the rewards)."""
    algorithm = experiment.algorithm
    gamma = algorithm.kwargs.get("gamma")
    return float(_default(algorithm, "gamma") if gamma is None else gamma)


def _default(algorithm: AlgorithmConfig, keyword: str):
    """The learner's own default for one keyword argument of its constructor."""
    learner = algorithm_class(algorithm.name, algorithm.backend)
    return inspect.signature(learner.__init__).parameters[keyword].default


def build_model(experiment: Experiment, vec_env, seed: int, device: str, *, tensorboard: Path | None):
    """A new learner on `vec_env`: stable-baselines3's (on `device`), rlc's own, or sbx's (`backend: sbx`)."""
    algorithm = experiment.algorithm
    if algorithm.backend == "sbx":  # JAX's device, not torch's
        from rlcontroller.learning.jax_learners import jax_policy_kwargs

        return _constructed(
            experiment, vec_env, seed, "MlpPolicy", jax_policy_kwargs(experiment), {}, tensorboard
        )
    import torch

    net_arch: list[int] | dict[str, list[int]] = list(algorithm.policy.net_arch)
    if algorithm.name == "RandomSearch":  # no critic is trained; without actor_arch a linear actor
        net_arch = {"pi": list(algorithm.policy.actor_arch or []), "vf": []}
    elif algorithm.name == "DAgger":
        net_arch = {"pi": list(algorithm.policy.actor_arch or algorithm.policy.net_arch), "vf": []}
    elif algorithm.policy.actor_arch is not None:
        critic = "vf" if algorithm.name in ("PPO", "A2C") else "qf"
        net_arch = {"pi": list(algorithm.policy.actor_arch), critic: net_arch}
    policy_kwargs = {
        "net_arch": net_arch,
        "activation_fn": getattr(torch.nn, ACTIVATIONS[algorithm.policy.activation]),
    }
    if algorithm.policy.log_std_init is not None:
        policy_kwargs["log_std_init"] = algorithm.policy.log_std_init
    policy = "MlpPolicy"
    if algorithm.policy.odd:
        from rlcontroller.learning.odd_policy import OddActorCriticPolicy

        policy = OddActorCriticPolicy
    return _constructed(experiment, vec_env, seed, policy, policy_kwargs, {"device": device}, tensorboard)


def _constructed(
    experiment: Experiment, vec_env, seed: int, policy, policy_kwargs: dict, extra: dict, tensorboard
):
    """The learner of the experiment's algorithm and backend; what its constructor refuses is one line."""
    algorithm = experiment.algorithm
    kwargs = dict(algorithm.kwargs)
    if algorithm.learning_rate_schedule == "linear":
        from stable_baselines3.common.utils import LinearSchedule

        start = kwargs["learning_rate"] if "learning_rate" in kwargs else _default(algorithm, "learning_rate")
        kwargs["learning_rate"] = LinearSchedule(start=float(start), end=0.0, end_fraction=1.0)
    if algorithm.exploration_noise:
        import numpy as np
        from stable_baselines3.common.noise import NormalActionNoise

        size = vec_env.action_space.shape[-1]
        kwargs["action_noise"] = NormalActionNoise(np.zeros(size), np.full(size, algorithm.exploration_noise))
    try:
        return algorithm_class(algorithm.name, algorithm.backend)(
            policy,
            vec_env,
            policy_kwargs=policy_kwargs,
            seed=seed,
            tensorboard_log=str(tensorboard) if tensorboard else None,
            verbose=0,
            **extra,
            **kwargs,
        )
    except (TypeError, ValueError, AssertionError) as error:
        file, prefix = experiment.origin("algorithm")
        message = str(error).splitlines()[0] if str(error) else type(error).__name__
        learner = f"sbx's {algorithm.name}" if algorithm.backend == "sbx" else algorithm.name
        raise ConfigError(f"{location(file, prefix, 'kwargs')}: {learner} refused them: {message}") from None
