"""The MPC controllers (`control.mpc` holds the QP they solve): `MPCController` on the Kalman estimate of
LQG + ground model (under wind LQG + wind model's), `ObservedMPC` on the estimate an observation holds (as a
controller file's MPC does) and `SemiActiveMPC` for semi-active dampers, passivity as bounds; `mpc_controller`
picks the one for a plant's devices. Each counts the steps whose QP OSQP did not solve (`fallbacks`)."""

from __future__ import annotations

import numpy as np

from rlcontroller.config import RewardConfig
from rlcontroller.control.controllers import ClippedOptimal, LQGController, LQGPrior
from rlcontroller.control.lqg import design_lqg_ground_model, design_lqg_wind_model
from rlcontroller.control.mpc import (
    DEFAULT_HORIZON,
    MPCDesign,
    MPCPlanner,
    condensed_predictions,
    mpc_design,
)
from rlcontroller.physics.observation import ObservationLayout
from rlcontroller.physics.plant import Plant

REACH_TOLERANCE = 1e-3  # a planned damper force this close to its reach (action units) is at the reach
ALL_IT_GIVES = 1e30  # N: the demand of a force planned at a damper's reach


class _Planned:
    """A controller of a planner and the filter that gives it estimates (anything with `reset`)."""

    planner: MPCPlanner
    estimator: LQGController | ClippedOptimal | None

    @property
    def fallbacks(self) -> int:
        """Steps whose QP OSQP did not solve."""
        return self.planner.fallbacks

    def reset(self) -> None:
        if self.estimator is not None:
            self.estimator.reset()
        self.planner.reset()


class MPCController(_Planned):
    """MPC on the estimate of LQG + ground model's Kalman filter (under wind LQG + wind model's; the QP in
    place of its gain): `horizon` control steps; `fallbacks` counts the steps whose QP OSQP did not solve (the
    last plan's next action taken instead, or LQR's clipped action)."""

    def __init__(self, plant: Plant, horizon: int = DEFAULT_HORIZON, name: str | None = None) -> None:
        self.name = name or f"MPC (N = {horizon})"
        lqg = design_lqg_ground_model(plant) if plant.wind is None else design_lqg_wind_model(plant)
        self.estimator = LQGController(lqg, plant, self.name)  # and LQR's fallback
        self.planner = MPCPlanner(mpc_design(plant, horizon).problem())
        self.problem = self.planner.problem

    def act(self, observation: np.ndarray) -> np.ndarray:
        lqg = self.estimator
        fallback = lqg.act(observation)  # the filter steps here; LQR's clipped action
        estimates = lqg.estimate.reshape(-1, lqg.estimate.shape[-1])
        actions = self.planner.first_actions(estimates, fallback.reshape(-1, self.problem.actions))
        return actions.reshape(fallback.shape)


class ObservedMPC(_Planned):
    """MPC of `design` on the Kalman estimate the observation holds (the env's own filter, designed on the
    design model as LQG + ground model's: `sensors.state_estimate` and `ground_model`), as a controller file
    holds it; `prior` (LQR's action on that estimate) clipped is the fallback. Maps observations (..., size)
    to actions (..., m)."""

    estimator = None

    def __init__(self, design: MPCDesign, prior: LQGPrior, layout: ObservationLayout) -> None:
        self.design, self.prior, self.layout = design, prior, layout
        self.planner = MPCPlanner(design.problem())

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        observation = np.asarray(observation, dtype=float)
        rows = observation.reshape(-1, observation.shape[-1])
        estimates = rows[:, self.layout.estimate] * self.layout.estimate_scale
        actions = self.planner.first_actions(estimates, np.clip(self.prior(rows), -1.0, 1.0))
        return actions.reshape(*observation.shape[:-1], actions.shape[-1])


