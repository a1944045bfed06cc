"""The learner: algorithm, policy network, schedule, `rlc tune`'s search space, and what each learner's
constructor takes (`LEARNER_KWARGS`, checked at loading by `learner_checks.check_algorithm`)."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import (
    Field,
    model_validator,
)

from rlcontroller.bounds import MAX_ENVS, MAX_HORIZON, MAX_TOTAL_STEPS
from rlcontroller.config.base import StrictModel


class PolicyConfig(StrictModel):
    """The MLP; `net_arch` are the hidden layers of actor and critic, `actor_arch` (if given) the
    actor's own ([]: a linear actor, the action mean a linear map of the observation);
    `log_std_init` sets the initial exploration noise of Gaussian policies (log of std); `odd`
    makes the action odd in the observation, a(-o) = -a(o) and a(0) = 0 (PPO, A2C, RandomSearch, and SAC or
    TQC with `backend: sbx`)."""

    net_arch: list[Annotated[int, Field(ge=1, le=4096)]] = Field([128, 128, 128], min_length=1, max_length=16)
    actor_arch: list[Annotated[int, Field(ge=1, le=4096)]] | None = Field(None, max_length=16)
    activation: Literal["relu", "tanh", "elu", "leaky_relu", "gelu"] = "relu"
    log_std_init: Annotated[float, Field(ge=-20.0, le=5.0)] | None = None
    odd: bool = False


class SearchRange(StrictModel):
    """One tuned setting of `rlc tune`: a number in [low, high] (log-uniform with `log: true`, whole
    numbers with `integer: true`), or one of `choices` (any YAML values, lists included)."""

    low: float | None = Field(default=None, ge=-1.0e12, le=1.0e12)
    high: float | None = Field(default=None, ge=-1.0e12, le=1.0e12)
    log: bool = False
    integer: bool = False
    choices: list[Any] | None = Field(default=None, min_length=1, max_length=1000)

    @model_validator(mode="after")
    def _one_kind(self) -> SearchRange:
        if self.choices is not None:
            if self.low is not None or self.high is not None:
                raise ValueError("give either choices or low and high, not both")
            return self
        if self.low is None or self.high is None:
            raise ValueError("expected low and high (or choices)")
        if self.low >= self.high:
            raise ValueError(f"expected low < high, got low {self.low:g}, high {self.high:g}")
        if self.log and self.low <= 0.0:
            raise ValueError("a log range needs low > 0")
        if self.integer and not (self.low.is_integer() and self.high.is_integer()):
            raise ValueError("an integer range needs whole-number bounds")
        return self


class AlgorithmConfig(StrictModel):
    """The learner (a stable-baselines3 one; `RandomSearch`: random search with common random
    numbers on a linear policy, odd or with `policy.odd: false` affine,
    `rlcontroller.learning.random_search`; or `DAgger`: an MLP taught to act as MPC,
    `rlcontroller.learning.imitation`), its keyword arguments and the training schedule.

    `kwargs` go to the learner's constructor (learning_rate, batch_size, buffer_size, train_freq,
    gradient_steps, n_steps, ...); `policy` sets the MLP. `n_envs` environments run as one batch
    (`vec_env: batched`, the default: `simulation.batch` stepped as one), or in a dummy (same
    process) or subprocess vector env. `normalize_observations` and `normalize_rewards` add a
    VecNormalize whose statistics are checkpointed. With `residual_lqg` the policy's action is added
    to the action of LQG (+ measured ground, or + ground model with `sensors.ground_model`) computed
    from the observation's state estimate (needs `sensors.state_estimate`): the agent learns a
    correction to LQG. `checkpoint_every` and
    `eval_every` count environment steps; `best_model` is the validation with the highest reward, or
    with `select_by: J1` the lowest mean J1 (every validation motion counts alike, weak or strong,
    where the reward is dominated by the strongest), with `J1+J2` the lowest mean J1 + mean J2 (drift
    and floor acceleration weighed alike, as the safety check gates both), with `standard` the fewest
    motions worse than the building failed safe (the safety check's own measure), then the lowest J1 + J2.
    `backend: sbx` trains SAC, TQC or TD3 with sbx-rl (Stable Baselines Jax: the same interface, the updates
    compiled by JAX; the `fast` extra), about 2x the steps/s of stable-baselines3's torch learners on the
    paper's small networks (docs/training.md); its run folders hold no pickle (`learning.jax_learners`).
    `learning_rate_schedule: linear` lowers `kwargs.learning_rate` linearly to 0 at `total_steps` (the
    zoo's `lin_` schedule; a run stopped by `--time-limit` ends above 0). `exploration_noise` (TD3 and DDPG):
    the standard deviation of Gaussian noise added to their deterministic action (in [-1, 1] units) while
    they collect (stable-baselines3's `NormalActionNoise`); without it they explore only before
    `learning_starts`.
    `search` is `rlc tune`'s
    search space: dotted paths into the experiment (`algorithm.kwargs.learning_rate`,
    `algorithm.policy.net_arch`, `reward.terms.0.weight`, ...) and their ranges; training ignores it.
    """

    name: Literal["SAC", "PPO", "TD3", "DDPG", "A2C", "TQC", "RandomSearch", "DAgger"] = "SAC"
    backend: Literal["sb3", "sbx"] = "sb3"
    total_steps: Annotated[int, Field(ge=1, le=MAX_TOTAL_STEPS)] = 1_500_000
    n_envs: Annotated[int, Field(ge=1, le=MAX_ENVS)] = 1
    vec_env: Literal["batched", "dummy", "subproc"] = "batched"
    policy: PolicyConfig = PolicyConfig()
    kwargs: dict[str, Any] = Field(default_factory=lambda: {"gamma": 0.999})
    normalize_observations: bool = False
    normalize_rewards: bool = False  # scale rewards by a running std of the return (training only)
    residual_lqg: bool = False
    torch_threads: Annotated[int, Field(ge=1, le=256)] = 1
    checkpoint_every: Annotated[int, Field(ge=1, le=MAX_TOTAL_STEPS)] = 50_000
    eval_every: Annotated[int, Field(ge=1, le=MAX_TOTAL_STEPS)] = 25_000
    select_by: Literal["reward", "J1", "J1+J2", "standard"] = "reward"
    learning_rate_schedule: Literal["constant", "linear"] = "constant"
    exploration_noise: Annotated[float, Field(ge=0.0, le=1.0)] = 0.0
    search: dict[str, SearchRange] = Field(default_factory=dict, max_length=100)


# The keyword arguments each learner's constructor takes (stable-baselines3 2.x and
# `learning.random_search.RandomSearch`), so that an experiment is checked completely when it is loaded,
# without importing torch. tests/config/test_learning.py compares this table with the installed
# learners' signatures.
_COMMON = {"policy", "env", "learning_rate", "policy_kwargs", "seed", "device", "tensorboard_log", "verbose"}
_COMMON |= {"_init_setup_model"}
_ON_POLICY = _COMMON | {
    "n_steps",
    "gamma",
    "gae_lambda",
    "ent_coef",
    "vf_coef",
    "max_grad_norm",
    "use_sde",
    "sde_sample_freq",
    "rollout_buffer_class",
    "rollout_buffer_kwargs",
    "normalize_advantage",
    "stats_window_size",
}
_OFF_POLICY = _COMMON | {
    "buffer_size",
    "learning_starts",
    "batch_size",
    "tau",
    "gamma",
    "train_freq",
    "gradient_steps",
    "action_noise",
    "replay_buffer_class",
    "replay_buffer_kwargs",
    "optimize_memory_usage",
    "n_steps",
}
LEARNER_KWARGS = {
    "PPO": _ON_POLICY | {"batch_size", "n_epochs", "clip_range", "clip_range_vf", "target_kl"},
    "A2C": _ON_POLICY | {"rms_prop_eps", "use_rms_prop"},
    "SAC": _OFF_POLICY
    | {
        "ent_coef",
        "target_update_interval",
        "target_entropy",
        "use_sde",
        "sde_sample_freq",
        "use_sde_at_warmup",
    }
    | {"stats_window_size"},
    "TD3": _OFF_POLICY | {"policy_delay", "target_policy_noise", "target_noise_clip", "stats_window_size"},
    "DDPG": _OFF_POLICY,
    "RandomSearch": _COMMON | {"n_delta", "n_motions", "delta_std", "initial_bias", "objective"},
    "DAgger": _COMMON | {"horizon", "n_motions", "epochs", "batch_size", "max_samples"},
}
# sbx-rl 0.28's learners (`backend: sbx`): SB3's off-policy arguments less optimize_memory_usage, plus a
# critic learning rate, delayed actor updates and parameter resets.
_JAX_OFF_POLICY = (_OFF_POLICY - {"optimize_memory_usage"}) | {
    "qf_learning_rate",
    "policy_delay",
    "param_resets",
}
_JAX_OFF_POLICY |= {"stats_window_size"}
_JAX_ENTROPY = {"ent_coef", "target_entropy", "use_sde", "sde_sample_freq", "use_sde_at_warmup"}
JAX_LEARNER_KWARGS = {
    "SAC": _JAX_OFF_POLICY | _JAX_ENTROPY,
    "TQC": _JAX_OFF_POLICY | _JAX_ENTROPY | {"top_quantiles_to_drop_per_net"},
    "TD3": _JAX_OFF_POLICY | {"target_policy_noise", "target_noise_clip"},
}
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
# RandomSearch: what f is (its module docstring)
CHOICE_KWARGS = {"objective": ("return", "standard", "peaks")}
# sbx: the time steps (whole numbers >= 0) after which its networks are reset
STEP_LIST_KWARGS = {"param_resets"}
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
    "initial_bias": (-1.0, 1.0, False),
    "horizon": (1, MAX_HORIZON, True),
    "epochs": (1, 10_000, True),
    "max_samples": (1, 10_000_000, True),
    "policy_delay": (1, 2**31, True),
    "qf_learning_rate": (0.0, 1.0, False),
    "learning_rate": (0.0, 1.0, False),
}
