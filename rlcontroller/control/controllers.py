"""Controllers share one interface: `reset()` before a record, then `act(observation)` -> action.

The action is what the env takes: each actuator's force as a fraction of its force limit, in
[-1, 1] (force = action * force_limit, N). Every controller reads the same observation the agent
gets (the plant's `ObservationLayout` says where each reading sits) and runs in the same simulator.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from rlcontroller.control.lqg import LQGDesign, design_lqg, design_lqg_ground_model
from rlcontroller.physics.plant import Plant


class Controller(Protocol):
    name: str

    def reset(self) -> None: ...

    def act(self, observation: np.ndarray) -> np.ndarray:
        """The action for the next control step: forces / force limits, in [-1, 1]."""
        ...


class Uncontrolled:
    """Zero force: the bare building."""

    name = "uncontrolled"

    def __init__(self, n_actuators: int) -> None:
        self._zero = np.zeros(n_actuators)

    def reset(self) -> None:
        pass

    def act(self, observation: np.ndarray) -> np.ndarray:
        return self._zero


class LQGController:
    """Kalman filter + LQR on the observation (the same readings the agent gets)."""

    def __init__(self, design: LQGDesign, plant: Plant, name: str = "LQG") -> None:
        self.design = design
        self.name = name
        self.layout = plant.layout
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
        return np.clip(action, -1.0, 1.0)


class LQGPrior:
    """The action of LQG + measured ground, or of LQG + ground model with `sensors.ground_model`
    (action units, unclipped), from an observation that holds the env's own Kalman estimate
    (`sensors.state_estimate`), for residual policies."""

    def __init__(self, plant: Plant) -> None:
        sensors = plant.experiment.sensors
        if not sensors.state_estimate:
            raise ValueError("a residual on LQG needs sensors.state_estimate: true")
        design = design_lqg_ground_model(plant) if sensors.ground_model else design_lqg(plant, known_ground=True)
        layout = plant.layout
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
