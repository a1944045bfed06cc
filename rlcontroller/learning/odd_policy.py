"""An actor-critic policy whose action is odd in the observation: a(-o) = -a(o), so a(0) = 0.

A linear building under a reversed ground motion needs the reversed forces, and with nothing to
measure it needs none; LQG has both properties by construction. An MLP has neither: its biases give
a constant force at zero input (the committed policy: 3-6 kN, a static drift as large as a weak
motion's), which made it worse than no control in weak shaking. Here the Gaussian's mean is
(g(o) - g(-o)) / 2 for the usual MLP g, so biases cancel and the symmetry is exact; the value
function is the usual one. For PPO and A2C (`policy.odd: true`).
"""

from __future__ import annotations

import torch
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.torch_layers import MlpExtractor


class OddMlpExtractor(MlpExtractor):
    """The actor's latent for o and for -o side by side; the critic's as usual."""

    def forward(self, features: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.forward_actor(features), self.forward_critic(features)

    def forward_actor(self, features: torch.Tensor) -> torch.Tensor:
        return torch.cat([self.policy_net(features), self.policy_net(-features)], dim=-1)


class OddActorCriticPolicy(ActorCriticPolicy):
    """`MlpPolicy` with the odd action mean (g(o) - g(-o)) / 2 (Gaussian actions only)."""

    def _build_mlp_extractor(self) -> None:
        self.mlp_extractor = OddMlpExtractor(
            self.features_dim, net_arch=self.net_arch, activation_fn=self.activation_fn, device=self.device
        )

    def _get_action_dist_from_latent(self, latent_pi: torch.Tensor):
        half = latent_pi.shape[-1] // 2
        mean = 0.5 * (self.action_net(latent_pi[..., :half]) - self.action_net(latent_pi[..., half:]))
        return self.action_dist.proba_distribution(mean, self.log_std)
