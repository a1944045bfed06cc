"""Model predictive control: the experiment's quadratic cost minimised over a horizon of N control steps, subject
to the actuators' force limits, from the Kalman estimate of LQG + ground model.

With the ground model's control-step map z_{k+1} = Phi z_k + B a_k (action units a = u / force limit; the coming
ground is what the Kanai-Tajimi states predict, its unknown part zero in expectation) and the reward's cost
rows (`lqr.quadratic_cost`), each step solves

    min over a_0..a_{N-1}   sum_k |H_z z_k + H_u a_k|^2 + z_N' P z_N    subject to  -1 <= a_k <= 1,

P the stationary Riccati solution, so that where no limit binds the first move is LQR's -K z_0 exactly. The
predictions are condensed (z = T z_0 + S a), leaving a dense QP in the N m actions: 1/2 a' H a + (F z_0)' a,
H and F built once; OSQP (Stellato et al. 2020, Math. Prog. Comp. 12) solves it, one warm-started solver per
building of a batch, only the linear term updated each step. A step the solver does not finish falls back to
LQR's clipped action and is counted (`fallbacks`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rlcontroller.config import RewardConfig
from rlcontroller.control.controllers import LQGController
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.control.lqr import lqr_gain, quadratic_cost
from rlcontroller.physics.plant import Plant

DEFAULT_HORIZON = 20  # control steps (0.4 s at 20 ms)
TOLERANCE = 1e-6  # OSQP's absolute and relative tolerances, per unit action


@dataclass(frozen=True)
class MPCProblem:
    """The condensed QP of one step: 1/2 a' hessian a + (linear @ z_0)' a over the N m actions (action units,
    step by step), each in [-1, 1]."""

    hessian: np.ndarray
    linear: np.ndarray
    horizon: int
    actions: int


def mpc_problem(plant: Plant, horizon: int = DEFAULT_HORIZON, reward: RewardConfig | None = None) -> MPCProblem:
    """The QP of MPC on `plant`'s ground-model map with the experiment's cost (or `reward`'s)."""
    step = plant.ground_model_step()
    cost = quadratic_cost(plant, reward or plant.experiment.reward, step)
    _, riccati = lqr_gain(step, cost, plant.force_limits)
    phi, action_gain = step.phi, step.force_gain * plant.force_limits
    n, m = action_gain.shape
    free = np.zeros(((horizon + 1) * n, n))  # T: z_k from z_0
    forced = np.zeros(((horizon + 1) * n, horizon * m))  # S: z_k from the actions
    free[:n] = np.eye(n)
    for k in range(1, horizon + 1):
        rows, previous = slice(k * n, (k + 1) * n), slice((k - 1) * n, k * n)
        free[rows] = phi @ free[previous]
        forced[rows] = phi @ forced[previous]
        forced[rows, (k - 1) * m : k * m] += action_gain
    stage_state = np.kron(np.eye(horizon), cost.state)  # H_z on z_0..z_{N-1}
    stage_action = np.kron(np.eye(horizon), cost.action)  # H_u on a_0..a_{N-1}
    stage = stage_state @ forced[: horizon * n] + stage_action
    stage_free = stage_state @ free[: horizon * n]
    last = slice(horizon * n, (horizon + 1) * n)
    hessian = 2.0 * (stage.T @ stage + forced[last].T @ riccati @ forced[last])
    linear = 2.0 * (stage.T @ stage_free + forced[last].T @ riccati @ free[last])
    return MPCProblem(hessian=0.5 * (hessian + hessian.T), linear=linear, horizon=horizon, actions=m)


class MPCController:
    """MPC on the estimate of LQG + ground model's Kalman filter (the same filter, the QP in place of its gain):
    `horizon` control steps; `fallbacks` counts the steps whose QP OSQP did not solve (LQR's clipped action
    taken instead)."""

    def __init__(self, plant: Plant, horizon: int = DEFAULT_HORIZON, name: str | None = None) -> None:
        self.name = name or f"MPC (N = {horizon})"
        self.lqg = LQGController(design_lqg_ground_model(plant), plant, self.name)  # the filter, and the fallback
        self.problem = mpc_problem(plant, horizon)
        self.fallbacks = 0
        self._solvers: list = []

    def reset(self) -> None:
        self.lqg.reset()

    def _solver(self, row: int):
        """The warm-started OSQP solver of the batch's `row`-th building (built on first use)."""
        import osqp  # only where MPC runs
        import scipy.sparse

        while len(self._solvers) <= row:
            size = self.problem.hessian.shape[0]
            solver = osqp.OSQP()
            solver.setup(
                P=scipy.sparse.csc_matrix(np.triu(self.problem.hessian)),
                q=np.zeros(size),
                A=scipy.sparse.identity(size, format="csc"),
                l=-np.ones(size),
                u=np.ones(size),
                eps_abs=TOLERANCE,
                eps_rel=TOLERANCE,
                polishing=False,
                warm_starting=True,
                verbose=False,
            )
            self._solvers.append(solver)
        return self._solvers[row]

    def act(self, observation: np.ndarray) -> np.ndarray:
        fallback = self.lqg.act(observation)  # the filter steps here; LQR's clipped action
        estimates = self.lqg.estimate.reshape(-1, self.lqg.estimate.shape[-1])
        actions = fallback.reshape(-1, self.problem.actions).copy()
        for row, estimate in enumerate(estimates):
            solver = self._solver(row)
            solver.update(q=self.problem.linear @ estimate)
            result = solver.solve(raise_error=False)
            if result.info.status_val == 1:  # solved
                actions[row] = np.clip(result.x[: self.problem.actions], -1.0, 1.0)
            else:
                self.fallbacks += 1
        return actions.reshape(fallback.shape)
