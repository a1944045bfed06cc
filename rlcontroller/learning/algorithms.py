"""The stable-baselines3 learners: keyword-argument checks, the training vector env, the model.

`algorithm.kwargs` of an experiment go to the learner's constructor; keys it does not take, keys
rlc sets itself and out-of-range values of the common numeric ones are refused with one line.
"""

from __future__ import annotations

import functools
import inspect
import math
from pathlib import Path
from typing import Any

import gymnasium as gym

from rlcontroller.config import ConfigError, Experiment, location
from rlcontroller.control.controllers import LQGPrior
from rlcontroller.learning.env import BuildingEnv
from rlcontroller.learning.policy import ResidualAction, algorithm_class
from rlcontroller.learning.vec_env import BatchedVecEnv
from rlcontroller.physics.plant import Plant

ACTIVATIONS = {"relu": "ReLU", "tanh": "Tanh", "elu": "ELU", "leaky_relu": "LeakyReLU", "gelu": "GELU"}
RESERVED_KWARGS = {
    "policy",
    "env",
    "policy_kwargs",
    "seed",
    "device",
    "tensorboard_log",
    "verbose",
    "_init_setup_model",
}
# (low, high, integer) for the learners' common numeric keyword arguments.
NUMERIC_KWARGS = {
    "gamma": (0.0, 1.0, False),
    "tau": (0.0, 1.0, False),
    "gae_lambda": (0.0, 1.0, False),
    "batch_size": (1, 2**31, True),
    "buffer_size": (1, 2**40, True),
    "n_steps": (1, 2**31, True),
    "n_epochs": (1, 2**31, True),
    "learning_starts": (0, 2**40, True),
    "n_delta": (1, 10_000, True),
    "n_motions": (1, 10_000, True),
    "delta_std": (1e-12, 1e6, False),
}


def check_algorithm(experiment: Experiment) -> None:
    """Refuse keyword arguments the learner does not take, naming the file and key."""
    algorithm = experiment.algorithm
    file, prefix = experiment.origin("algorithm")
    if algorithm.policy.odd and algorithm.name not in ("PPO", "A2C", "RandomSearch"):
        raise ConfigError(
            f"{location(file, prefix, 'policy.odd')}: only for PPO, A2C and RandomSearch, not {algorithm.name}"
        )
    if algorithm.name == "RandomSearch":
        _check_random_search(experiment)
    if algorithm.policy.odd and algorithm.normalize_observations:
        raise ConfigError(
            f"{location(file, prefix, 'policy.odd')}: needs normalize_observations: false "
            "(centring the observation breaks a(-o) = -a(o)); scale the readings in the sensors part instead"
        )
    accepted = set(inspect.signature(algorithm_class(algorithm.name).__init__).parameters) - {"self"}
    for key, value in algorithm.kwargs.items():
        where = location(file, prefix, f"kwargs.{key}")
        if key in RESERVED_KWARGS:
            raise ConfigError(f"{where}: set by rlc (use 'policy:', 'seed' or --device instead)")
        if key not in accepted:
            options = ", ".join(sorted(accepted - RESERVED_KWARGS))
            raise ConfigError(f"{where}: not a keyword argument of {algorithm.name}; expected one of: {options}")
        if isinstance(value, float) and not math.isfinite(value):
            raise ConfigError(f"{where}: expected a finite number, got {value!r}")
        if key in NUMERIC_KWARGS and not _in_range(value, *NUMERIC_KWARGS[key]):
            low, high, integer = NUMERIC_KWARGS[key]
            kind = "an integer" if integer else "a number"
            raise ConfigError(f"{where}: expected {kind} in [{low}, {high}], got {value!r}")


def _check_random_search(experiment: Experiment) -> None:
    """RandomSearch learns a linear odd actor (a residual with `residual_lqg`) on the batched env's plant."""
    algorithm = experiment.algorithm
    file, prefix = experiment.origin("algorithm")
    if algorithm.policy.actor_arch != [] or not algorithm.policy.odd:
        raise ConfigError(
            f"{location(file, prefix, 'policy')}: RandomSearch trains a linear odd actor; "
            "expected actor_arch: [] and odd: true"
        )
    refused = {
        "normalize_rewards": (algorithm.normalize_rewards, "its objective, the log of the return, is scale-free"),
        "vec_env": (algorithm.vec_env != "batched", "it runs on the batched env's plant; expected batched"),
    }
    for key, (wrong, why) in refused.items():
        if wrong:
            raise ConfigError(f"{location(file, prefix, key)}: not for RandomSearch ({why})")


def _in_range(value: Any, low: float, high: float, integer: bool) -> bool:
    if isinstance(value, bool) or not isinstance(value, int | float) or (integer and not isinstance(value, int)):
        return False
    return low <= value <= high


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
    gamma = experiment.algorithm.kwargs.get("gamma")
    if gamma is None:
        gamma = inspect.signature(algorithm_class(experiment.algorithm.name).__init__).parameters["gamma"].default
    return float(gamma)


def build_model(experiment: Experiment, vec_env, seed: int, device: str, tensorboard: Path | None):
    import torch

    algorithm = experiment.algorithm
    check_algorithm(experiment)
    net_arch: list[int] | dict[str, list[int]] = list(algorithm.policy.net_arch)
    if algorithm.name == "RandomSearch":
        net_arch = {"pi": [], "vf": []}  # no critic is trained
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
    try:
        return algorithm_class(algorithm.name)(
            policy,
            vec_env,
            policy_kwargs=policy_kwargs,
            seed=seed,
            device=device,
            tensorboard_log=str(tensorboard) if tensorboard else None,
            verbose=0,
            **algorithm.kwargs,
        )
    except (TypeError, ValueError, AssertionError) as error:
        file, prefix = experiment.origin("algorithm")
        message = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise ConfigError(f"{location(file, prefix, 'kwargs')}: {algorithm.name} refused them: {message}") from None
