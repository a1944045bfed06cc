"""Model predictive control: the experiment's quadratic cost minimised over a horizon of N control steps,
subject to the actuators' force limits and (soft) the mass devices' stroke limits, from the Kalman estimate of
LQG + ground model, or under wind of LQG + wind model; for semi-active dampers with passivity as bounds (the
controllers are in `control.mpc_controllers`). `MPCDesign` is what it is made of (model, cost, terminal
weight, stroke rows, horizon), as a controller file holds it; `MPCDesign.problem()` the QP.

With the ground model's control-step map z_{k+1} = Phi z_k + B a_k (action units a = u / force limit; the
coming ground is what the Kanai-Tajimi states predict, its unknown part zero in expectation; under wind the
wind model's, whose states are the floor forces) and the reward's cost rows (`lqr.quadratic_cost`), each step
solves

    min over a, s   sum_k |H_z z_k + H_u a_k|^2 + z_N' P z_N + sum_k,j (rho_1 s_kj + rho_2 s_kj^2 / 2)
    subject to      -1 <= a_k <= 1,   |stroke_j(z_k)| <= limit_j (1 + s_kj),   s_kj >= 0   (k = 1..N),

P the stationary Riccati solution, so that where no limit binds the first move is LQR's -K z_0 exactly. The
slack s (a stroke's excess as a fraction of its limit) keeps every problem feasible; its linear price
`STROKE_PRICE` is an exact penalty (larger than the constraint's multiplier in every test, so that a plan
that can keep the limit does), the quadratic one makes the excess unique. The predictions are condensed
(z = T z_0 + S a), leaving a QP in the N m actions (and the slacks) whose Hessian and constraint matrix are
built once, only the linear term and the stroke rows' bounds (affine in z_0) updated each step; OSQP (Stellato
et al. 2020, Math. Prog. Comp. 12) solves it, one warm-started solver per building of a batch. A step the
solver does not finish (OSQP's status neither solved nor solved inaccurate) is counted (`fallbacks`) and takes
the next action of the last plan solved, or LQR's clipped action when there is none within the horizon.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rlcontroller.config import RewardConfig
from rlcontroller.control.lqr import lqr_gain, quadratic_cost
from rlcontroller.physics.plant import Plant

DEFAULT_HORIZON = 20  # control steps (0.4 s at 20 ms): studies/mpc/horizon_sweep.py, docs/mpc.md
TOLERANCE = 1e-6  # OSQP's absolute and relative tolerances, per unit action
SOLVED = (1, 2)  # OSQP's status values of a solution: solved, solved to a lower accuracy
STROKE_PRICE = (1e3, 1e4)  # rho_1, rho_2: the cost of a stroke's excess s (fraction of its limit) per step


@dataclass(frozen=True)
class MPCProblem:
    """The condensed QP of one step over x = [a; s] (the N m actions in action units, step by step, then the
    slacks of the stroke rows): min 1/2 x' hessian x + (linear @ z_0 + offset)' x subject to
    lower + lower_gain @ z_0 <= constraints x <= upper + upper_gain @ z_0."""

    hessian: np.ndarray
    linear: np.ndarray
    offset: np.ndarray
    constraints: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    lower_gain: np.ndarray
    upper_gain: np.ndarray
    horizon: int
    actions: int

    def bounds(self, estimate: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.lower + self.lower_gain @ estimate, self.upper + self.upper_gain @ estimate


def condensed_predictions(
    phi: np.ndarray, action_gain: np.ndarray, horizon: int
) -> tuple[np.ndarray, np.ndarray]:
    """(T, S) with [z_0; ...; z_N] = T z_0 + S [a_0; ...; a_(N-1)]."""
    n, m = action_gain.shape
    free = np.zeros(((horizon + 1) * n, n))
    forced = np.zeros(((horizon + 1) * n, horizon * m))
    free[:n] = np.eye(n)
    for k in range(1, horizon + 1):
        rows, previous = slice(k * n, (k + 1) * n), slice((k - 1) * n, k * n)
        free[rows] = phi @ free[previous]
        forced[rows] = phi @ forced[previous]
        forced[rows, (k - 1) * m : k * m] += action_gain
    return free, forced


def stroke_rows(plant: Plant, size: int) -> np.ndarray:
    """Each stroke-limited mass device's stroke as a fraction of its limit, on the state z of `size`."""
    building = plant.building
    devices = getattr(building, "devices", ())
    limited = [index for index, device in enumerate(devices) if device.stroke_limit is not None]
    if not limited:
        return np.zeros((0, size))
    c = plant.outputs("stroke")[0][:, : building.n_states]  # on the building's own states
    limits = np.array([devices[index].stroke_limit for index in limited])
    rows = c[limited] / limits[:, None]
    return np.pad(rows, ((0, 0), (0, size - rows.shape[1])))


