"""A policy controller as a feedback graph: affine maps and scalar slope-restricted units, as a certificate
needs it (`evaluation.certificate`).

The graph acts on the closed loop's state s = [plant state; observation] (`simulation.linearised`). Its
coordinates are zeta = [s; w_1; ...; w_L]: each stage k computes pre-activations v_k = F_k zeta + f_k
(F_k reads s and earlier stages' outputs only) and outputs w_k = phi(v_k), unit by unit; the action is
a = G zeta + g.
The observation normalisation's clip, the network's activations, SAC's squashing, a residual's two clips and
the final clip to [-1, 1] are all units; a clip to [-c, c] is a unit saturation of v / c, scaled by c after.
An odd network is two copies of the network, on o and on -o; tanh squashes their half difference."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rlcontroller.control.policy_controller import PolicyController

SATURATION = "Saturation"  # clip to [-1, 1]


def _elu_slope(v: np.ndarray) -> np.ndarray:
    return np.where(v > 0.0, 1.0, np.exp(np.minimum(v, 0.0)))


# phi, phi' and the largest phi' on [lower, upper]; each phi is monotone with phi' in [0, 1] and phi' unimodal
# (so a chord's slope from a point is smallest at an end of the interval: `certificate.sectors`)
UNITS = {
    "Tanh": (
        np.tanh,
        lambda v: 1.0 - np.tanh(v) ** 2,
        lambda lo, up: 1.0 - np.tanh(np.clip(0.0, lo, up)) ** 2,
    ),
    "ReLU": (
        lambda v: np.maximum(v, 0.0),
        lambda v: (v > 0.0).astype(float),
        lambda lo, up: (up > 0.0).astype(float),
    ),
    "LeakyReLU": (
        lambda v: np.where(v > 0.0, v, 0.01 * v),
        lambda v: np.where(v > 0.0, 1.0, 0.01),
        lambda lo, up: np.where(up > 0.0, 1.0, 0.01),
    ),
    "ELU": (
        lambda v: np.where(v > 0.0, v, np.expm1(np.minimum(v, 0.0))),
        _elu_slope,
        lambda lo, up: _elu_slope(up),
    ),
    SATURATION: (
        lambda v: np.clip(v, -1.0, 1.0),
        lambda v: (np.abs(v) < 1.0).astype(float),
        lambda lo, up: ((lo < 1.0) & (up > -1.0)).astype(float),
    ),
}


@dataclass(frozen=True)
class Stage:
    """v = weight @ zeta + bias (units,); w = phi(v) with phi = UNITS[kind], one kind for the stage."""

    weight: np.ndarray  # (units, zeta size)
    bias: np.ndarray
    kind: str


@dataclass(frozen=True)
class FeedbackGraph:
    n_state: int  # size of s
    stages: tuple[Stage, ...]
    output: np.ndarray  # G (m, zeta size): the action in [-1, 1]
    output_bias: np.ndarray  # g (m,)

    @property
    def size(self) -> int:
        """The size of zeta."""
        return self.output.shape[1]

    def offsets(self) -> list[int]:
        """Where each stage's units start in zeta."""
        starts, start = [], self.n_state
        for stage in self.stages:
            starts.append(start)
            start += stage.bias.size
        return starts

    def forward(self, state: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """zeta, the pre-activations v (all stages, stacked) and the action a at the state s."""
        zeta = np.zeros(self.size)
        zeta[: self.n_state] = state
        pre = []
        for start, stage in zip(self.offsets(), self.stages, strict=True):
            v = stage.weight @ zeta + stage.bias
            zeta[start : start + v.size] = UNITS[stage.kind][0](v)
            pre.append(v)
        return zeta, np.concatenate(pre), self.output @ zeta + self.output_bias

    def jacobian(self, state: np.ndarray) -> np.ndarray:
        """da/ds (m, n) at s (one-sided where a unit sits on a kink)."""
        zeta, _, _ = self.forward(state)
        tangent = np.zeros((self.size, self.n_state))
        tangent[: self.n_state] = np.eye(self.n_state)
        for start, stage in zip(self.offsets(), self.stages, strict=True):
            slope = UNITS[stage.kind][1](stage.weight @ zeta + stage.bias)
            tangent[start : start + stage.bias.size] = slope[:, None] * (stage.weight @ tangent)
        return self.output @ tangent


class _Builder:
    """Stages appended one at a time; a signal is an affine map of zeta (matrix, offset), padded as zeta
    grows."""

    def __init__(self, n_state: int) -> None:
        self.n_state, self.size, self.stages = n_state, n_state, []

    def pad(self, matrix: np.ndarray) -> np.ndarray:
        return np.hstack([matrix, np.zeros((matrix.shape[0], self.size - matrix.shape[1]))])

    def unit(self, signal: tuple[np.ndarray, np.ndarray], kind: str, scale: float = 1.0):
        """phi(signal / scale) * scale, as a new stage; returns the output as a signal."""
        matrix, offset = signal
        units = offset.size
        self.stages.append(Stage(self.pad(matrix) / scale, offset / scale, kind))
        selected = np.zeros((units, self.size + units))
        selected[:, self.size :] = np.eye(units) * scale
        self.size += units
        return selected, np.zeros(units)

    def affine(self, weight: np.ndarray, signal, bias: np.ndarray):
        matrix, offset = signal
        return weight @ self.pad(matrix), weight @ offset + bias


def feedback_graph(controller: PolicyController, *, n_plant: int, n_observation: int) -> FeedbackGraph:
    """The graph of `controller` (no MPC) on s = [plant state (n_plant); observation (n_observation)]."""
    if controller.mpc is not None:
        raise ValueError("an MPC law is a quadratic program every step, not a network")
    actor = controller.actor
    unknown = {layer.activation for layer in actor.layers} - set(UNITS) - {None}
    if unknown:
        raise ValueError(f"activation {sorted(unknown)[0]} is not monotone with slopes in [0, 1]")
    n = n_plant + n_observation
    build = _Builder(n)
    raw = (np.hstack([np.zeros((n_observation, n_plant)), np.eye(n_observation)]), np.zeros(n_observation))
    observation = raw
    if (norm := controller.normalizer) is not None:
        spread = np.sqrt(np.asarray(norm.var, dtype=float) + norm.epsilon)
        observation = build.affine(np.diag(1.0 / spread), raw, -np.asarray(norm.mean, dtype=float) / spread)
        observation = build.unit(observation, SATURATION, scale=float(norm.clip))

    def network(signal):
        for layer in actor.layers:
            signal = build.affine(layer.weight.astype(float), signal, layer.bias.astype(float))
            if layer.activation is not None:
                signal = build.unit(signal, layer.activation)
        return signal

    if actor.odd:
        plus = network(observation)
        minus = network((-observation[0], -observation[1]))
        action = (0.5 * (build.pad(plus[0]) - build.pad(minus[0])), 0.5 * (plus[1] - minus[1]))
    else:
        action = network(observation)
    if actor.squash:
        action = build.unit(action, "Tanh")
    action = build.unit(action, SATURATION)
    if controller.prior is not None:
        gain = controller.prior.observation_gain  # (m, observation)
        prior = build.affine(gain, raw, np.zeros(gain.shape[0]))
        action = build.unit((build.pad(action[0]) + build.pad(prior[0]), action[1] + prior[1]), SATURATION)
    matrix, offset = action
    stages = tuple(Stage(build.pad(stage.weight), stage.bias, stage.kind) for stage in build.stages)
    return FeedbackGraph(n, stages, build.pad(matrix), offset)
