"""Runtime assurance (the Simplex architecture): a fail-safe twin inside the controller and a switching rule
that hands the devices back to their fail-safe action when the controlled building is about to do worse
than the twin.

**The twin** (`control.twin`): the observation's Kalman estimate less the controller's own response x_u
to the forces it applied, the Kalman filter of the building failed safe.

**The switching rule**, per building and step, on story drift ratios δ = drift / height:

- the envelope of each story's motion, e = sqrt(δ² + (δ'/ω₁)²) (ω₁ the design model's first mode,
  rad/s): the peak it reaches within half a cycle if no new load or force comes in;
- the *risk* is the largest over stories of the controlled envelope over the larger of the twin's
  envelope and the twin's running peak |δ| so far: the controlled building's next peak against the
  reference's peak so far or about to come;
- the proposer's action passes while engaged; it disengages when the risk exceeds `release` and is
  engaged again when the risk falls below `engage` (hysteresis). It starts engaged: with x_u = 0 the
  risk is exactly 1;
- disengaged, the devices steer the difference x_u back to zero (a = -K x_u, clipped; K the design's
  LQR gain on the experiment's cost): the building rejoins the reference's own trajectory rather than
  ringing on in another state than the reference's.

The applied action (after the previous supervisor stages and this one) drives x_u, so the twin sees exactly
what the actuators received.
"""

from __future__ import annotations

import numpy as np

from rlcontroller.config import AssuranceConfig
from rlcontroller.control.lqr import lqr_gain, quadratic_cost
from rlcontroller.control.twin import FailSafeTwin
from rlcontroller.physics.plant import Plant


class RuntimeAssurance:
    """The twin and the switching rule of `size` buildings of one plant: `reset(members)` at each start,
    then `__call__(observations, actions)` turns the proposed actions (size, m) in [-1, 1], in place, into
    the ones the actuators receive."""

    def __init__(self, config: AssuranceConfig, plant: Plant, size: int) -> None:
        design, building = plant.design, plant.building
        self.twin_model = twin = FailSafeTwin(plant, size)
        n, floors, states = building.n_dofs, building.n_floors, twin.phi_t.shape[0]
        self.scale = plant.layout.estimate_scale
        self.estimate = plant.layout.estimate
        heights = building.story_heights if building.story_heights is not None else np.ones(floors)
        self.drift_t = twin.drift_t / heights  # story drift ratios from an estimate
        self.velocity_t = np.zeros((states, floors))
        self.velocity_t[n : 2 * n] = self.drift_t[:n] / (2.0 * np.pi / design.building.periods()[0])
        self.feedback_t = self._recovery_gain(design, states).T
        self.release, self.engage = config.release, config.engage
        self.floor = config.floor  # drift ratio below which a running peak counts as this
        self.peak = np.zeros((size, floors))
        self.engaged = np.ones(size, dtype=bool)

    @staticmethod
    def _recovery_gain(design: Plant, size: int) -> np.ndarray:
        """K (m, size): the design's LQR on the experiment's cost, padded to the filter's state."""
        step = design.sampled().step
        gain, _ = lqr_gain(
            step, quadratic_cost(design, design.experiment.reward, step), design.building.force_limits
        )
        padded = np.zeros((gain.shape[0], size))
        padded[:, : gain.shape[1]] = gain
        return padded

    def reset(self, members: int | slice | np.ndarray = slice(None)) -> None:
        self.twin_model.reset(members)
        self.peak[members] = 0.0
        self.engaged[members] = True

    def twin(self, observations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(controlled, twin) estimates (size, E) in SI units."""
        controlled = observations[:, self.estimate].astype(float) * self.scale
        return controlled, controlled - self.twin_model.difference

    def risk(self, controlled: np.ndarray, twin: np.ndarray) -> np.ndarray:
        """The largest over stories of the controlled envelope over the twin's envelope or running peak."""

        def envelope(z: np.ndarray) -> np.ndarray:
            return np.hypot(z @ self.drift_t, z @ self.velocity_t)

        np.maximum(self.peak, np.abs(twin @ self.drift_t), out=self.peak)
        reference = np.maximum(np.maximum(envelope(twin), self.peak), self.floor)
        return (envelope(controlled) / reference).max(axis=1)

    def __call__(self, observations: np.ndarray, actions: np.ndarray) -> None:
        controlled, twin = self.twin(observations)
        risk = self.risk(controlled, twin)
        self.engaged = np.where(self.engaged, risk <= self.release, risk < self.engage)
        recovering = ~self.engaged
        if recovering.any():
            actions[recovering] = np.clip(
                -self.twin_model.difference[recovering] @ self.feedback_t, -1.0, 1.0
            )
        self.twin_model.advance(actions)
