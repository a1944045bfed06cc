"""A saved policy's deterministic actor as plain layers: numpy inference and the export's network.

stable-baselines3's MLP policies act deterministically through a chain of linear layers and
activations: PPO/A2C's Gaussian mean (`mlp_extractor.policy_net`, then `action_net`) and SAC/TD3's
actor (`latent_pi` then `mu`, squashed by tanh). `actor_of` reads those weights once; `Actor` applies
them to a batch of observations in float32 numpy, the same numbers as torch's forward up to float32
rounding, without torch's per-call overhead (which dominates at the batch sizes of evaluation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.special

ACTIVATIONS = {
    "ReLU": lambda x: np.maximum(x, 0.0),
    "Tanh": np.tanh,
    "ELU": lambda x: np.where(x > 0.0, x, np.expm1(np.minimum(x, 0.0))),
    "LeakyReLU": lambda x: np.where(x > 0.0, x, 0.01 * x),
    "GELU": lambda x: 0.5 * x * (1.0 + scipy.special.erf(x / np.sqrt(2.0))),
}


@dataclass(frozen=True)
class Layer:
    weight: np.ndarray  # (out, in), float32
    bias: np.ndarray  # (out,), float32
    activation: str | None  # a key of ACTIVATIONS applied after the layer, or None


@dataclass(frozen=True)
class Actor:
    """observation (..., n) float32 -> deterministic action (..., m), before clipping."""

    layers: tuple[Layer, ...]
    squash: bool  # tanh on the output (SAC's squashed Gaussian)
    odd: bool = False  # the action is (g(o) - g(-o)) / 2 (`OddActorCriticPolicy`)

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        x = np.asarray(observation, dtype=np.float32)
        if self.odd:
            return 0.5 * (self._network(x) - self._network(-x))
        return self._network(x)

    def _network(self, x: np.ndarray) -> np.ndarray:
        for layer in self.layers:
            x = x @ layer.weight.T + layer.bias
            if layer.activation is not None:
                x = ACTIVATIONS[layer.activation](x).astype(np.float32, copy=False)
        return np.tanh(x) if self.squash else x


def actor_of(model) -> Actor | None:
    """The deterministic actor of an SB3 model with a flat-observation MLP policy (PPO or A2C with a
    Gaussian, SAC), or None for anything else (use the model's own predict)."""
    import torch
    from stable_baselines3.common.distributions import DiagGaussianDistribution
    from stable_baselines3.common.policies import ActorCriticPolicy
    from stable_baselines3.common.torch_layers import FlattenExtractor

    policy = getattr(model, "policy", None)
    if isinstance(policy, ActorCriticPolicy) and isinstance(policy.action_dist, DiagGaussianDistribution):
        extractor, modules, squash = (
            policy.pi_features_extractor,
            [*policy.mlp_extractor.policy_net, policy.action_net],
            False,
        )
    elif all(hasattr(getattr(policy, "actor", None), name) for name in ("latent_pi", "mu", "log_std")):
        actor = policy.actor  # SAC: latent_pi, mu, then tanh
        extractor, modules, squash = actor.features_extractor, [*actor.latent_pi, actor.mu], True
    else:
        return None
    if not isinstance(extractor, FlattenExtractor):
        return None
    layers: list[Layer] = []
    for module in modules:
        if isinstance(module, torch.nn.Linear):
            weight = module.weight.detach().cpu().numpy().astype(np.float32)
            layers.append(Layer(weight, module.bias.detach().cpu().numpy().astype(np.float32), None))
        elif type(module).__name__ in ACTIVATIONS and layers and layers[-1].activation is None:
            if isinstance(module, torch.nn.LeakyReLU) and module.negative_slope != 0.01:
                return None
            layers[-1] = Layer(layers[-1].weight, layers[-1].bias, type(module).__name__)
        else:
            return None
    from rlcontroller.learning.odd_policy import OddActorCriticPolicy

    return Actor(tuple(layers), squash, isinstance(policy, OddActorCriticPolicy)) if layers else None
