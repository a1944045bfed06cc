"""The observation every controller reads: where each value sits, and how a step updates it.

One definition for the gymnasium env, the batch and (through `ObservationLayout`) the exported ONNX
graph. An observation (float32, each value divided by its scale, so of order one) is, for p
configured readings, H = `sensors.history`, m actuators and A = `sensors.action_history`:

| indices (k = 0 newest ... H - 1; j = 0 newest ... A - 1) | what | divided by |
|---|---|---|
| k (p + 1) ... k (p + 1) + p - 1 | step t - k's readings, with noise and bias | each sensor's `scale` |
| k (p + 1) + p | step t - k's ground acceleration reading, with noise (m/s^2) | `ground_scale` |
| H (p + 1) ... H (p + 1) + E - 1 | the estimate (below) | `displacement_scale`, `velocity_scale` |
| then T = E + n, with `twin` | the fail-safe twin's estimate, each story's running peak drift (m) | ditto |
| then j m ... + m - 1 | the action applied j steps ago (after the supervisor), in [-1, 1] | 1 |

The estimate: with `state_estimate`, the Kalman estimate of [x (n floors, m); v (n, m/s)], then in an
experiment trained under wind the wind model's fluctuating floor forces (N, scaled by their design std), then
with `ground_model` the ground filter's 2 states (E = 2n, 2n + 2, 2n + floors or 2n + floors + 2); with
`integration_cutoff`, per channel (p + 1): leaky velocity, displacement, velocity (E = 3 (p + 1)); else none
(E = 0). The twin (`control.twin`, T = E + n) makes the observation the controller's whole state still: the
difference it subtracts is the estimate less the twin's estimate.

Before the motion starts the history and the actions are zero. `layout.readings` and
`layout.ground` index the newest block, `layout.estimate` the estimate, `layout.action` the newest
action and `layout.actions` all A of them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rlcontroller.config import SensorConfig
from rlcontroller.physics.motions.generators import GroundModel
from rlcontroller.physics.structure import Building


@dataclass(frozen=True)
class ObservationLayout:
    """Where the newest readings, ground reading, state estimate and last action sit in an
    observation, and the scales that turn them back into SI units."""

    readings: slice
    ground: int
    estimate: slice  # empty without `sensors.state_estimate` or `sensors.integration_cutoff`
    twin: slice  # the twin's estimate, then its running story peaks; empty without `sensors.twin`
    action: slice  # the newest action
    actions: slice  # the last `sensors.action_history` actions, newest first
    reading_scale: np.ndarray
    ground_scale: float
    estimate_scale: np.ndarray
    twin_scale: np.ndarray
    size: int

    @property
    def block(self) -> int:
        """Values per step of history: the p readings and the ground reading."""
        return self.ground + 1

    def start(self, observations: np.ndarray, readings: np.ndarray) -> None:
        """Observations (N, size) before the motion: zeros but the first scaled readings (N, p + 1)."""
        observations[:] = 0.0
        observations[:, : self.block] = readings

    def advance(self, observations: np.ndarray, readings: np.ndarray, action: np.ndarray) -> None:
        """One control step of observations (N, size), in place: the history shifts by one block and
        takes the new scaled readings (N, p + 1) first; the actions shift and take the applied action
        (N, m) first. The simulator writes the filter's new estimate (`scaled_estimate`)."""
        block, first_action, m = self.block, self.action.start, self.action.stop - self.action.start
        observations[:, block:first_action] = observations[:, : first_action - block]
        observations[:, :block] = readings
        observations[:, first_action + m : self.actions.stop] = observations[
            :, first_action : self.actions.stop - m
        ]
        observations[:, self.action] = action

    def scaled_estimate(self, estimates: np.ndarray) -> np.ndarray:
        """The filter's estimates (..., E) in SI units as they sit in the observation."""
        return estimates / self.estimate_scale

    def scaled_twin(self, twin: np.ndarray, peaks: np.ndarray) -> np.ndarray:
        """The twin's estimates (..., E) and running story peaks (..., n), SI units, as they sit in the
        observation."""
        return np.concatenate([twin, peaks], axis=-1) / self.twin_scale


def observation_layout(
    building: Building,
    sensors: SensorConfig,
    n_readings: int,
    reading_scale: np.ndarray,
    *,
    load_scale: np.ndarray | None = None,
) -> ObservationLayout:
    """The layout of the table above for `building`, `sensors` and its n_readings readings; with
    `load_scale` (N, one per floor: an experiment trained under wind) the state estimate also holds
    the fluctuating floor forces of the wind model (before the ground model's states, if both)."""
    estimate_scale = np.zeros(0)
    if sensors.integration_cutoff is not None:  # leaky velocity, displacement, velocity per channel
        channels = n_readings + 1
        estimate_scale = np.repeat(
            [sensors.velocity_scale, sensors.displacement_scale, sensors.velocity_scale], channels
        )
    if sensors.state_estimate:
        n = building.n_dofs
        estimate_scale = np.array([sensors.displacement_scale] * n + [sensors.velocity_scale] * n)
        if load_scale is not None:
            estimate_scale = np.append(estimate_scale, load_scale)
        if sensors.ground_model:
            estimate_scale = np.append(estimate_scale, GroundModel().state_scale(sensors.ground_scale))
    twin_scale = np.zeros(0)
    if sensors.twin:
        twin_scale = np.append(estimate_scale, [sensors.displacement_scale] * building.n_floors)
    estimate_start = sensors.history * (n_readings + 1)
    twin_start = estimate_start + estimate_scale.size
    action_start = twin_start + twin_scale.size
    return ObservationLayout(
        readings=slice(0, n_readings),
        ground=n_readings,
        estimate=slice(estimate_start, twin_start),
        twin=slice(twin_start, action_start),
        action=slice(action_start, action_start + building.n_actuators),
        actions=slice(action_start, action_start + sensors.action_history * building.n_actuators),
        reading_scale=reading_scale,
        ground_scale=sensors.ground_scale,
        estimate_scale=estimate_scale,
        twin_scale=twin_scale,
        size=action_start + sensors.action_history * building.n_actuators,
    )
