"""The base of the learners whose iterations simulate whole motions on the batched env's plant
(`RandomSearch`, `DAgger`): a stable-baselines3 `BaseAlgorithm`, so that validation, checkpoints, `--resume`,
the progress bar and saving are those of any run.

A subclass builds its policy and its own state in `_setup_model` (after `_setup_policy_and_plant`) and runs
one iteration in `iterate`, returning the control steps it simulated: `num_timesteps` counts them.
"""

from __future__ import annotations

from typing import Any

from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.callbacks import ProgressBarCallback

from rlcontroller.control.controllers import LQGPrior


class BatchLearner(BaseAlgorithm):
    """A learner that runs iterations of whole simulated motions on the plant of its training env (a
    `BatchedVecEnv`), with the env's LQG prior when the experiment trains a residual."""

    def __init__(
        self,
        policy,
        env,
        learning_rate: float,
        policy_kwargs: dict[str, Any] | None,
        tensorboard_log: str | None,
        seed: int | None,
        device: str,
        verbose: int,
    ) -> None:
        super().__init__(
            policy,
            env,
            learning_rate=learning_rate,
            policy_kwargs=policy_kwargs,
            tensorboard_log=tensorboard_log,
            verbose=verbose,
            device=device,
            seed=seed,
            support_multi_env=True,
        )

    def _setup_policy_and_plant(self) -> None:
        """The policy, the env's plant (None without an env: a model loaded to be read) and the prior."""
        self._setup_lr_schedule()
        self.set_random_seed(self.seed)
        policy = self.policy_class(
            self.observation_space, self.action_space, self.lr_schedule, **self.policy_kwargs
        )
        self.policy = policy.to(self.device)
        self.plant = getattr(self.env.unwrapped, "plant", None) if self.env is not None else None
        residual = self.plant is not None and self.plant.experiment.algorithm.residual_lqg
        self.prior = LQGPrior.design(self.plant) if residual else None

    def _excluded_save_params(self) -> list[str]:
        return [*super()._excluded_save_params(), "plant", "prior"]

    def iterate(self) -> int:
        """One iteration; returns the control steps it simulated."""
        raise NotImplementedError

    def learn(
        self,
        total_timesteps: int,
        *,
        callback=None,
        log_interval: int = 1,
        tb_log_name: str = "",
        reset_num_timesteps: bool = True,
        progress_bar: bool = False,
    ) -> BatchLearner:
        name = type(self).__name__
        if self.plant is None:
            raise ValueError(f"{name} needs a BatchedVecEnv as its env (algorithm.vec_env: batched)")
        if progress_bar:  # stable-baselines3's own bar would advance by n_envs per iteration
            given = callback if isinstance(callback, list) else [callback] if callback is not None else []
            callback = [*given, StepsProgressBar()]
        total_timesteps, callback = self._setup_learn(
            total_timesteps, callback, reset_num_timesteps, tb_log_name or name
        )
        callback.on_training_start(locals(), globals())
        while self.num_timesteps < total_timesteps:
            self.num_timesteps += self.iterate()
            self._update_current_progress_remaining(self.num_timesteps, total_timesteps)
            callback.update_locals(locals())
            if not callback.on_step():
                break
        callback.on_training_end()
        return self


class StepsProgressBar(ProgressBarCallback):
    """stable-baselines3's progress bar, advanced by the steps an iteration simulated (not by n_envs)."""

    def _on_step(self) -> bool:
        self.pbar.update(self.model.num_timesteps - self.model._num_timesteps_at_start - self.pbar.n)
        return True
