"""Random search with common random numbers: a learner of a linear odd policy a = clip(W o), or with
`policy.odd: false` of an affine one a = clip(W o + b).

Augmented random search (Mania et al., 2018) on W (actuators x observation; with b, [W | b]),
started at W = 0 and b = `initial_bias` (no control, or a constant command; the learner needs no
model of the building). An affine policy is for devices whose command is not a force: a damper's
best command at rest is not zero, and "full voltage, less when ..." is b = 1 plus a linear switch.
Each iteration draws `n_motions` training motions (the experiment's generator) with their noise
seeds and `n_delta` random directions d_k, runs W + delta_std d_k and W - delta_std d_k on the
*same* motions, noise and (with `plant_randomization`) plants drawn from those seeds, and steps along
sum_k (f(W + delta_std d_k) - f(W - delta_std d_k)) d_k, scaled by `learning_rate` / (n_delta
delta_std std(f)), where f is the mean over the motions of log(-return): each motion counts by its
relative change, since a strong motion's return is 10^4 times a weak one's and would drown every
difference on unpaired motions. That pairing is why this learner exists: sb3-contrib's ARS evaluates
each candidate on the environment's next episodes, so + and - never see the same motion.

With `objective: standard` f aims at the safety check instead of the reward: the building failed safe
runs on the same motions, noise and plants, and f is the mean over the motions of the candidate's J1
against it (mean over stories of each story's peak drift ratio) plus `STANDARD_PENALTY` times how far the
check's own measure (`metrics.ratio_to_reference`) exceeds 1: every motion made worse than failing safe
is priced, as the check fails it. With `objective: peaks` each motion's J2 against the same reference (mean
over floors of each floor's peak absolute acceleration ratio) is added to its J1: drift and floor acceleration
weighed alike, as the check and the scoreboard weigh them, on the peaks no quadratic cost states.

The policy is `OddActorCriticPolicy` (a stable-baselines3 actor-critic policy) with a linear actor
(`actor_arch: []`; its action layer is W, bias 0; no critic is trained), or for an affine policy
stable-baselines3's own `ActorCriticPolicy` (its action layer is W, b), so saving, loading,
evaluation, validation and ONNX export are those of any run. With hidden layers (`actor_arch: [64, 64]`)
the searched parameters are every weight and bias of the actor's network, one vector (the hidden layers
start at stable-baselines3's initialisation, the action layer at W = 0, b = `initial_bias`: the search starts
at no action, a constant command, or the prior), and each candidate runs as the numpy network a saved policy
is. `num_timesteps` counts the control steps simulated. The learner runs on the plant of its training env
(a `BatchedVecEnv`), whose generator and randomisation it uses; every field needed to resume exactly (W,
the search's random generator) is saved with the model.
With `residual_lqg` the candidates are residuals on the LQG prior (`LinearFeedback` with a prior),
and W = 0 starts the search at LQG.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
from stable_baselines3.common.policies import ActorCriticPolicy

from rlcontroller.config.learning import CHOICE_KWARGS
from rlcontroller.control.controllers import Controller, LinearFeedback, fail_safe_controller
from rlcontroller.control.networks import Actor, Layer
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.learning.actor import actor_of
from rlcontroller.learning.batch_learner import BatchLearner
from rlcontroller.learning.odd_policy import OddActorCriticPolicy
from rlcontroller.physics.metrics import peak, ratio_to_reference
from rlcontroller.physics.motions.excitation import Load
from rlcontroller.physics.motions.loads import generate_suite
from rlcontroller.simulation.rollout import batch_rollout

STANDARD_PENALTY = 10.0  # per unit of the check's ratio above 1 (objective: standard or peaks)
OBJECTIVES = CHOICE_KWARGS["objective"]


class RandomSearch(BatchLearner):
    """Augmented random search with common random numbers (module docstring).

    Parameters
    ----------
    n_delta : random directions per iteration (each run with + and -).
    n_motions : training motions per iteration, shared by every candidate.
    delta_std : size of the perturbations of W (action per unit observation).
    learning_rate : step size of W's update, as in the module docstring's formula.
    initial_bias : b at the start, every action's (an affine policy, or an affine network's action layer):
        1 starts dampers at full voltage (passive-on), -1 at their least (passive-off).
    objective : "return" (the reward), "standard" (J1 against the building failed safe, every motion
        made worse priced: module docstring) or "peaks" (the same with J2 added).
    """

    policy_aliases = {"MlpPolicy": ActorCriticPolicy}  # affine; the odd policy is passed as its class

    def __init__(
        self,
        policy: str | type[OddActorCriticPolicy],
        env,
        n_delta: int = 8,
        n_motions: int = 8,
        delta_std: float = 0.02,
        learning_rate: float = 0.01,
        initial_bias: float = 0.0,
        objective: str = "return",
        policy_kwargs: dict[str, Any] | None = None,
        tensorboard_log: str | None = None,
        seed: int | None = None,
        device: str = "auto",
        verbose: int = 0,
        _init_setup_model: bool = True,
    ) -> None:
        super().__init__(policy, env, learning_rate, policy_kwargs, tensorboard_log, seed, device, verbose)
        self.n_delta = n_delta
        self.n_motions = n_motions
        self.delta_std = delta_std
        self.initial_bias = initial_bias
        if objective not in OBJECTIVES:
            raise ValueError(f"objective {objective!r}: expected one of {', '.join(OBJECTIVES)}")
        self.objective = objective
        if _init_setup_model:
            self._setup_model()

    def _setup_model(self) -> None:
        self._setup_policy_and_plant()
        self.affine = not isinstance(self.policy, OddActorCriticPolicy)
        self.network = bool(self.policy.mlp_extractor.policy_net)  # hidden layers: search every parameter
        if self.initial_bias != 0.0 and not self.affine:
            raise ValueError(f"initial_bias {self.initial_bias} needs an affine policy (policy.odd: false)")
        if not hasattr(self, "weights"):  # a new model (a loaded one brings W and the generator)
            if self.network:  # the action layer starts at the prior's action: W = 0, b = initial_bias
                with torch.no_grad():
                    self.policy.action_net.weight.zero_()
                    self.policy.action_net.bias.fill_(self.initial_bias)
                values = [p.detach().cpu().numpy().ravel() for p in self._parameters()]
                self.weights = np.concatenate(values, dtype=float)
            else:
                rows, columns = self.policy.action_net.weight.shape
                self.weights = np.zeros((rows, columns + self.affine))  # [W | b] when affine
                self.weights[:, columns:] = self.initial_bias
            self.search_rng = np.random.default_rng(self.seed)
        self._set_actor()
        self._network = actor_of(self) if self.network else None  # the layers' shapes and activations

    def _parameters(self) -> list[torch.Tensor]:
        """The actor network's weights and biases, layer by layer (the order of the searched vector)."""
        linears = [*self.policy.mlp_extractor.policy_net, self.policy.action_net]
        return [
            p
            for module in linears
            if isinstance(module, torch.nn.Linear)
            for p in (module.weight, module.bias)
        ]

    def _set_actor(self) -> None:
        with torch.no_grad():
            if self.network:
                start = 0
                for parameter in self._parameters():
                    values = self.weights[start : start + parameter.numel()].reshape(parameter.shape)
                    parameter.copy_(torch.as_tensor(values, dtype=torch.float32))
                    start += parameter.numel()
                return
            weights, bias = self._split(self.weights)
            self.policy.action_net.weight.copy_(torch.as_tensor(weights, dtype=torch.float32))
            self.policy.action_net.bias.copy_(
                torch.as_tensor(0.0 if bias is None else bias, dtype=torch.float32)
            )

    def candidate(self, parameters: np.ndarray) -> Controller:
        """The controller of one candidate's parameters, as its saved policy would act."""
        if not self.network:
            weights, bias = self._split(parameters)
            return LinearFeedback(weights, prior=self.prior, bias=bias)
        layers, start = [], 0
        for layer in self._network.layers:
            weight = parameters[start : start + layer.weight.size].reshape(layer.weight.shape)
            bias = parameters[start + weight.size : start + weight.size + layer.bias.size]
            layers.append(Layer(weight.astype(np.float32), bias.astype(np.float32), layer.activation))
            start += weight.size + bias.size
        actor = Actor(tuple(layers), squash=False, odd=self._network.odd)
        return PolicyController(actor, None, self.prior, "candidate")

    def _split(self, parameters: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """W and b (None for an odd policy) of a candidate's parameters."""
        return (parameters[:, :-1], parameters[:, -1]) if self.affine else (parameters, None)

    def paired_log_costs(
        self, deltas: np.ndarray, motions: list[Load], seeds: list[int]
    ) -> tuple[np.ndarray, np.ndarray, int]:
        """f(W + d_k) and f(W - d_k) for every direction d_k, all on the same motions, noise seeds
        and (with `plant_randomization`) plants drawn from those seeds; and the control steps run."""
        candidates = [self.weights + d for d in deltas] + [self.weights - d for d in deltas]
        controllers = [self.candidate(parameters) for parameters in candidates]
        runs = batch_rollout(self.plant, motions, controllers, seeds=seeds, randomize=True)
        if self.objective != "return":  # the reference with the control system failed safe: no supervisor
            failed_safe = self.plant.failed_safe
            reference = batch_rollout(
                failed_safe, motions, [fail_safe_controller(failed_safe)], seeds=seeds, randomize=True
            )
            peaks = self.objective == "peaks"
            f = np.array([standard_cost(lane, reference[0], accelerations=peaks) for lane in runs])
        else:
            f = np.array([np.mean([np.log(max(-total, 1e-300)) for _, total in lane]) for lane in runs])
        episodes = [
            {"r": total, "l": response.drift.shape[0] - 1} for lane in runs for response, total in lane
        ]
        self.ep_info_buffer.extend(episodes)
        return f[: len(deltas)], f[len(deltas) :], sum(episode["l"] for episode in episodes)

    def iterate(self) -> int:
        """One update of W; returns the control steps it simulated."""
        rng = self.search_rng
        generator = self.plant.experiment.excitation.generator
        motions = generate_suite(generator, self.n_motions, int(rng.integers(2**31)), self.plant.building)
        seeds = [int(s) for s in rng.integers(2**31, size=self.n_motions)]
        deltas = self.delta_std * rng.standard_normal((self.n_delta, *self.weights.shape))
        plus, minus, steps = self.paired_log_costs(deltas, motions, seeds)
        spread = float(np.std(np.concatenate([plus, minus]))) or 1.0
        step = self.lr_schedule(self._current_progress_remaining) / (self.n_delta * spread * self.delta_std)
        self.weights = self.weights - step * np.tensordot(plus - minus, deltas, axes=1)
        self._set_actor()
        self._n_updates += 1
        return steps


def standard_cost(lane: list, reference: list, *, accelerations: bool = False) -> float:
    """`objective: standard`'s f of one candidate: over its (response, return) runs and the building failed
    safe's on the same motions, the mean of J1 against the reference (with `accelerations`, `objective:
    peaks`: J1 + J2) plus the priced excess of the check's measure over 1."""
    costs = []
    for (response, _), (failed_safe, _) in zip(lane, reference, strict=True):
        j = float(np.mean(peak(response.drift) / peak(failed_safe.drift)))
        if accelerations:
            acceleration = response.absolute_acceleration
            j += float(np.mean(peak(acceleration) / peak(failed_safe.absolute_acceleration)))
        costs.append(j + STANDARD_PENALTY * max(ratio_to_reference(response, failed_safe) - 1.0, 0.0))
    return float(np.mean(costs))