@dataclass(frozen=True)
class MPCDesign:
    """What MPC is made of, as a controller file holds it: the control-step map z' = phi z + action_gain a
    (action units; the ground model's states in z), the stage cost |cost_state z + cost_action a|^2, the
    terminal weight z_N' terminal z_N, each stroke-limited device's stroke as a fraction of its limit
    (`strokes` @ z), and the horizon (control steps)."""

    phi: np.ndarray
    action_gain: np.ndarray
    cost_state: np.ndarray
    cost_action: np.ndarray
    terminal: np.ndarray
    strokes: np.ndarray
    horizon: int

    def problem(self) -> MPCProblem:
        """The condensed QP (module docstring)."""
        horizon, phi, action_gain, cost_state, cost_action = (
            self.horizon,
            self.phi,
            self.action_gain,
            self.cost_state,
            self.cost_action,
        )
        n, m = action_gain.shape
        free, forced = condensed_predictions(phi, action_gain, horizon)
        stage_state = np.kron(np.eye(horizon), cost_state)  # H_z on z_0..z_{N-1}
        stage_action = np.kron(np.eye(horizon), cost_action)  # H_u on a_0..a_{N-1}
        stage = stage_state @ forced[: horizon * n] + stage_action
        stage_free = stage_state @ free[: horizon * n]
        last = slice(horizon * n, (horizon + 1) * n)
        action_hessian = 2.0 * (stage.T @ stage + forced[last].T @ self.terminal @ forced[last])
        action_linear = 2.0 * (stage.T @ stage_free + forced[last].T @ self.terminal @ free[last])

        strokes = np.kron(np.eye(horizon), self.strokes)  # on z_1..z_N
        slacks = strokes.shape[0]
        stroke_forced, stroke_free = strokes @ forced[n:], strokes @ free[n:]
        size = horizon * m + slacks
        hessian = np.zeros((size, size))
        hessian[: horizon * m, : horizon * m] = 0.5 * (action_hessian + action_hessian.T)
        hessian[horizon * m :, horizon * m :] = STROKE_PRICE[1] * np.eye(slacks)
        linear = np.vstack([action_linear, np.zeros((slacks, n))])
        offset = np.concatenate([np.zeros(horizon * m), np.full(slacks, STROKE_PRICE[0])])
        identity, zeros = np.eye(slacks), np.zeros((slacks, horizon * m))
        constraints = np.block(
            [
                [np.eye(horizon * m), np.zeros((horizon * m, slacks))],  # -1 <= a <= 1
                [stroke_forced, -identity],  # stroke - s <= 1
                [stroke_forced, identity],  # stroke + s >= -1
                [zeros, identity],  # s >= 0
            ]
        )
        inf, actions = np.inf, horizon * m
        lower = np.concatenate([-np.ones(actions), np.full(slacks, -inf), -np.ones(slacks), np.zeros(slacks)])
        upper = np.concatenate(
            [np.ones(actions), np.ones(slacks), np.full(slacks, inf), np.full(slacks, inf)]
        )
        gain = np.vstack([np.zeros((actions, n)), -stroke_free, -stroke_free, np.zeros((slacks, n))])
        return MPCProblem(
            hessian=hessian,
            linear=linear,
            offset=offset,
            constraints=constraints,
            lower=lower,
            upper=upper,
            lower_gain=gain,
            upper_gain=gain,
            horizon=horizon,
            actions=m,
        )


