"""The numpy forward pass of a policy network: its layers, activations, the odd symmetry and the
observation normalisation of training. Imports numpy alone (scipy for GELU): a policy file's network runs
without torch, stable-baselines3, MPC or the plant."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def gelu(x: np.ndarray) -> np.ndarray:
    """PyTorch's exact GELU, x Phi(x) (scipy imported here: only GELU networks pay for it)."""
    from scipy.special import erf

    return 0.5 * x * (1.0 + erf(x / np.sqrt(2.0)))


ACTIVATIONS = {
    "ReLU": lambda x: np.maximum(x, 0.0),
    "Tanh": np.tanh,
    "ELU": lambda x: np.where(x > 0.0, x, np.expm1(np.minimum(x, 0.0))),
    "LeakyReLU": lambda x: np.where(x > 0.0, x, 0.01 * x),
    "GELU": gelu,
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
    squash: bool  # tanh on the output (SAC's squashed Gaussian, TD3's actor)
    odd: bool = False  # the output before tanh is (g(o) - g(-o)) / 2 (PPO's and sbx's odd actors)

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        x = np.asarray(observation, dtype=np.float32)
        x = 0.5 * (self._layers(x) - self._layers(-x)) if self.odd else self._layers(x)
        return np.tanh(x) if self.squash else x

    def _layers(self, x: np.ndarray) -> np.ndarray:
        for layer in self.layers:
            x = x @ layer.weight.T + layer.bias
            if layer.activation is not None:
                x = ACTIVATIONS[layer.activation](x).astype(x.dtype, copy=False)
        return x


@dataclass(frozen=True)
class Normalizer:
    """The observation normalisation of training: clip((o - mean) / sqrt(var + epsilon), -clip, clip)."""

    mean: np.ndarray
    var: np.ndarray
    epsilon: float
    clip: float

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        spread = np.sqrt(self.var + self.epsilon)
        return ((observation - self.mean) / spread).clip(-self.clip, self.clip)
