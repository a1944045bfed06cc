"""LQG with the same cost as the reward, and the clairvoyant optimal reference.

The reward of a step is -|F y_{k+1}|^2 with y_{k+1} = C_r z_{k+1} + D_r u_k and
F = diag(sqrt(weight) / scale). With the exact control-step map
z_{k+1} = Phi z_k + Gamma u_k + g_k (g_k: the ground's contribution) that is

    cost_k = |H_z z_k + H_u u_k + F C_r g_k|^2,   H_z = F C_r Phi,  H_u = F (C_r Gamma + D_r),

so Q = H_z' H_z, R = H_u' H_u, N = H_z' H_u: the discrete-time LQR of exactly the reward
(python-control's Riccati solvers, method='scipy'). Everything is designed in action units
a = u / force_limit, which keeps the Riccati equations well scaled.

The steady-state Kalman filter estimates z from the same noisy sensors the agent sees,
y_k = C_s z_k + D_s u_{k-1} + v_k (feed-through of the held force included), with the ground
acceleration as process noise; optionally the measured ground acceleration is a known input.
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np

from rlcontroller.config import Experiment, RewardConfig
from rlcontroller.dynamics import Response, StepMap, response, step_map
from rlcontroller.env import BuildingEnv, reward_matrices, sensor_matrices
from rlcontroller.excitation import GroundMotion, for_control_step
from rlcontroller.structure import Building


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
    """Gains of the LQG controller, in action units a = u / force_limit."""

    phi: np.ndarray
    action_gain: np.ndarray  # Gamma * limits
    ground_gain: np.ndarray  # response of z to a unit ground acceleration held over a step
    sensor_c: np.ndarray
    sensor_d: np.ndarray  # per unit action
    feedback: np.ndarray  # K
    feedforward: np.ndarray  # K_g (known-input variant), zero otherwise
    kalman: np.ndarray  # L (measurement update)
    known_ground: bool

    def closed_loop_eigenvalues(self) -> np.ndarray:
        return np.linalg.eigvals(self.phi - self.action_gain @ self.feedback)


def design_lqg(
    experiment: Experiment,
    known_ground: bool = False,
    ground_std: float = 1.0,
    reward: RewardConfig | None = None,
) -> LQGDesign:
    """LQG for the experiment's building, sensors and reward (or another `reward` for sweeps).

    `ground_std` (m/s^2) is the process-noise level of the ground acceleration per step; the
    sensors' `noise_std` sets the measurement noise (floored at 1e-3 of each sensor's scale).
    With `known_ground` the measured ground acceleration enters the filter and the control law.
    """
    building = BuildingEnv(experiment).building
    step = step_map(building, experiment.simulation, substeps=1)
    cost = quadratic_cost(building, reward or experiment.reward, step)
    feedback, riccati = lqr_gain(step, cost, building.force_limits)
    action_gain = step.force_gain * building.force_limits
    ground_gain = step.ground_gain.sum(axis=1)
    c, d, scale, noise = sensor_matrices(building, experiment.sensors)
    noise = np.maximum(noise, 1e-3 * scale)
    if known_ground:
        # The ground at t_k is measured; only its change over the step is unknown.
        process_std = ground_std * 0.5
        solve = cost.action.T @ cost.action + action_gain.T @ riccati @ action_gain
        feedforward = np.linalg.solve(solve, (cost.action.T @ cost.ground + action_gain.T @ riccati) @ ground_gain)[
            :, None
        ]
    else:
        process_std = ground_std
        feedforward = np.zeros((building.n_actuators, 1))
    process = process_std**2 * np.outer(ground_gain, ground_gain)
    process += 1e-12 * np.eye(process.shape[0])  # keeps the filter Riccati equation well posed
    prior, _, _ = control.dare(step.phi.T, c.T, process, np.diag(noise**2), method="scipy")
    kalman = prior @ c.T @ np.linalg.inv(c @ prior @ c.T + np.diag(noise**2))
    return LQGDesign(
        phi=step.phi,
        action_gain=action_gain,
        ground_gain=ground_gain,
        sensor_c=c,
        sensor_d=d * building.force_limits,
        feedback=feedback,
        feedforward=feedforward,
        kalman=kalman,
        known_ground=known_ground,
    )


class LQGController:
    """Kalman filter + LQR on the env's observation (the same readings the agent gets)."""

    def __init__(self, design: LQGDesign, env: BuildingEnv, name: str = "LQG") -> None:
        self.design = design
        self.name = name
        self.force_limits = env.force_limits
        scale = sensor_matrices(env.building, env.experiment.sensors)[2]
        self._readings = slice(0, scale.size)
        self._reading_scale = scale
        self._ground_index = scale.size
        self._ground_scale = env.experiment.sensors.ground_scale
        self._action = slice(env.observation_space.shape[0] - env.building.n_actuators, None)
        self.reset()

    def reset(self) -> None:
        self.estimate = np.zeros(self.design.phi.shape[0])
        self._previous_ground = 0.0
        self._first = True

    def act(self, observation: np.ndarray) -> np.ndarray:
        design = self.design
        readings = observation[self._readings] * self._reading_scale
        ground = float(observation[self._ground_index]) * self._ground_scale
        held = np.asarray(observation[self._action], dtype=float)  # the clipped action just applied
        if not self._first:
            self.estimate = design.phi @ self.estimate + design.action_gain @ held
            if design.known_ground:
                self.estimate += design.ground_gain * self._previous_ground
        self._first = False
        innovation = readings - design.sensor_c @ self.estimate - design.sensor_d @ held
        self.estimate = self.estimate + design.kalman @ innovation
        action = -design.feedback @ self.estimate - design.feedforward[:, 0] * ground
        self._previous_ground = ground
        return np.clip(action, -1.0, 1.0) * self.force_limits


def optimal_response(experiment: Experiment, motion: GroundMotion, reward: RewardConfig | None = None) -> Response:
    """The clairvoyant reference: full state and the whole ground motion known in advance.

    Stationary Riccati gain plus a backward feed-forward recursion over the record for the same
    quadratic cost, forces clipped to the limits. No causal controller can do better on that cost.
    """
    building = BuildingEnv(experiment).building
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