def mpc_design(plant: Plant, horizon: int = DEFAULT_HORIZON, reward: RewardConfig | None = None) -> MPCDesign:
    """MPC on `plant`'s ground-model map (under wind its wind-model map) with the experiment's cost (or
    `reward`'s), its terminal weight the stationary Riccati solution."""
    step = plant.sampled().ground_model if plant.wind is None else plant.sampled().wind_model
    cost = quadratic_cost(plant, reward or plant.experiment.reward, step, floor_loads=plant.wind is not None)
    _, riccati = lqr_gain(step, cost, plant.force_limits)
    action_gain = step.force_gain * plant.force_limits
    return MPCDesign(
        phi=step.phi,
        action_gain=action_gain,
        cost_state=cost.state,
        cost_action=cost.action,
        terminal=riccati,
        strokes=stroke_rows(plant, step.phi.shape[0]),
        horizon=horizon,
    )


class MPCPlanner:
    """The QP of `problem` solved for each building of a batch (one warm-started OSQP solver per row), with
    the last plan of each kept: `first_actions` returns each row's first planned action, or on a step OSQP did
    not solve (counted in `fallbacks`) the last plan's next action, or the given fallback action."""

    def __init__(self, problem: MPCProblem) -> None:
        self.problem = problem
        self.fallbacks = 0
        self.reset()

    def reset(self) -> None:
        """Before a record: no plans and new solvers (OSQP adapts its step size as it goes), so that a
        record's actions do not depend on the records run before it."""
        self._solvers: list = []
        self._plans: dict[int, tuple[np.ndarray, int]] = {}  # row: (its last plan's actions, steps since)

    def _solver(self, row: int):
        """The warm-started OSQP solver of the batch's `row`-th building (built on first use)."""
        import osqp  # only where MPC runs
        import scipy.sparse

        problem = self.problem
        while len(self._solvers) <= row:
            lower, upper = problem.bounds(np.zeros(problem.linear.shape[1]))
            solver = osqp.OSQP()
            solver.setup(
                P=scipy.sparse.csc_matrix(np.triu(problem.hessian)),
                q=problem.offset.copy(),
                A=scipy.sparse.csc_matrix(problem.constraints),
                l=lower,
                u=upper,
                eps_abs=TOLERANCE,
                eps_rel=TOLERANCE,
                polishing=False,
                warm_starting=True,
                verbose=False,
            )
            self._solvers.append(solver)
        return self._solvers[row]

    def plan(self, row: int, estimate: np.ndarray, action_bounds: tuple | None = None) -> np.ndarray | None:
        """The solution [a; s] of the QP from `estimate` for the batch's `row`-th building (the actions within
        `action_bounds`, (lower, upper) per planned action, instead of [-1, 1] if given), or None when OSQP
        did not solve it."""
        solver = self._solver(row)
        lower, upper = self.problem.bounds(estimate)
        if action_bounds is not None:
            size = self.problem.horizon * self.problem.actions
            lower[:size], upper[:size] = action_bounds
        solver.update(q=self.problem.linear @ estimate + self.problem.offset, l=lower, u=upper)
        result = solver.solve(raise_error=False)
        self.last_solve_time = result.info.solve_time  # s, OSQP's own (scripts/bench_mpc.py)
        return result.x if result.info.status_val in SOLVED else None

    def planned(self, row: int) -> np.ndarray | None:
        """The rest of the last plan of `row` (actions by step, from the coming one), or None."""
        if row not in self._plans:
            return None
        previous, since = self._plans[row]
        return previous[since + 1 :]

    def first_actions(
        self, estimates: np.ndarray, fallback: np.ndarray, action_bounds: list | None = None
    ) -> np.ndarray:
        """Each row's action (action units) from its estimate; `fallback` (rows, m) where no plan is left."""
        m = self.problem.actions
        actions = fallback.copy()
        for row, estimate in enumerate(estimates):
            plan = self.plan(row, estimate, None if action_bounds is None else action_bounds[row])
            if plan is not None:
                self._plans[row] = (np.clip(plan[: self.problem.horizon * m], -1.0, 1.0).reshape(-1, m), 0)
            elif row in self._plans and self._plans[row][1] + 1 < self.problem.horizon:
                previous, since = self._plans[row]
                self._plans[row] = (previous, since + 1)
                self.fallbacks += 1
            else:
                self._plans.pop(row, None)
                self.fallbacks += 1
                continue
            previous, since = self._plans[row]
            actions[row] = previous[since]
        return actions
