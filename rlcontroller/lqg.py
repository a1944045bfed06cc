"""LQG with the same cost as the reward, and the clairvoyant optimal reference.

The reward of a step is -|F y_{k+1}|^2 with y_{k+1} = C_r z_{k+1} + D_r u_k and
F = diag(sqrt(weight) / scale). With the exact control-step map
z_{k+1} = Phi z_k + Gamma u_k + g_k (g_k: the ground's contribution) that is

    cost_k = |H_z z_k + H_u u_k + F C_r g_k|^2,   H_z = F C_r Phi,  H_u = F (C_r Gamma + D_r),

so Q = H_z' H_z, R = H_u' H_u, N = H_z' H_u: the discrete-time LQR of exactly the reward
(python-control's Riccati solvers, method='scipy'). Everything is designed in action units
a = u / force_limit, which keeps the Riccati equations well scaled.

The steady-state Kalman filter (`estimation`) estimates z from the same noisy sensors the agent
sees, with the feed-through of the held force; optionally the measured ground acceleration is a
known input.
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np

from rlcontroller.config import Experiment, RewardConfig
from rlcontroller.dynamics import Response, StepMap, response, reward_matrices, step_map
from rlcontroller.env import BuildingEnv
from rlcontroller.estimation import KalmanFilter, design_kalman
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
    feedback, riccati = lqr_gain(step, cost, building.force_limits)
    kalman = design_kalman(building, experiment.sensors, experiment.simulation, known_ground, ground_std)
    feedforward = np.zeros(building.n_actuators)
    if known_ground:
        action_gain = kalman.action_gain
        curvature = cost.action.T @ cost.action + action_gain.T @ riccati @ action_gain
        feedforward = np.linalg.solve(
            curvature, (cost.action.T @ cost.ground + action_gain.T @ riccati) @ kalman.ground_gain
        )
    return LQGDesign(feedback=feedback, feedforward=feedforward, filter=kalman)


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
        estimate = self.design.filter.update(readings, held, self._previous_ground)
        self._previous_ground = ground
        action = -self.design.feedback @ estimate - self.design.feedforward * ground
        return np.clip(action, -1.0, 1.0) * self.force_limits


class LQGPrior:
    """The action of LQG + measured ground (action units, unclipped) from an observation that holds
    the env's own Kalman estimate (`sensors.state_estimate`), for residual policies."""

    def __init__(self, experiment: Experiment) -> None:
        env = BuildingEnv(experiment)
        if env.kalman is None:
            raise ValueError("a residual on LQG needs sensors.state_estimate: true")
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


def optimal_response(experiment: Experiment, motion: GroundMotion, reward: RewardConfig | None = None) -> Response:
    """The clairvoyant reference: full state and the whole ground motion known in advance.

    Stationary Riccati gain plus a backward feed-forward recursion over the record for the same
    quadratic cost, forces clipped to the limits. No causal controller can do better on that cost.
    """
    building = build(experiment.building, experiment.actuators)
    samples, substeps = for_control_step(motion, experiment.simulation.control_dt)
    step = step_map(building, experiment.simulation, substeps)
    cost = quadratic_cost(building, reward or experiment.reward, step)
    feedback, riccati = lqr_gain(step, cost, building.force_limits)
    action_gain = step.force_gain * building.force_limits
    ground_terms = step.ground_terms(samples)
    n_steps = ground_terms.shape[0]
    solve = cost.action.T @ cost.action + action_gain.T @ riccati @ action_gain
    closed_state = cost.state - cost.action @ feedback
    closed_phi = step.phi - action_gain @ feedback
    feedforward = np.zeros((n_steps, building.n_actuators))
    linear = np.zeros(step.phi.shape[0])  # b_{k+1}, zero after the record
    for k in range(n_steps - 1, -1, -1):
        g, h = ground_terms[k], cost.ground @ ground_terms[k]
        f = np.linalg.solve(solve, cost.action.T @ h + action_gain.T @ (riccati @ g + linear))
        feedforward[k] = f
        linear = closed_state.T @ (h - cost.action @ f) + closed_phi.T @ (riccati @ (g - action_gain @ f) + linear)
    states = np.zeros((n_steps + 1, step.phi.shape[0]))
    actions = np.zeros((n_steps, building.n_actuators))
    for k in range(n_steps):
        actions[k] = np.clip(-feedback @ states[k] - feedforward[k], -1.0, 1.0)
        states[k + 1] = step.phi @ states[k] + action_gain @ actions[k] + ground_terms[k]
    held = np.vstack([np.zeros((1, building.n_actuators)), actions * building.force_limits])
    time = np.arange(n_steps + 1) * step.control_dt
    return response(building, states, held, time, samples[::substeps][: n_steps + 1])
