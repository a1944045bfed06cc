"""A stable-baselines3 policy's deterministic actor as plain layers (`control.networks.Actor`).

stable-baselines3's MLP policies act deterministically through a chain of linear layers and
activations: PPO/A2C's Gaussian mean (`mlp_extractor.policy_net`, then `action_net`), SAC's actor
(`latent_pi` then `mu`, squashed by tanh) and TD3/DDPG's actor (`mu`, ending in tanh). `actor_of`
reads those weights once, so that the saved controller is data (`control.policy_file`) and evaluation
runs in numpy, the same numbers as torch's forward up to float32 rounding.
"""

from __future__ import annotations

import numpy as np

from rlcontroller.control.networks import ACTIVATIONS, Actor, Layer


def actor_of(model) -> Actor | None:
    """The deterministic actor of an SB3 model with a flat-observation MLP policy (PPO or A2C with a
    Gaussian, SAC, TD3, DDPG) or of an sbx one (SAC, TQC, TD3), or None for anything else."""
    from rlcontroller.learning.jax_learners import is_jax_model, jax_actor

    if is_jax_model(model):
        return jax_actor(model)
    import torch
    from stable_baselines3.common.distributions import DiagGaussianDistribution
    from stable_baselines3.common.policies import ActorCriticPolicy
    from stable_baselines3.common.torch_layers import FlattenExtractor

    policy = getattr(model, "policy", None)
    actor = getattr(policy, "actor", None)
    if isinstance(policy, ActorCriticPolicy) and isinstance(policy.action_dist, DiagGaussianDistribution):
        extractor, modules, squash = (
            policy.pi_features_extractor,
            [*policy.mlp_extractor.policy_net, policy.action_net],
            False,
        )
    elif all(hasattr(actor, name) for name in ("latent_pi", "mu", "log_std")):
        extractor, modules, squash = actor.features_extractor, [*actor.latent_pi, actor.mu], True  # SAC
    elif isinstance(getattr(actor, "mu", None), torch.nn.Sequential) and isinstance(
        actor.mu[-1], torch.nn.Tanh
    ):
        extractor, modules, squash = actor.features_extractor, list(actor.mu)[:-1], True  # TD3, DDPG
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
