"""Yielding stories: the Bouc-Wen model and its integrator over one control step.

Story i (drift d_i = x_i - x_{i-1}) resists with F_i = a k_i d_i + (1 - a) k_i d_y,i z_i, where

    z_i' = (d_i' / d_y,i) [1 - |z_i|^n (beta sgn(d_i' z_i) + gamma)],   beta + gamma = 1,

so |z| -> 1 once the story yields. With the drift matrix D (d = D x) the floors obey

    M v' = -C v - D' F + Gamma u - M 1 a_g,   x' = v,

on the state s = [x; v; z] (m, m/s, -). The force u is held over the control step and the ground
acceleration is linear between its samples, as in the linear plant; classical RK4 with `substeps`
steps per ground-sample interval, compiled with numba in `integrators.py` (`scripts/bench_env.py`
measures it against the same code run by the interpreter). a = 1 is the linear shear building.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rlcontroller.config import HysteresisConfig
from rlcontroller.physics.structure import Building


@dataclass(frozen=True)
class BoucWen:
    """Bouc-Wen stories of a building: everything the integrator needs, as arrays (SI)."""

    floor_gain: np.ndarray  # Gamma times the force limits (n, m): actions to floor forces (N)
    mass_inverse: np.ndarray  # (n,) 1/m_i
    damping: np.ndarray  # C (n, n)
    linear_stiffness: np.ndarray  # a k_i (n,)
    hysteretic_stiffness: np.ndarray  # (1 - a) k_i d_y,i (n,): the story force at z = 1 beyond a k d
    yield_drift: np.ndarray  # d_y,i (n,)
    exponent: float
    beta: float
    gamma: float
    substeps: int

    @classmethod
    def of(cls, building: Building, config: HysteresisConfig, story_stiffness: np.ndarray) -> BoucWen:
        n = building.n_floors
        yield_drift = np.broadcast_to(np.asarray(config.yield_drift, dtype=float), n).copy()
        alpha = config.post_yield_ratio
        return cls(
            floor_gain=building.actuator_matrix * building.force_limits,
            mass_inverse=1.0 / np.diag(building.mass),
            damping=building.damping,
            linear_stiffness=alpha * story_stiffness,
            hysteretic_stiffness=(1.0 - alpha) * story_stiffness * yield_drift,
            yield_drift=yield_drift,
            exponent=config.exponent,
            beta=config.beta,
            gamma=config.gamma,
            substeps=config.substeps,
        )

    def step(self, state: np.ndarray, action: np.ndarray, ground: np.ndarray, control_dt: float) -> np.ndarray:
        """The state after one control step: the action (forces / force limits) held, `ground` the
        r + 1 ground samples (m/s^2) spanning the step."""
        from rlcontroller.physics.integrators import bouc_wen_step  # numba: imported when first needed

        return bouc_wen_step(
            state,
            self.floor_gain @ action,
            ground,
            control_dt,
            self.substeps,
            self.mass_inverse,
            self.damping,
            self.linear_stiffness,
            self.hysteretic_stiffness,
            self.yield_drift,
            self.exponent,
            self.beta,
            self.gamma,
        )