class SemiActiveMPC(_Planned):
    """MPC for semi-active dampers: the QP of the active equivalent (each damper an ideal actuator of its
    capacity, as clipped-optimal control designs on) with passivity as bounds, on clipped-optimal control's
    Kalman estimate (which takes the measured damper forces as applied); each damper is then switched by
    clipped-optimal control's rule towards the first planned force.

    Passivity (force u opposing the damper's velocity v, u v <= 0, and |u| within its reach) is bilinear in
    the plan, since v depends on the forces; it is approximated by fixing the sign of each step's velocity at
    its prediction from the last plan shifted by a step (from no force at a record's start): u_k in
    [-reach_k, 0] where that velocity is positive, [0, reach_k] where not. The reach is the capacity for an MR
    damper (its yield-like force) and c_max |v| for a variable damper (at most its capacity). A force planned
    at the reach asks for all the damper gives (switched on where the measured force has its sign): an MR
    damper's force exceeds its capacity by its viscous part at speed, and the plain rule would switch it off
    there. `reward`: another cost (trade-off sweeps)."""

    def __init__(
        self,
        plant: Plant,
        horizon: int = DEFAULT_HORIZON,
        name: str | None = None,
        reward: RewardConfig | None = None,
    ) -> None:
        self.name = name or f"MPC (N = {horizon})"
        self.estimator = ClippedOptimal(plant, self.name, reward)  # the filter and the switching law
        equivalent = plant.active_equivalent
        design = mpc_design(equivalent, horizon, reward)
        self.planner = MPCPlanner(design.problem())
        self.problem = self.planner.problem
        n, m = design.action_gain.shape
        dampers = [device for device in plant.experiment.devices if device.semi_active]
        self.first_damper = m - len(dampers)
        free, forced = condensed_predictions(design.phi, design.action_gain, horizon)
        c = equivalent.outputs("device_velocity")[0][:, : equivalent.building.n_states]
        velocity = np.kron(np.eye(horizon), np.pad(c[self.first_damper :], ((0, 0), (0, n - c.shape[1]))))
        self.velocity_free = velocity @ free[: horizon * n]  # v_0..v_(N-1), by step and damper
        self.velocity_forced = velocity @ forced[: horizon * n]
        # reach per unit velocity / capacity (variable dampers), or None (MR dampers: the capacity)
        self.reach_slope = [
            getattr(device, "damping_max", None) and device.damping_max / device.capacity
            for device in dampers
        ]

    def action_bounds(self, row: int, estimate: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each planned action's bounds: [-1, 1] for actuators, passivity's for dampers."""
        horizon, m = self.problem.horizon, self.problem.actions
        coming = self.planner.planned(row)
        shifted = np.zeros((horizon, m))
        if coming is not None:
            shifted[: len(coming)] = coming
        velocity = (self.velocity_free @ estimate + self.velocity_forced @ shifted.ravel()).reshape(
            horizon, -1
        )
        reach = np.ones_like(velocity)
        for j, slope in enumerate(self.reach_slope):
            if slope is not None:
                reach[:, j] = np.minimum(1.0, slope * np.abs(velocity[:, j]))
        lower, upper = -np.ones((horizon, m)), np.ones((horizon, m))
        lower[:, self.first_damper :] = np.where(velocity > 0.0, -reach, 0.0)
        upper[:, self.first_damper :] = np.where(velocity > 0.0, 0.0, reach)
        return lower.ravel(), upper.ravel()

    def act(self, observation: np.ndarray) -> np.ndarray:
        clipped = self.estimator
        measured = clipped.update(observation)
        estimates = clipped.estimate.reshape(-1, clipped.estimate.shape[-1])
        lqr = np.clip(-(estimates @ clipped.design.feedback.T), -1.0, 1.0)
        bounds = [self.action_bounds(row, estimate) for row, estimate in enumerate(estimates)]
        planned = self.planner.first_actions(estimates, lqr, bounds)
        m = self.problem.actions
        lower, upper = (np.array([bound[side][:m] for bound in bounds]) for side in (0, 1))
        # a force planned at the reach asks for all the damper gives (an MR damper's exceeds its capacity
        # by its viscous part at speed): switched on wherever the measured force has the planned sign
        at_reach = ((planned >= upper - REACH_TOLERANCE) & (upper > 0)) | (
            (planned <= lower + REACH_TOLERANCE) & (lower < 0)
        )
        desired = np.where(at_reach, np.sign(planned) * ALL_IT_GIVES, planned * clipped.capacity)
        return clipped.switch(desired.reshape(measured.shape), measured)


def mpc_controller(plant: Plant, horizon: int = DEFAULT_HORIZON) -> MPCController | SemiActiveMPC:
    """MPC for the devices of `plant` (its design model): `SemiActiveMPC` for semi-active dampers, else
    `MPCController`."""
    return (SemiActiveMPC if plant.semi_active is not None else MPCController)(plant, horizon)
