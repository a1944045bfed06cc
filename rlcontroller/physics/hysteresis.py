"""Yielding stories: the Bouc-Wen model and its integrator over one control step.

Each story has a spring that yields: its stiffness k_i is the story's as a first-mode pushover sees it,
story shear over story drift under the forces M phi_1 (for a shear building, its story stiffness). What
the stiffness matrix K holds beyond these springs, K - D' diag(k) D, stays linear: nothing for a shear
building, the frame action of a condensed FE model (it carries no load in the first mode's shape; for
the nine-story frame it is positive semi-definite, so no post-yield ratio makes it unstable, where
reading the coupling of adjacent floors as the story springs, as Patsialis & Taflanidis 2020 do, leaves
it indefinite below a = 0.65). A building whose yielded stiffness K - D' diag((1 - a) k) D would not be
positive semi-definite is refused, unless a story's a is negative (losing strength is then the point). Story
i's spring (drift d_i = x_i - x_{i-1}) resists with F_i = a_i k_i d_i + (1 - a_i) k_i d_y,i z_i, where

    z_i' = (d_i' / d_y,i) [1 - |z_i|^n_i (beta_i sgn(d_i' z_i) + gamma_i)],   beta_i + gamma_i = 1,

so |z| -> 1 once the story yields; a < 0 (P-Delta past yield) makes the story lose strength, and a story
whose drift reaches its collapse drift has collapsed: the building stays as it lies, at rest. With the drift
matrix D (d = D x) the floors obey

    M v' = -C v - K_e x - D' h z + Gamma u - M 1 a_g,   x' = v,

K_e = K - D' diag((1 - a) k) D (the springs that stay linear), h = (1 - a) k d_y, on the state
s = [x; v; z] (m, m/s, -). The force u is held over the control step and the ground acceleration is
linear between its samples, as in the linear plant; classical RK4 with `substeps` steps per
ground-sample interval, compiled with numba in `integrators.py` (`scripts/bench_env.py` measures it
against the same code run by the interpreter). a = 1 is the linear building.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from rlcontroller.config import HysteresisConfig
from rlcontroller.physics.structure import Building


def story_springs(mass: np.ndarray, stiffness: np.ndarray) -> np.ndarray:
    """Each story's stiffness (N/m) as a first-mode pushover sees it: story shear over story drift under
    the floor forces M phi_1, from the floors' mass and stiffness matrices (n, n)."""
    import scipy.linalg

    _, shapes = scipy.linalg.eigh(stiffness, mass, subset_by_index=[0, 0])
    forces = mass @ shapes[:, 0]
    drift = drift_matrix(len(forces)) @ np.linalg.solve(stiffness, forces)
    return np.cumsum(forces[::-1])[::-1] / drift


def drift_matrix(n: int) -> np.ndarray:
    """D with d = D x: story drifts (floor minus the floor below) from floor displacements."""
    return np.eye(n) - np.eye(n, k=-1)


def per_story(value: float | list[float], n: int) -> np.ndarray:
    """A scalar or a list of one value per story, as an array of n."""
    return np.broadcast_to(np.asarray(value, dtype=float), n).copy()


class BoucWenArrays(NamedTuple):
    """The arrays the Bouc-Wen kernels take after their leading arguments, in their order (a test pins it to
    the kernels' own parameter names: `integrators.bouc_wen_step`, `bouc_wen_history`)."""

    mass_inverse: np.ndarray  # 1/kg per floor
    damping: np.ndarray  # N s/m, (n, n)
    linear: np.ndarray  # N/m, (n, n): the post-yield part of the story springs
    hysteretic: np.ndarray  # N/m per story: (1 - a) k
    yield_drift: np.ndarray  # m per story
    exponent: np.ndarray
    beta: np.ndarray
    gamma: np.ndarray
    collapse: np.ndarray  # m per story (inf: none)


