"""sbx's squashed Gaussian actor with an odd mean: a(-o) = -a(o), so a(0) = 0 (`policy.odd`, `backend: sbx`).

The JAX twin of `odd_policy.OddActorCriticPolicy` for SAC and TQC: the Gaussian's mean before tanh is
(g(o) - g(-o)) / 2 for the usual MLP g, so biases cancel and a linear actor (`actor_arch: []`) is tanh(W o),
LQG's own family of laws inside the limits; its log std is the even part (h(o) + h(-o)) / 2, the same spread
for mirrored readings. The layers are those of sbx's `SquashedGaussianActor`, created in the same order (the
hidden ones, the mean, the log std), so the saved actor reads as any sbx actor's, with `Actor.odd` set
(`jax_learners.jax_actor`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import flax.linen as nn
import jax.numpy as jnp
from sbx.common.distributions import TanhTransformedDistribution
from sbx.common.policies import tfd


class OddSquashedGaussianActor(nn.Module):
    """observation (batch, n) -> tanh of a Gaussian whose mean is odd and whose log std is even in it."""

    net_arch: Sequence[int]
    action_dim: int
    log_std_min: float = -20
    log_std_max: float = 2
    activation_fn: Callable[[jnp.ndarray], jnp.ndarray] = nn.relu

    def get_std(self):  # sbx's gSDE hook, as its own actor has it
        return jnp.array(0.0)

    @nn.compact
    def __call__(self, x: jnp.ndarray):
        x = x.reshape((x.shape[0], -1))
        hidden = [nn.Dense(units) for units in self.net_arch]
        mean_layer, log_std_layer = nn.Dense(self.action_dim), nn.Dense(self.action_dim)

        def features(h: jnp.ndarray) -> jnp.ndarray:
            for layer in hidden:
                h = self.activation_fn(layer(h))
            return h

        direct, mirrored = features(x), features(-x)
        mean = 0.5 * (mean_layer(direct) - mean_layer(mirrored))
        log_std = jnp.clip(
            0.5 * (log_std_layer(direct) + log_std_layer(mirrored)), self.log_std_min, self.log_std_max
        )
        return TanhTransformedDistribution(tfd.MultivariateNormalDiag(loc=mean, scale_diag=jnp.exp(log_std)))
