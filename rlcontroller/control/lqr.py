"""The quadratic cost of the reward and its optimal full-state control: LQR and preview feed-forward.

The reward of a step is -|F y_{k+1}|^2 with y_{k+1} = C_r z_{k+1} + D_r u_k and
F = diag(sqrt(weight) / scale). With the exact control-step map
z_{k+1} = Phi z_k + Gamma u_k + g_k (g_k: the ground's contribution) that is

    cost_k = |H_z z_k + H_u u_k + F C_r g_k|^2,   H_z = F C_r Phi,  H_u = F (C_r Gamma + D_r),

so Q = H_z' H_z, R = H_u' H_u, N = H_z' H_u: the discrete-time LQR of exactly the reward
(`riccati.lqr`: scipy's solver, its residual checked). Everything is in action units
a = u / force_limit, which keeps the Riccati equations well scaled.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rlcontroller.config import RewardConfig
from rlcontroller.control.cost import reward_matrices
from rlcontroller.control.riccati import lqr
from rlcontroller.physics.dynamics import StepMap
from rlcontroller.physics.plant import Plant

DELAYED_ACTION_WEIGHT = 1.0e-4  # sqrt of the vanishing direct weight of a delayed command


@dataclass(frozen=True)
class QuadraticCost:
    """cost_k = |state z_k + action a_k + ground g_k|^2 with the matrices below."""

    state: np.ndarray  # H_z
    action: np.ndarray  # H_u (per unit action)
    ground: np.ndarray  # F C_r, applied to the ground term g_k


def quadratic_cost(
    plant: Plant, reward: RewardConfig, step: StepMap, floor_loads: bool = False
) -> QuadraticCost:
    """The reward's quadratic terms as a cost on the plant's state and action, through `step`.

    States beyond the plant's (a disturbance model's) reach the outputs only through the dynamics,
    unless `floor_loads`: then they are forces on the floors (N), felt at once by absolute accelerations."""
    building = plant.building
    terms = [term for term in reward.terms if term.quadratic]
    c, d, factor, _ = reward_matrices(plant, terms)
    weighted_c, weighted_d = factor[:, None] * c, factor[:, None] * d
    if floor_loads:
        loads = np.vstack([plant.load_outputs(term.quantity) for term in terms])
        weighted_c = np.hstack([weighted_c, factor[:, None] * loads])
    weighted_c = np.pad(weighted_c, ((0, 0), (0, step.phi.shape[0] - weighted_c.shape[1])))
    action_gain = step.force_gain * building.force_limits
    cost = QuadraticCost(
        state=weighted_c @ step.phi,
        action=weighted_c @ action_gain + weighted_d * building.force_limits,
        ground=weighted_c,
    )
    if plant.delay_steps == 0:
        return cost
    # With a delay, a command's force is paid for d steps later (through the plant's buffer states),
    # so the direct action weight is zero; a vanishing one (1e-8 per unit action) keeps R regular.
    m = building.n_actuators
    return QuadraticCost(
        state=np.vstack([cost.state, np.zeros((m, cost.state.shape[1]))]),
        action=np.vstack([cost.action, DELAYED_ACTION_WEIGHT * np.eye(m)]),
        ground=np.vstack([cost.ground, np.zeros((m, cost.ground.shape[1]))]),
    )


def lqr_gain(step: StepMap, cost: QuadraticCost, force_limits: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(K, P): a = -K z minimises the summed cost; P is the stationary Riccati solution."""
    q = cost.state.T @ cost.state
    r = cost.action.T @ cost.action
    n = cost.state.T @ cost.action
    if np.linalg.matrix_rank(r) < r.shape[0]:
        raise ValueError(
            "the reward does not penalise every actuator force (R is singular); add a force term"
        )
    return lqr(step.phi, step.force_gain * force_limits, q, r, n=n)


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


def preview_feedforward(
    cost: QuadraticCost, step: StepMap, force_limits: np.ndarray, ground_terms: np.ndarray, *, length: int
) -> np.ndarray:
    """a_ff,k = sum_{j < length} W_j g_{k+j} for ground terms g (..., K, states), without forming the
    kernels: with W_j = S^-1 B' (Phi_c')^(j-1) X for j >= 1, the tail sum v_k = X g_{k+1} + Phi_c' v_{k+1}
    runs backwards once, and a finite preview subtracts (Phi_c')^(length-1) v_{k+length-1}. O(K) instead
    of O(K length); shape (..., K, actions)."""
    n_steps = ground_terms.shape[-2]
    if length == 0:
        return np.zeros((*ground_terms.shape[:-1], force_limits.size))
    feedback, riccati = lqr_gain(step, cost, force_limits)
    action_gain = step.force_gain * force_limits
    curvature_inverse = np.linalg.inv(cost.action.T @ cost.action + action_gain.T @ riccati @ action_gain)
    closed_phi = step.phi - action_gain @ feedback
    costate = (cost.state - cost.action @ feedback).T @ cost.ground + closed_phi.T @ riccati
    first = curvature_inverse @ (cost.action.T @ cost.ground + action_gain.T @ riccati)
    tails = np.zeros_like(ground_terms)  # v_k
    projected = ground_terms @ costate.T  # X g_k
    for k in range(n_steps - 2, -1, -1):
        tails[..., k, :] = projected[..., k + 1, :] + tails[..., k + 1, :] @ closed_phi
    if length < n_steps:
        decay = np.linalg.matrix_power(closed_phi.T, length - 1)
        tails[..., : n_steps - length + 1, :] -= tails[..., length - 1 :, :] @ decay.T
    return ground_terms @ first.T + tails @ (curvature_inverse @ action_gain.T).T
