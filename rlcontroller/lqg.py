"""LQG with the same cost as the reward, and the clairvoyant optimal reference.

The reward of a step is -|F y_{k+1}|^2 with y_{k+1} = C_r z_{k+1} + D_r u_k and
F = diag(sqrt(weight) / scale). With the exact control-step map
z_{k+1} = Phi z_k + Gamma u_k + g_k (g_k: the ground's contribution) that is

    cost_k = |H_z z_k + H_u u_k + F C_r g_k|^2,   H_z = F C_r Phi,  H_u = F (C_r Gamma + D_r),

so Q = H_z' H_z, R = H_u' H_u, N = H_z' H_u: the discrete-time LQR of exactly the reward
(python-control's Riccati solvers, method='scipy'). Everything is designed in action units
a = u / force_limit, which keeps the Riccati equations well scaled.

The steady-state Kalman filter (`estimation`) estimates z from the same noisy sensors the agent
sees, with the feed-through of the held force. Three variants: the ground acceleration unknown
(process noise), measured and used as a known input, or measured and predicted through a
Kanai-Tajimi ground model in the state (`design_lqg_ground_model`).

`optimal_response` is the reference with the state known and the ground known `preview` steps
ahead (the whole record: the clairvoyant optimum).
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np

from rlcontroller.config import Experiment, RewardConfig
from rlcontroller.dynamics import Response, StepMap, response, reward_matrices, step_map
from rlcontroller.env import BuildingEnv
from rlcontroller.estimation import (
    GroundModel,
    KalmanFilter,
    design_kalman,
    design_kalman_ground_model,
    ground_model_step,
)
from rlcontroller.excitation import GroundMotion, for_control_step
from rlcontroller.structure import Building, build


@dataclass(frozen=True)
class QuadraticCost:
    """cost_k = |state z_k + action a_k + ground g_k|^2 with the matrices below."""

    state: np.ndarray  # H_z
    action: np.ndarray  # H_u (per unit action)
    ground: np.ndarray  # F C_r, applied to the ground term g_k


def quadratic_cost(building: Building, reward: RewardConfig, step: StepMap) -> QuadraticCost:
    c, d, factor, _ = reward_matrices(building, [term for term in reward.terms if term.quadratic])
    weighted_c, weighted_d = factor[:, None] * c, factor[:, None] * d
    # states beyond the building's (a ground model's) reach the outputs only through the dynamics
    weighted_c = np.pad(weighted_c, ((0, 0), (0, step.phi.shape[0] - weighted_c.shape[1])))
    action_gain = step.force_gain * building.force_limits
    return QuadraticCost(
        state=weighted_c @ step.phi,
        action=weighted_c @ action_gain + weighted_d * building.force_limits,
        ground=weighted_c,
    )


def lqr_gain(step: StepMap, cost: QuadraticCost, force_limits: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(K, P): a = -K z minimises the summed cost; P is the stationary Riccati solution."""
    q = cost.state.T @ cost.state
    r = cost.action.T @ cost.action
    n = cost.state.T @ cost.action
    if np.linalg.matrix_rank(r) < r.shape[0]:
        raise ValueError("the reward does not penalise every actuator force (R is singular); add a force term")
    gain, riccati, _ = control.dlqr(step.phi, step.force_gain * force_limits, q, r, n, method="scipy")
    return np.asarray(gain), np.asarray(riccati)


@dataclass
class LQGDesign:
    """LQR gains in action units a = u / force_limit, and the Kalman filter."""

    feedback: np.ndarray  # K
    feedforward: np.ndarray  # K_g on the measured ground acceleration (known-input variant), else zero
    filter: KalmanFilter

    def closed_loop_eigenvalues(self) -> np.ndarray:
        return np.linalg.eigvals(self.filter.phi - self.filter.action_gain @ self.feedback)


def design_lqg(
    experiment: Experiment,
    known_ground: bool = False,
    ground_std: float = 1.0,
    reward: RewardConfig | None = None,
) -> LQGDesign:
    """LQG for the experiment's building, sensors and reward (or another `reward` for sweeps).

    With `known_ground` the measured ground acceleration enters the filter and, through the
    optimal one-step feed-forward, the control law.
    """
    building = build(experiment.building, experiment.actuators)
    step = step_map(building, experiment.simulation, substeps=1)
    cost = quadratic_cost(building, reward or experiment.reward, step)
    feedback, _ = lqr_gain(step, cost, building.force_limits)
    kalman = design_kalman(building, experiment.sensors, experiment.simulation, known_ground, ground_std)
    feedforward = np.zeros(building.n_actuators)
    if known_ground:  # the ground held over the coming step: the first preview kernel
        feedforward = preview_kernel(cost, step, building.force_limits, 1)[0] @ kalman.ground_gain
    return LQGDesign(feedback=feedback, feedforward=feedforward, filter=kalman)


def design_lqg_ground_model(
    experiment: Experiment, model: GroundModel | None = None, ground_std: float = 1.0
) -> LQGDesign:
    """LQG whose model includes a Kanai-Tajimi filter for the (measured) ground acceleration.

    The Kalman filter estimates the building and filter states from the floor sensors plus the
    ground reading; the LQR on the augmented state (same cost) acts on the predicted ground.
    """
    building = build(experiment.building, experiment.actuators)
    model = model or GroundModel()
    step = ground_model_step(building, experiment.simulation.control_dt, model)
    feedback, _ = lqr_gain(step, quadratic_cost(building, experiment.reward, step), building.force_limits)
    kalman = design_kalman_ground_model(building, experiment.sensors, experiment.simulation, model, ground_std)
    return LQGDesign(feedback=feedback, feedforward=np.zeros(building.n_actuators), filter=kalman)