@dataclass(frozen=True)
class BoucWen:
    """Bouc-Wen stories of a building: everything the integrator needs, as arrays (SI)."""

    floor_gain: np.ndarray  # Gamma times the force limits (n, m): actions to floor forces (N)
    mass_inverse: np.ndarray  # (n,) 1/m_i
    damping: np.ndarray  # C (n, n)
    linear_stiffness: np.ndarray  # K_e (n, n): the springs that stay linear, a k d of the stories' among them
    hysteretic_stiffness: np.ndarray  # (1 - a) k d_y (n,): the story force at z = 1 beyond a k d
    yield_drift: np.ndarray  # d_y,i (n,)
    exponent: np.ndarray  # n_i (n,)
    beta: np.ndarray  # (n,)
    gamma: np.ndarray  # (n,)
    collapse_drift: np.ndarray  # (n,) m: past it a story has collapsed (inf: never)
    substeps: int

    @classmethod
    def of(cls, building: Building, config: HysteresisConfig) -> BoucWen:
        n = building.n_floors
        stiffness = building.stiffness[:n, :n]
        springs = story_springs(building.mass[:n, :n], stiffness)
        yield_drift = per_story(config.yield_drift, n)
        yielding = (1.0 - per_story(config.post_yield_ratio, n)) * springs
        drift = building.drift_matrix()  # floors only: yielding stories take no mass devices
        linear = stiffness - drift.T @ np.diag(yielding) @ drift
        lowest, highest = np.linalg.eigvalsh(linear)[[0, -1]]
        # the yielded building may lose stiffness: on purpose
        softening = np.min(config.post_yield_ratio) < 0.0
        if lowest < -1e-9 * highest and not softening:
            raise ValueError(
                "the yielded building's stiffness is not positive semi-definite (lowest eigenvalue "
                f"{lowest:.3g} N/m): its stories' springs hold more than its stiffness matrix; expected a "
                "larger post_yield_ratio"
            )
        return cls(
            floor_gain=building.actuator_matrix * building.force_limits,
            mass_inverse=1.0 / np.diag(building.mass),
            damping=building.damping,
            linear_stiffness=linear,
            hysteretic_stiffness=yielding * yield_drift,
            yield_drift=yield_drift,
            exponent=per_story(config.exponent, n),
            beta=per_story(config.beta, n),
            gamma=per_story(config.gamma, n),
            collapse_drift=per_story(np.inf if config.collapse_drift is None else config.collapse_drift, n),
            substeps=config.substeps,
        )

    @property
    def hysteretic_matrix(self) -> np.ndarray:
        """D' diag(h) (n, n): the floors' restoring forces from the stories' z (N)."""
        return drift_matrix(self.hysteretic_stiffness.size).T @ np.diag(self.hysteretic_stiffness)

    def arrays(self) -> BoucWenArrays:
        return BoucWenArrays(
            mass_inverse=self.mass_inverse,
            damping=self.damping,
            linear=self.linear_stiffness,
            hysteretic=self.hysteretic_stiffness,
            yield_drift=self.yield_drift,
            exponent=self.exponent,
            beta=self.beta,
            gamma=self.gamma,
            collapse=self.collapse_drift,
        )

    @property
    def story_force_map(self) -> np.ndarray:
        """diag(h) (n, n): each story's hysteretic force from z (N)."""
        return np.diag(self.hysteretic_stiffness)

    def step(
        self, state: np.ndarray, action: np.ndarray, ground: np.ndarray, control_dt: float
    ) -> np.ndarray:
        """The state after one control step: the action (forces / force limits) held, `ground` the
        r + 1 ground samples (m/s^2) spanning the step."""
        from rlcontroller.physics.integrators.yielding import (
            bouc_wen_step,  # numba: imported when first needed
        )

        return bouc_wen_step(
            state, self.floor_gain @ action, ground, control_dt, self.substeps, *self.arrays()
        )

    def history(self, ground: np.ndarray, per_step: int, control_dt: float) -> np.ndarray:
        """The uncontrolled states [x; v; z] at every control step (K + 1, 3n) from rest under `ground`
        (m/s^2, K * per_step + 1 samples, `per_step` per control step of `control_dt` s)."""
        from rlcontroller.physics.integrators.yielding import bouc_wen_history

        n = self.mass_inverse.size
        return bouc_wen_history(
            np.zeros(3 * n), np.zeros(n), ground, per_step, control_dt, self.substeps, *self.arrays()
        )
