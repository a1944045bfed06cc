"""The learner's settings against the learner: keyword arguments each learner's constructor takes, their
ranges and choices, and what RandomSearch, DAgger and the sbx backend refuse (without importing torch or
JAX)."""

from __future__ import annotations

import difflib
import math
from typing import Any

from rlcontroller.config.base import ConfigError, location
from rlcontroller.config.experiment import Experiment
from rlcontroller.config.learning import (
    CHOICE_KWARGS,
    JAX_LEARNER_KWARGS,
    LEARNER_KWARGS,
    NUMERIC_KWARGS,
    RESERVED_KWARGS,
    STEP_LIST_KWARGS,
)


def check_algorithm(experiment: Experiment) -> None:
    """Refuse keyword arguments the learner does not take, naming the file and key."""
    algorithm = experiment.algorithm
    file, prefix = experiment.origin("algorithm")
    odd_learners = ("SAC", "TQC") if algorithm.backend == "sbx" else ("PPO", "A2C", "RandomSearch")
    if algorithm.policy.odd and algorithm.name not in odd_learners:
        raise ConfigError(
            f"{location(file, prefix, 'policy.odd')}: only for PPO, A2C, RandomSearch, and SAC or TQC with "
            f"backend: sbx, not {algorithm.name}"
            + (" with backend: sbx" if algorithm.backend == "sbx" else "")
        )
    batched = algorithm.vec_env == "batched" and algorithm.name not in ("RandomSearch", "DAgger")
    if experiment.reward.baseline != "none" and not batched:
        reward_file, reward_prefix = experiment.origin("reward")
        raise ConfigError(
            f"{location(reward_file, reward_prefix, 'baseline')}: taken by a learner stepping the batched "
            f"vector env (algorithm.vec_env: batched; not {algorithm.name} with vec_env: {algorithm.vec_env})"
        )
    if algorithm.name == "RandomSearch":
        _check_random_search(experiment)
    if algorithm.name == "DAgger":
        _check_dagger(experiment)
    if algorithm.policy.odd and algorithm.normalize_observations:
        raise ConfigError(
            f"{location(file, prefix, 'policy.odd')}: needs normalize_observations: false "
            "(centring the observation breaks a(-o) = -a(o)); scale the readings in the sensors part instead"
        )
    if algorithm.exploration_noise and algorithm.name not in ("TD3", "DDPG"):
        raise ConfigError(
            f"{location(file, prefix, 'exploration_noise')}: only for TD3 and DDPG (deterministic actors), "
            f"not {algorithm.name}"
        )
    if "action_noise" in algorithm.kwargs:
        raise ConfigError(
            f"{location(file, prefix, 'kwargs.action_noise')}: an object, not a value a file can hold; use "
            "algorithm.exploration_noise (the standard deviation of Gaussian noise on the action)"
        )
    if algorithm.backend == "sbx":
        _check_jax_backend(experiment)
    elif algorithm.name == "TQC":
        raise ConfigError(f"{location(file, prefix, 'name')}: TQC is an sbx learner; add backend: sbx")
    accepted = (JAX_LEARNER_KWARGS if algorithm.backend == "sbx" else LEARNER_KWARGS)[algorithm.name]
    for key, value in algorithm.kwargs.items():
        where = location(file, prefix, f"kwargs.{key}")
        if key in RESERVED_KWARGS:
            raise ConfigError(f"{where}: set by rlc (use 'policy:', 'seed' or --device instead)")
        if key not in accepted:
            options = sorted(accepted - RESERVED_KWARGS)
            close = difflib.get_close_matches(key, options, n=1, cutoff=0.6)
            hint = f"did you mean {close[0]!r}?" if close else f"expected one of: {', '.join(options)}"
            raise ConfigError(f"{where}: not a keyword argument of {algorithm.name}; {hint}")
        if isinstance(value, float) and not math.isfinite(value):
            raise ConfigError(f"{where}: expected a finite number, got {value!r}")
        if key in NUMERIC_KWARGS and not _in_range(value, *NUMERIC_KWARGS[key]):
            low, high, integer = NUMERIC_KWARGS[key]
            kind = "an integer" if integer else "a number"
            raise ConfigError(f"{where}: expected {kind} in [{low}, {high}], got {value!r}")
        if key in CHOICE_KWARGS and value not in CHOICE_KWARGS[key]:
            raise ConfigError(f"{where}: expected one of {', '.join(CHOICE_KWARGS[key])}, got {value!r}")
        steps = isinstance(value, list) and all(_in_range(step, 0, 2**40, True) for step in value)
        if key in STEP_LIST_KWARGS and not steps:
            raise ConfigError(f"{where}: expected a list of time steps (whole numbers >= 0), got {value!r}")


def _check_jax_backend(experiment: Experiment) -> None:
    """sbx-rl learns SAC, TQC and TD3 with squashed MLP actors, which save as data; it has no initial log
    std."""
    algorithm = experiment.algorithm
    file, prefix = experiment.origin("algorithm")
    if algorithm.name not in JAX_LEARNER_KWARGS:
        expected = ", ".join(JAX_LEARNER_KWARGS)
        raise ConfigError(f"{location(file, prefix, 'backend')}: sbx learns {expected}, not {algorithm.name}")
    if algorithm.policy.log_std_init is not None:
        raise ConfigError(
            f"{location(file, prefix, 'policy.log_std_init')}: not with backend: sbx (its SAC has none)"
        )


def _check_random_search(experiment: Experiment) -> None:
    """RandomSearch learns an actor (linear or a network; odd, or affine with `odd: false`; a residual with
    `residual_lqg`) on the batched env's plant."""
    algorithm = experiment.algorithm
    file, prefix = experiment.origin("algorithm")
    refused = {
        "normalize_rewards": (
            algorithm.normalize_rewards,
            "its objective, the log of the return, is scale-free",
        ),
        "vec_env": (algorithm.vec_env != "batched", "it runs on the batched env's plant; expected batched"),
    }
    for key, (wrong, why) in refused.items():
        if wrong:
            raise ConfigError(f"{location(file, prefix, key)}: not for RandomSearch ({why})")


def _check_dagger(experiment: Experiment) -> None:
    """DAgger imitates MPC on raw observations (its data set holds them as the env gives them), on the batched
    env's plant."""
    algorithm = experiment.algorithm
    file, prefix = experiment.origin("algorithm")
    refused = {
        "normalize_observations": (algorithm.normalize_observations, "its data set keeps raw observations"),
        "normalize_rewards": (algorithm.normalize_rewards, "it learns from MPC's actions, not from rewards"),
        "vec_env": (algorithm.vec_env != "batched", "it runs on the batched env's plant; expected batched"),
    }
    for key, (wrong, why) in refused.items():
        if wrong:
            raise ConfigError(f"{location(file, prefix, key)}: not for DAgger ({why})")


def _in_range(value: Any, low: float, high: float, integer: bool) -> bool:
    wrong_type = isinstance(value, bool) or not isinstance(value, int if integer else int | float)
    return not wrong_type and low <= value <= high