class LQGController:
    """Kalman filter + LQR on the env's observation (the same readings the agent gets)."""

    def __init__(self, design: LQGDesign, env: BuildingEnv, name: str = "LQG") -> None:
        self.design = design
        self.name = name
        self.force_limits = env.force_limits
        self.layout = env.layout
        self.reset()

    def reset(self) -> None:
        self.design.filter.reset()
        self._previous_ground = 0.0

    def act(self, observation: np.ndarray) -> np.ndarray:
        layout = self.layout
        readings = observation[layout.readings] * layout.reading_scale
        ground = float(observation[layout.ground]) * layout.ground_scale
        held = np.asarray(observation[layout.action], dtype=float)  # the clipped action just applied
        estimate = self.design.filter.update(readings, held, ground, self._previous_ground)
        self._previous_ground = ground
        action = -self.design.feedback @ estimate - self.design.feedforward * ground
        return np.clip(action, -1.0, 1.0) * self.force_limits


class LQGPrior:
    """The action of LQG + measured ground, or of LQG + ground model with `sensors.ground_model`
    (action units, unclipped), from an observation that holds the env's own Kalman estimate
    (`sensors.state_estimate`), for residual policies."""

    def __init__(self, experiment: Experiment) -> None:
        env = BuildingEnv(experiment)
        if env.kalman is None:
            raise ValueError("a residual on LQG needs sensors.state_estimate: true")
        if experiment.sensors.ground_model:
            design = design_lqg_ground_model(experiment)
        else:
            design = design_lqg(experiment, known_ground=True)
        layout = env.layout
        self._feedback = design.feedback * layout.estimate_scale  # acts on the scaled estimate
        self._feedforward = design.feedforward * layout.ground_scale  # on the scaled ground reading
        self._estimate = layout.estimate
        self._ground = layout.ground

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        observation = np.asarray(observation, dtype=float)
        return (
            -(observation[..., self._estimate] @ self._feedback.T)
            - observation[..., self._ground, None] * self._feedforward
        )


def preview_kernel(cost: QuadraticCost, step: StepMap, force_limits: np.ndarray, length: int) -> np.ndarray:
    """W_0..W_{length-1}: the optimal feed-forward a_ff,k = sum_j W_j g_{k+j} on known ground terms.

    For the stationary LQR (gain K, Riccati P, closed loop Phi_c = Phi - B K) the feed-forward on
    the ground terms g_k, g_{k+1}, ... of the coming steps is

        W_0 = S^-1 (H_u' F C_r + B' P),   W_j = S^-1 B' (Phi_c')^(j-1) (C_c' F C_r + Phi_c' P),

    with S = H_u' H_u + B' P B and C_c = H_z - H_u K (a test checks it against brute-force least
    squares). Unknown ground terms are zero in expectation, so knowing `length` steps ahead means
    using the first `length` kernels. Shape (length, actions, states).
    """
    feedback, riccati = lqr_gain(step, cost, force_limits)
    action_gain = step.force_gain * force_limits
    curvature_inverse = np.linalg.inv(cost.action.T @ cost.action + action_gain.T @ riccati @ action_gain)
    closed_phi = step.phi - action_gain @ feedback
    closed_cost = cost.state - cost.action @ feedback
    kernels = np.zeros((length, *feedback.shape))
    if length:
        kernels[0] = curvature_inverse @ (cost.action.T @ cost.ground + action_gain.T @ riccati)
    costate = closed_cost.T @ cost.ground + closed_phi.T @ riccati
    for lag in range(1, length):
        kernels[lag] = curvature_inverse @ action_gain.T @ costate
        costate = closed_phi.T @ costate
    return kernels


def optimal_response(
    experiment: Experiment, motion: GroundMotion, reward: RewardConfig | None = None, preview: int | None = None
) -> Response:
    """Full-state LQR plus the optimal feed-forward on the next `preview` control steps of the
    ground motion (None: the whole record), forces clipped to the limits.

    With preview=None this is the clairvoyant reference: no causal controller can do better on
    the quadratic cost. preview=0 is full-state LQR that knows nothing of the ground; preview=p
    knows the ground up to p control steps ahead, the sequence between the two.
    """
    building = build(experiment.building, experiment.actuators)
    samples, substeps = for_control_step(motion, experiment.simulation.control_dt)
    step = step_map(building, experiment.simulation, substeps)
    cost = quadratic_cost(building, reward or experiment.reward, step)
    feedback, _ = lqr_gain(step, cost, building.force_limits)
    action_gain = step.force_gain * building.force_limits
    ground_terms = step.ground_terms(samples)
    n_steps = ground_terms.shape[0]
    length = n_steps if preview is None else min(preview, n_steps)
    feedforward = np.zeros((n_steps, building.n_actuators))
    for lag, kernel in enumerate(preview_kernel(cost, step, building.force_limits, length)):
        feedforward[: n_steps - lag] += ground_terms[lag:] @ kernel.T
    states = np.zeros((n_steps + 1, step.phi.shape[0]))
    actions = np.zeros((n_steps, building.n_actuators))
    for k in range(n_steps):
        actions[k] = np.clip(-feedback @ states[k] - feedforward[k], -1.0, 1.0)
        states[k + 1] = step.phi @ states[k] + action_gain @ actions[k] + ground_terms[k]
    held = np.vstack([np.zeros((1, building.n_actuators)), actions * building.force_limits])
    time = np.arange(n_steps + 1) * step.control_dt
    return response(building, states, held, time, samples[::substeps][: n_steps + 1])
