"""The supervisory layer between a controller and the actuators (`supervisor:` in an experiment).

Real active control systems do not pass a controller's command straight to the actuators: they stay
off until the ground shakes noticeably and they guard against a command that would do harm. The
supervisor does both, from the same observation the controller read, for every controller of an
experiment alike (LQG, learned, uncontrolled), so comparisons stay fair:

- **trigger** [start, full] (m/s²): the action is scaled by a gain that is 0 while the largest
  ground reading so far (noise included) is below `start`, rises linearly, and is 1 from `full` on.
  Sensor noise alone (0.05 m/s² per reading) then never drives the building. In an experiment trained
  under wind, which the ground reading does not see, the largest of the floors' absolute accelerations
  instead (`trigger_readings`): what wind and earthquakes both move.
- **dissipative**: an actuator's force passes only when it takes energy out of the building,
  u_j (Γ_jᵀ v) ≤ 0 with Γ the actuator matrix and v the filter's estimate of the floor velocities
  (relative to the ground); otherwise that actuator's action is 0. For an inter-story actuator this
  is a force opposing the estimated story velocity, as a damper's does. With `fade_velocity` v_f
  (m/s) the rule is continuous: a force that would feed energy in is scaled by
  max(0, 1 - |Γ_jᵀ v| / v_f) instead, so it passes near a velocity reversal and fades out as the
  story moves faster the wrong way. The hard rule switches the force off at every reversal, and a
  force step is a floor-acceleration step (docs/safety_check.md, the supervisor study).
- **dissipative: measured**: the same rule on each stroke's velocity integrated from the floor
  accelerations (`control.fallback`: no model, so it holds where the building yields).
- **fallback**: once any story's estimated drift passes a level, every actuator acts for good as a
  viscous damper on its measured stroke velocity (`control.fallback`).
- **assurance**: runtime assurance against the fail-safe twin (`control.assurance`), last: it sees the
  action the actuators would receive and may hand the devices back to their fail-safe action.
"""

from __future__ import annotations

import numpy as np

from rlcontroller.config import SupervisorConfig
from rlcontroller.control.assurance import RuntimeAssurance
from rlcontroller.control.fallback import DamperFallback, MeasuredStrokeVelocity
from rlcontroller.physics.plant import Plant


class Supervisor:
    """The supervisor of `size` buildings of one plant: `reset(members)` at each start, then
    `__call__(observations, actions)` turns the actions (size, m) in [-1, 1], in place, into those
    the actuators receive."""

    def __init__(self, config: SupervisorConfig, plant: Plant, size: int) -> None:
        layout, n = plant.layout, plant.building.n_dofs
        self.trigger = config.trigger
        self.trigger_indices, self.trigger_scales = trigger_readings(plant)
        self.velocity = None
        self.dissipative = config.dissipative
        self.fade = config.fade_velocity  # m/s (measured) or in the estimate's scaled units
        if config.dissipative is True:
            start = layout.estimate.start + n  # the estimate is [x; v (; ground filter)], scaled
            self.velocity = slice(start, start + n)
            # Γ: v @ Γ is each actuator's stroke velocity
            self.actuator_matrix = plant.building.actuator_matrix
            self.fade = config.fade_velocity / layout.estimate_scale[n]
        self.measured = MeasuredStrokeVelocity(plant, size) if config.measured else None
        self.fallback = None if config.fallback is None else DamperFallback(config.fallback, plant, size)
        self.peak_ground = np.zeros(size)
        self.assurance = None if config.assurance is None else RuntimeAssurance(config.assurance, plant, size)

    def reset(self, members: int | slice | np.ndarray = slice(None)) -> None:
        self.peak_ground[members] = 0.0
        for stage in (self.measured, self.fallback):
            if stage is not None:
                stage.reset(members)
        if self.assurance is not None:
            self.assurance.reset(members)

    def gain(self, observations: np.ndarray) -> np.ndarray:
        """The trigger's gain per building, (size,), after taking in the newest readings it watches."""
        if self.trigger_indices.size == 1:  # the ground reading: a column, no copy through an index array
            newest = np.abs(observations[:, self.trigger_indices[0]]) * self.trigger_scales[0]
        else:
            newest = np.max(np.abs(observations[:, self.trigger_indices] * self.trigger_scales), axis=1)
        np.maximum(self.peak_ground, newest, out=self.peak_ground)
        start, full = self.trigger
        if full == start:
            return (self.peak_ground >= full).astype(float)
        return np.minimum(np.maximum((self.peak_ground - start) / (full - start), 0.0), 1.0)

    def __call__(self, observations: np.ndarray, actions: np.ndarray) -> None:
        measured = None if self.measured is None else self.measured.update(observations)
        if self.dissipative:
            if self.velocity is not None:
                # scaled (one scale for all)
                stroke_velocity = observations[:, self.velocity] @ self.actuator_matrix
            else:
                stroke_velocity = measured
            # every entry times 1 where the force takes energy out, else its fade factor: arithmetic on every
            # entry costs less per step than writing through a boolean mask
            feeding = actions * stroke_velocity > 0.0
            if self.fade > 0.0:
                faded = np.maximum(1.0 - np.abs(stroke_velocity) / self.fade, 0.0)
                actions *= np.where(feeding, faded, 1.0)
            else:
                np.copyto(actions, 0.0, where=feeding)
        if self.fallback is not None:
            self.fallback(observations, measured, actions)
        if self.trigger is not None:
            actions *= self.gain(observations)[:, None]
        if self.assurance is not None:
            self.assurance(observations, actions)


def trigger_readings(plant: Plant) -> tuple[np.ndarray, np.ndarray]:
    """Where in an observation the trigger reads (the newest block) and those readings' scales (m/s^2): the
    ground reading, or in an experiment trained under wind every floor absolute acceleration read (the ground
    reading still where it reads none)."""
    layout = plant.layout
    ground = np.array([layout.ground]), np.array([layout.ground_scale])
    if plant.wind is None:
        return ground
    indices, scales, start = [], [], 0
    for measurement in plant.experiment.sensors.measurements:
        floors = measurement.floors
        rows = plant.outputs(measurement.quantity)[0].shape[0] if floors is None else len(floors)
        if measurement.quantity == "absolute_acceleration":
            indices.extend(range(start, start + rows))
            scales.extend([measurement.scale] * rows)
        start += rows
    return (np.array(indices), np.array(scales)) if indices else ground


def supervisor(plant: Plant, size: int) -> Supervisor | None:
    """The experiment's supervisor for `size` buildings, or None when it has none."""
    config = plant.experiment.supervisor
    return None if config is None else Supervisor(config, plant, size)
