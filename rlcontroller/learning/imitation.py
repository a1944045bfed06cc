"""Imitation of MPC by DAgger: a learner of an MLP policy that acts as MPC does, at a network's cost.

DAgger (Ross, Gordon and Bagnell 2011, AISTATS): each iteration draws `n_motions` training motions (the
experiment's generator, never the records) with their noise seeds, runs them with the current policy (the
first iteration with MPC itself: behaviour cloning), asks MPC (`control.mpc.MPCController` on the design
model, horizon `horizon`; `SemiActiveMPC`, whose action is each damper's command, for semi-active dampers)
what it would do at every observation the policy met, adds those pairs to the data set (at most `max_samples`,
a uniform subset kept), and fits the actor to the whole set for `epochs` passes of Adam. The expert's labels
come from the states the learner itself visits, so its mistakes are corrected where they lead, which cloning
MPC's own trajectories does not do.

The loss is the squared error of the action the env takes against MPC's (`imitation_loss`). With
`residual_lqg` the policy learns a correction to LQG + ground model (the env's own prior), without it the
whole action; a residual cannot imitate MPC where LQG's demand is beyond twice the force limit and MPC's is
not (the env clips the residual to [-1, 1] before adding it), so the study's policy learns the whole action
from the observation's Kalman estimate.

The policy is stable-baselines3's `ActorCriticPolicy` (its Gaussian mean is the actor; no critic is trained),
so saving, loading, validation, `rlc check` and ONNX export are those of any run. `num_timesteps` counts the
control steps simulated. The data set, the optimiser and the iteration's random generator are saved with the
model, so a run resumes where it stopped.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
from stable_baselines3.common.policies import ActorCriticPolicy

from rlcontroller.control.controllers import residual_action
from rlcontroller.control.mpc import DEFAULT_HORIZON
from rlcontroller.control.mpc_controllers import mpc_controller
from rlcontroller.learning.batch_learner import BatchLearner
from rlcontroller.physics.motions.loads import generate_suite
from rlcontroller.simulation.rollout import batch_rollout


class DAgger(BatchLearner):
    """DAgger with MPC as the expert (module docstring).

    Parameters
    ----------
    horizon : MPC's horizon (control steps).
    n_motions : training motions per iteration.
    epochs : passes over the data set after each iteration.
    batch_size : samples per gradient step.
    max_samples : the largest data set kept (observation, MPC's action, the prior's action).
    learning_rate : Adam's step size.
    """

    policy_aliases = {"MlpPolicy": ActorCriticPolicy}

    def __init__(
        self,
        policy: str | type[ActorCriticPolicy],
        env,
        horizon: int = DEFAULT_HORIZON,
        n_motions: int = 16,
        epochs: int = 10,
        batch_size: int = 256,
        max_samples: int = 300_000,
        learning_rate: float = 1e-3,
        policy_kwargs: dict[str, Any] | None = None,
        tensorboard_log: str | None = None,
        seed: int | None = None,
        device: str = "auto",
        verbose: int = 0,
        _init_setup_model: bool = True,
    ) -> None:
        super().__init__(policy, env, learning_rate, policy_kwargs, tensorboard_log, seed, device, verbose)
        self.horizon = horizon
        self.n_motions = n_motions
        self.epochs = epochs
        self.batch_size = batch_size
        self.max_samples = max_samples
        if _init_setup_model:
            self._setup_model()

    def _setup_model(self) -> None:
        self._setup_policy_and_plant()
        self.expert = mpc_controller(self.plant.design, self.horizon) if self.plant is not None else None
        if not hasattr(self, "samples"):  # a new model (a loaded one brings its data set and generator)
            size, m = self.observation_space.shape[0], self.action_space.shape[0]
            self.samples = {
                "observation": np.zeros((0, size), np.float32),
                "expert": np.zeros((0, m), np.float32),
                "prior": np.zeros((0, m), np.float32),
            }
            self.dagger_rng = np.random.default_rng(self.seed)

    def _excluded_save_params(self) -> list[str]:
        return [*super()._excluded_save_params(), "expert"]

    def _get_torch_save_params(self) -> tuple[list[str], list[str]]:
        return ["policy", "policy.optimizer"], []  # Adam's moments too: a resumed run fits as the whole one

    def _residual(self, observation: torch.Tensor) -> torch.Tensor:
        """The actor's output (the Gaussian's mean): the residual on the prior, or the action."""
        return self.policy.action_net(self.policy.mlp_extractor.forward_actor(observation))

    def act(self, observation: np.ndarray) -> np.ndarray:
        """The policy's action, as the env takes it, for a batch of observations."""
        with torch.no_grad():
            residual = self._residual(torch.as_tensor(observation, dtype=torch.float32)).numpy()
        prior = np.zeros_like(residual) if self.prior is None else self.prior(observation)
        return residual_action(residual, prior)

    def collect(self, expert_acts: bool) -> int:
        """One iteration's rollouts: the data set grows by MPC's action at every observation met; returns the
        control steps simulated."""
        rng = self.dagger_rng
        generator = self.plant.experiment.excitation.generator
        motions = generate_suite(generator, self.n_motions, int(rng.integers(2**31)), self.plant.building)
        seeds = [int(s) for s in rng.integers(2**31, size=self.n_motions)]
        collector = _Collector(self, expert_acts)
        runs = batch_rollout(self.plant, motions, [collector], seeds=seeds, randomize=True)
        episodes = [{"r": total, "l": response.drift.shape[0] - 1} for response, total in runs[0]]
        self.ep_info_buffer.extend(episodes)
        new = {key: np.concatenate(rows).astype(np.float32) for key, rows in collector.rows.items()}
        merged = {key: np.concatenate([self.samples[key], new[key]]) for key in new}
        count = merged["observation"].shape[0]
        if count > self.max_samples:
            kept = np.sort(rng.choice(count, self.max_samples, replace=False))
            merged = {key: value[kept] for key, value in merged.items()}
        self.samples = merged
        return sum(episode["l"] for episode in episodes)

    def fit(self) -> float:
        """`epochs` passes of Adam over the data set; returns the last pass' mean loss."""
        observation, expert, prior = (
            torch.as_tensor(self.samples[key]) for key in ("observation", "expert", "prior")
        )
        count = observation.shape[0]
        optimizer = self.policy.optimizer
        for group in optimizer.param_groups:
            group["lr"] = self.lr_schedule(self._current_progress_remaining)
        generator = torch.Generator().manual_seed(int(self.dagger_rng.integers(2**31)))
        loss_sum = 0.0
        for _ in range(self.epochs):
            loss_sum, order = 0.0, torch.randperm(count, generator=generator)
            for start in range(0, count, self.batch_size):
                batch = order[start : start + self.batch_size]
                loss = imitation_loss(self._residual(observation[batch]), prior[batch], expert[batch])
                optimizer.zero_grad()
                loss.backward()
                optimizer.step()
                loss_sum += loss.item() * batch.shape[0]
        self._n_updates += 1
        return loss_sum / count

    def iterate(self) -> int:
        """One DAgger iteration (MPC acts in the first): collect, then fit; returns the control steps
        simulated."""
        steps = self.collect(expert_acts=self._n_updates == 0)
        self.logger.record("train/imitation_loss", self.fit())
        return steps


