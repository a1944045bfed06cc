"""Model-free damping from the floor accelerations, for a building that leaves its design model behind.

A yielding building is no longer the linear model its controller and Kalman filter were designed on: once
its stories yield, the estimate's velocities lag or lead the true ones, and a force the estimate calls
dissipative can feed the building (five_story_yielding: every linear design is worse than no control on
its strongest motions, docs/assurance.md). Two supervisor stages read velocities that need no model:

- **the measured stroke velocity** of each actuator: the floors' absolute accelerations minus the ground's
  (relative floor accelerations), mapped onto the strokes by the actuator matrix and integrated through a
  leak with its corner at `INTEGRATION_CUTOFF` (the leak bounds the drift the sensors' noise and bias
  would integrate into; it leads the first mode of the five-story building, 0.69 Hz, by 8 degrees).
  `dissipative: measured` judges a force by it instead of by the estimate.
- **the fallback** (`FallbackConfig`): once any story's estimated drift passes `drift` (the estimate is
  still right at first yield: the building was elastic until then), every actuator acts for good as a
  viscous damper, force = -damping x (measured stroke velocity less a `deadband` of sensor noise). A damper
  on measured velocity takes energy out whatever the building's stiffness has become; graded from the
  lower stories up, it keeps the drift from collecting in the stories it leaves soft. The velocity is
  clipped where the first damper reaches its actuator's force limit, so past it every damper holds a force
  in the same proportion as below (stiffness-proportional dampers stay proportional to the stories'
  strengths instead of all pushing at equal limits, which moves drift into the weakest story).
"""

from __future__ import annotations

import numpy as np

from rlcontroller.config import FallbackConfig
from rlcontroller.physics.plant import Plant

# Hz: the leak's corner (the integrated sensors' default, sensors.integration_cutoff)

INTEGRATION_CUTOFF = 0.1


class MeasuredStrokeVelocity:
    """Each actuator's stroke velocity (m/s) from the floors' absolute accelerations (the observation's first
    readings, every floor, the config checks) and the ground reading, for `size` buildings."""

    def __init__(self, plant: Plant, size: int) -> None:
        layout, floors = plant.layout, plant.building.n_floors
        self.readings = slice(layout.readings.start, layout.readings.start + floors)
        self.reading_scale = layout.reading_scale[:floors]
        self.ground, self.ground_scale = layout.ground, layout.ground_scale
        self.stroke_map = plant.building.actuator_matrix[:floors]  # relative floor acceleration -> stroke's
        self.dt = plant.control_dt
        self.leak = float(np.exp(-2.0 * np.pi * INTEGRATION_CUTOFF * self.dt))
        self.velocity = np.zeros((size, self.stroke_map.shape[1]))

    def reset(self, members: int | slice | np.ndarray = slice(None)) -> None:
        self.velocity[members] = 0.0

    def update(self, observations: np.ndarray) -> np.ndarray:
        """Take in the newest readings of `observations` (size, observation size); the velocities (size,
        m)."""
        floors = observations[:, self.readings] * self.reading_scale
        relative = floors - observations[:, self.ground, None] * self.ground_scale
        self.velocity = self.leak * self.velocity + self.dt * (relative @ self.stroke_map)
        return self.velocity


class DamperFallback:
    """The fallback of `size` buildings: `__call__(observations, velocity, actions)` latches the buildings
    whose estimated story drift passes the threshold and gives their actuators the dampers' actions."""

    def __init__(self, config: FallbackConfig, plant: Plant, size: int) -> None:
        layout, n = plant.layout, plant.building.n_dofs
        self.displacements = slice(layout.estimate.start, layout.estimate.start + n)
        drift = plant.building.drift_matrix()  # story drift (m) from the displacements
        self.drift_t = (drift * layout.estimate_scale[:n]).T  # from the estimate's scaled displacements
        self.threshold = config.drift
        self.gain = np.asarray(config.damping) / plant.force_limits  # action per m/s of stroke velocity
        strongest = float(self.gain.max())
        # m/s: the first damper's limit reached
        self.saturation = 1.0 / strongest if strongest > 0.0 else np.inf
        self.deadband = config.deadband
        self.latched = np.zeros(size, dtype=bool)

    def reset(self, members: int | slice | np.ndarray = slice(None)) -> None:
        self.latched[members] = False

    def damper_actions(self, velocity: np.ndarray) -> np.ndarray:
        """The dampers' actions for stroke velocities (..., m) in m/s, their velocity clipped at
        `saturation`."""
        beyond = np.sign(velocity) * np.clip(np.abs(velocity) - self.deadband, 0.0, self.saturation)
        return -self.gain * beyond

    def __call__(self, observations: np.ndarray, velocity: np.ndarray, actions: np.ndarray) -> None:
        drift = observations[:, self.displacements] @ self.drift_t
        self.latched |= np.max(np.abs(drift), axis=1) > self.threshold
        if self.latched.any():
            actions[self.latched] = self.damper_actions(velocity[self.latched])
