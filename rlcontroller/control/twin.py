"""The fail-safe twin: what the building would do with its devices failed safe, estimated inside the
controller from the same readings.

On a linear design model the controlled building is the building failed safe plus its response x_u to
the forces the controller applied (superposition). The controller knows those forces, so it knows x_u
exactly: x_u' = Φ x_u + Γ a from x_u = 0 (Φ, Γ: the observation filter's model at the control step, Γ
per unit action a, the action the actuators received). The twin's estimate is the observation's Kalman
estimate less x_u, which is exactly the Kalman filter of the building failed safe fed the readings it
would give: a filter, not an open-loop simulation of the ground readings, so it carries no drift of its
own. It holds where the design model does (a yielding building leaves it behind) and for forces only:
a semi-active damper's command is not a force (config checks refuse it).

Used by runtime assurance (`control.assurance`) and, with `sensors.twin`, by the observation
(`physics.observation`): the twin's estimate and each story's running peak drift under it.
"""

from __future__ import annotations

import numpy as np

from rlcontroller.control.estimation import observation_filter
from rlcontroller.physics.plant import Plant


class FailSafeTwin:
    """The twin of `size` buildings of one plant: `reset(members)` at each start, `advance(actions)` once
    every building's actuator actions (size, m) in [-1, 1] are known, `observe(estimates, members)` once the
    observation's Kalman estimates (k, E, SI units) of the next step are."""

    def __init__(self, plant: Plant, size: int) -> None:
        kalman = observation_filter(plant)  # the observation's own (`sensors.state_estimate`: config checks)
        building = plant.building
        self.phi_t = kalman.phi.T
        self.gamma_t = kalman.action_gain.T
        self.drift_t = np.zeros((kalman.size, building.n_floors))  # story drifts (m) from an estimate
        self.drift_t[: building.n_dofs] = building.drift_matrix().T
        self.difference = np.zeros((size, kalman.size))  # x_u
        self.peak = np.zeros((size, building.n_floors))  # each story's running peak drift under the twin (m)

    def reset(self, members: int | slice | np.ndarray = slice(None)) -> None:
        self.difference[members] = 0.0
        self.peak[members] = 0.0

    def advance(self, actions: np.ndarray) -> None:
        """x_u over the step on which the actuators hold `actions`."""
        self.difference = self.difference @ self.phi_t + actions @ self.gamma_t

    def observe(
        self, estimates: np.ndarray, members: int | slice | np.ndarray = slice(None)
    ) -> tuple[np.ndarray, np.ndarray]:
        """The twin's estimates (k, E) and running story peak drifts (k, n stories, m) at the estimates'
        step; the peaks take this step's drifts in."""
        twin = estimates - self.difference[members]
        self.peak[members] = np.maximum(self.peak[members], np.abs(twin @ self.drift_t))
        return twin, self.peak[members]

    def restore(self, estimates: np.ndarray, twin: np.ndarray, peaks: np.ndarray) -> None:
        """Every member's state from an observation's estimate, twin estimate and peaks (SI units): the
        difference is the estimate less the twin's."""
        self.difference[:] = estimates - twin
        self.peak[:] = peaks
