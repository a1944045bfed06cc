"""A fishbone model of a moment frame: floors that sway, floor rotations that couple the stories, beams that
yield.

One elastic column line carries the frame's bending (flexural stiffness EI_i per story, Euler-Bernoulli
between the floors), each floor's beams act as one rotational spring k_b,j on the floor's rotation theta_j,
the base's rotation is held by a spring k_0, and the floors' weights stand on a leaning column (P-Delta: -W_i
/ h_i on story i's drift, W_i the weight above it) — Nakashima, Ogawa & Inoue (2002), "Generic frame model for
simulation of earthquake responses of steel moment frames", Earthquake Eng. Struct. Dyn. 31(3). Masses sit on
the floors' lateral displacements x only, so the n + 1 rotations (the base's first) are massless. Where story
springs (`physics.hysteresis`) make each story yield alone, here a floor's beam hinge acts on the stories
above and below it, which is what lets a frame's upper stories lean back while its lower ones keep their lean.

Each floor's beam spring yields (Bouc-Wen on its rotation): moment k_b (a theta + (1 - a) theta_y z) with
z' = (theta'/theta_y) [1 - |z|^n (beta sgn(theta' z) + gamma)]. The rotations are in equilibrium at every
instant, theta = -K_tt^-1 (K_tx x + H z) (K_tt with the beams' a k_b only, H = diag((1 - a) k_b theta_y), 0 at
the base), so the floors obey

    M v' = -C v - K_e x - B z + F - M 1 a_g,   K_e = K_xx - K_xt K_tt^-1 K_tx,   B = -K_xt K_tt^-1 H,

and theta' = -(I + G Phi)^-1 A v (A = K_tt^-1 K_tx, G = K_tt^-1 H, Phi = diag(z'/theta')), a linear solve per
RK4 stage with the sign of theta' taken from a first pass (`integrators.fishbone_step`). SI units throughout:
N m^2, N m/rad, m, kg, s.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from rlcontroller.config import HysteresisConfig
from rlcontroller.physics.hysteresis import BoucWen, drift_matrix, per_story
from rlcontroller.physics.motions.excitation import STANDARD_GRAVITY
from rlcontroller.physics.structure import Building


@dataclass(frozen=True)
class ColumnLine:
    """The fishbone's elastic parts: floor masses (kg), story heights (m), the column line's EI per story
    (N m^2), the beams' rotational stiffness per floor (N m/rad) and the base's (N m/rad)."""

    masses: np.ndarray
    heights: np.ndarray
    column: np.ndarray
    beams: np.ndarray
    base: float

    @property
    def n(self) -> int:
        return self.masses.size

    def matrices(self, beam_factor: np.ndarray | float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """K_xx (P-Delta included, N/m), K_xt (N/rad), K_tt (N m/rad; rotations 0..n, 0 the base) with each
        floor's beam spring times `beam_factor` (the hinges' linear part: their post-yield ratio)."""
        n = self.n
        full = np.zeros((2 * n + 1, 2 * n + 1))  # [x_1..x_n, theta_0..theta_n]
        for i, (stiffness, h) in enumerate(zip(self.column, self.heights, strict=True)):
            k = (
                stiffness
                / h**3
                * np.array(
                    [
                        [12, 6 * h, -12, 6 * h],
                        [6 * h, 4 * h * h, -6 * h, 2 * h * h],
                        [-12, -6 * h, 12, -6 * h],
                        [6 * h, 2 * h * h, -6 * h, 4 * h * h],
                    ]
                )
            )
            # x below (-1: the ground, fixed), theta below, x above, theta above
            dofs = [i - 1, n + i, i, n + i + 1]
            for a, p in enumerate(dofs):
                for b, q in enumerate(dofs):
                    if p >= 0 and q >= 0:
                        full[p, q] += k[a, b]
        full[n, n] += self.base
        full[n + 1 :, n + 1 :] += np.diag(self.beams * beam_factor)
        drift = drift_matrix(n)
        weight_above = STANDARD_GRAVITY * np.cumsum(self.masses[::-1])[::-1]
        p_delta = -drift.T @ np.diag(weight_above / self.heights) @ drift
        return full[:n, :n] + p_delta, full[:n, n:], full[n:, n:]

    def lateral(self) -> np.ndarray:
        """The lateral stiffness (N/m, n x n) the floors feel with the beams elastic, rotations condensed
        out."""
        xx, xt, tt = self.matrices()
        return xx - xt @ np.linalg.solve(tt, xt.T)


class FishboneArrays(NamedTuple):
    """The arrays the fishbone kernels take after their leading arguments, in their order (a test pins it to
    the kernels' own parameter names: `integrators.fishbone_step`, `fishbone_history`)."""

    mass_inverse: np.ndarray  # (n,) 1/m_j
    damping: np.ndarray  # C (n, n)
    linear: np.ndarray  # K_e (n, n)
    coupling: np.ndarray  # B (n, n): the floors' restoring forces from the hinges' z
    rotation: np.ndarray  # A (n + 1, n)
    hinge: np.ndarray  # G (n + 1, n + 1)
    yield_rotation: np.ndarray  # theta_y,j (rad)
    exponent: np.ndarray
    beta: np.ndarray


@dataclass(frozen=True)
class Fishbone:
    """A column line with yielding beam hinges, as arrays the integrator takes (SI; module docstring)."""

    mass_inverse: np.ndarray  # (n,) 1/m_j
    damping: np.ndarray  # C (n, n)
    linear_stiffness: np.ndarray  # K_e (n, n)
    hysteretic_matrix: np.ndarray  # B (n, n): the floors' restoring forces from the hinges' z, B z (N)
    rotation_map: np.ndarray  # A (n + 1, n)
    hinge_map: np.ndarray  # G (n + 1, n + 1)
    yield_rotation: np.ndarray  # theta_y,j (rad)
    exponent: np.ndarray
    beta: np.ndarray
    floor_gain: np.ndarray | None = None  # Gamma times the force limits (n, m): actions to floor forces (N)
    yield_drift: np.ndarray | None = None  # (n,) m: the stories' (ductility)
    collapse_drift: np.ndarray | None = None  # (n,) m: past it a story has collapsed (inf: never)
    substeps: int = 4
    elastic_stiffness: np.ndarray | None = None  # (n, n) N/m: P-Delta included, the beams elastic (at rest)

    @property
    def story_force_map(self) -> np.ndarray:
        """(n, n): each story's shear carried by the hinges' part, from z (N)."""
        return np.triu(np.ones((self.mass_inverse.size,) * 2)) @ self.hysteretic_matrix

    @classmethod
    def of(
        cls,
        line: ColumnLine,
        damping: np.ndarray,
        *,
        yield_rotation: np.ndarray,
        post_yield_ratio: np.ndarray,
        exponent: np.ndarray,
        beta: np.ndarray,
    ) -> Fishbone:
        """The fishbone of `line` with damping C (N s/m) and per floor's beam hinge: yield rotation (rad),
        post-yield ratio a, exponent n and beta (gamma = 1 - beta)."""
        xx, xt, tt = line.matrices(post_yield_ratio)
        hinge = np.concatenate([[0.0], (1.0 - post_yield_ratio) * line.beams * yield_rotation])
        inverse = np.linalg.inv(tt)
        hinge_map = inverse * hinge[np.newaxis, :]
        return cls(
            mass_inverse=1.0 / line.masses,
            damping=np.ascontiguousarray(damping),
            linear_stiffness=np.ascontiguousarray(xx - xt @ inverse @ xt.T),
            hysteretic_matrix=np.ascontiguousarray(-(xt @ hinge_map)[:, 1:]),
            rotation_map=np.ascontiguousarray(inverse @ xt.T),
            hinge_map=np.ascontiguousarray(hinge_map),
            yield_rotation=np.asarray(yield_rotation, dtype=float),
            exponent=np.asarray(exponent, dtype=float),
            beta=np.asarray(beta, dtype=float),
        )

    @classmethod
    def of_building(cls, building: Building, config: HysteresisConfig) -> Fishbone:
        """The fishbone `config` (model fishbone) describes, on `building`'s floors, damping and actuators."""
        n = building.n_floors
        if building.story_heights is None:
            raise ValueError("model fishbone needs the building's story_heights (m)")
        if len(config.column_stiffness) != n or len(config.beam_stiffness) != n:
            raise ValueError(
                f"column_stiffness and beam_stiffness: expected {n} values each (one per story, floor)"
            )
        masses = np.diag(building.mass)[:n].copy()
        line = ColumnLine(
            masses,
            np.asarray(building.story_heights, dtype=float),
            np.asarray(config.column_stiffness),
            np.asarray(config.beam_stiffness),
            config.base_stiffness,
        )
        fishbone = cls.of(
            line,
            building.damping[:n, :n],
            yield_rotation=per_story(config.yield_rotation, n),
            post_yield_ratio=per_story(config.post_yield_ratio, n),
            exponent=per_story(config.exponent, n),
            beta=per_story(config.beta, n),
        )
        collapse = np.inf if config.collapse_drift is None else config.collapse_drift
        gain = building.actuator_matrix[:n] * building.force_limits
        return replace(
            fishbone,
            floor_gain=gain,
            yield_drift=per_story(config.yield_drift, n),
            collapse_drift=per_story(collapse, n),
            substeps=config.substeps,
            elastic_stiffness=line.lateral(),
        )

    def arrays(self) -> FishboneArrays:
        return FishboneArrays(
            mass_inverse=self.mass_inverse,
            damping=self.damping,
            linear=self.linear_stiffness,
            coupling=self.hysteretic_matrix,
            rotation=self.rotation_map,
            hinge=self.hinge_map,
            yield_rotation=self.yield_rotation,
            exponent=self.exponent,
            beta=self.beta,
        )

    def step(
        self, state: np.ndarray, action: np.ndarray, ground: np.ndarray, control_dt: float
    ) -> np.ndarray:
        """The state [x; v; z] after one control step: the action (forces / force limits) held, `ground` the
        r + 1 ground samples (m/s^2) spanning the step."""
        from rlcontroller.physics.integrators.yielding import fishbone_step

        force = self.floor_gain @ action
        return fishbone_step(
            state, force, ground, control_dt, self.substeps, self.collapse_drift, *self.arrays()
        )

    def history(self, ground: np.ndarray, per_step: int, control_dt: float) -> np.ndarray:
        """The uncontrolled states [x; v; z] at every control step (K + 1, 3 n) from rest under `ground`
        (m/s^2, K * per_step + 1 samples), collapse included; a run that diverges is nan from there on."""
        from rlcontroller.physics.integrators.yielding import fishbone_history

        collapse = (
            np.full(self.mass_inverse.size, np.inf) if self.collapse_drift is None else self.collapse_drift
        )
        return fishbone_history(ground, per_step, control_dt, self.substeps, collapse, *self.arrays())


def hysteretic_model(building: Building, config: HysteresisConfig) -> BoucWen | Fishbone:
    """The yielding model `config` describes on `building`: story springs (model bouc_wen) or a fishbone. A
    collapse drift past its story's height, or a frame that cannot stand under its own weight, is refused
    (ValueError, one line)."""
    n = building.n_floors
    if config.collapse_drift is not None and building.story_heights is not None:
        collapse, heights = (
            per_story(config.collapse_drift, n),
            np.asarray(building.story_heights, dtype=float),
        )
        story = int(np.argmax(collapse > heights))
        if collapse[story] > heights[story]:
            raise ValueError(
                f"collapse_drift: {collapse[story]:g} m in story {story + 1}, beyond its height "
                f"{heights[story]:g} m"
            )
    if config.model == "fishbone":
        fishbone = Fishbone.of_building(building, config)
        lowest = float(
            np.min(np.linalg.eigvalsh(0.5 * (fishbone.elastic_stiffness + fishbone.elastic_stiffness.T)))
        )
        if lowest <= 0.0:
            raise ValueError(
                "the frame cannot stand under its own weight: its lateral stiffness with P-Delta (column "
                f"line, beams elastic) is not positive definite (lowest eigenvalue {lowest:.3g} N/m); "
                "expected stiffer columns or beams (column_stiffness, beam_stiffness, N m^2 and N m/rad) or "
                "lighter floors"
            )
        return fishbone
    return BoucWen.of(building, config)