def imitation_loss(residual: torch.Tensor, prior: torch.Tensor, expert: torch.Tensor) -> torch.Tensor:
    """Mean squared error of the env's action against the expert's: the env adds the residual, clipped to
    [-1, 1], to the prior and clips the sum to [-1, 1], so the error is zero where the sum is beyond the force
    limit the expert is at; elsewhere a residual beyond [-1, 1] also pays its excess squared (the clip
    passes no gradient back)."""
    action = residual.clamp(-1.0, 1.0) + prior
    saturated = ((expert >= 1.0) & (action >= 1.0)) | ((expert <= -1.0) & (action <= -1.0))
    zero = torch.zeros_like(action)
    error = torch.where(saturated, zero, action - expert)
    excess = torch.where(saturated, zero, torch.relu(residual.abs() - 1.0))
    return (error**2 + excess**2).mean()


class _Collector:
    """A controller for one iteration's rollouts: records each observation with MPC's action and the prior's,
    and acts as MPC (`expert_acts`) or as the learner."""

    def __init__(self, learner: DAgger, expert_acts: bool) -> None:
        self.learner, self.expert_acts = learner, expert_acts
        self.name = "DAgger"
        self.rows: dict[str, list[np.ndarray]] = {"observation": [], "expert": [], "prior": []}

    def reset(self) -> None:
        self.learner.expert.reset()

    def act(self, observation: np.ndarray) -> np.ndarray:
        learner = self.learner
        expert = learner.expert.act(observation)
        prior = np.zeros_like(expert) if learner.prior is None else learner.prior(observation)
        # the simulator reuses its buffer
        self.rows["observation"].append(np.array(observation, dtype=np.float32))
        self.rows["expert"].append(expert)
        self.rows["prior"].append(prior)
        return expert if self.expert_acts else learner.act(observation)
