"""Study: MR dampers on stories 1, 3 and 5 that never lock: each emulates a light viscous damper.

Usage: python studies/devices/mr_viscous.py [C ...]   (N s/m; default 1e5 1e6)

Every law tried so far for this layout fails the safety check against passive-off because holding voltage
locks the damped stories and moves the drift to stories 2 and 4 (docs/safety_check.md). Aimed at that: a
law whose desired force is purely dissipative and proportional, f = -C v (v each damped story's drift
velocity from clipped-optimal's Kalman estimate), switched as clipped-optimal switches (on while the measured
force falls short of it in its direction): a damper then never holds more than a viscous damper of
coefficient C would push. First, what even ideal viscous dampers do on these stories (the bare building,
linear, per unit ground acceleration): the largest rise of any story's drift over the frequencies, as a
share of that story's peak. Then the law through the safety check (about 3 min per C).
"""

from __future__ import annotations

import sys

import numpy as np

from rlcontroller.assets import CONFIGS
from rlcontroller.config import load_experiment, load_safety_check
from rlcontroller.config.scenarios import safety_standard
from rlcontroller.control.controllers import ClippedOptimal
from rlcontroller.evaluation.safety import safety_check
from rlcontroller.physics.plant import Plant


class ViscousEmulation(ClippedOptimal):
    """Each damper on (+1) while its measured force falls short of -C times its story's estimated drift
    velocity in that force's direction, else off (-1)."""

    def __init__(self, plant: Plant, coefficient: float) -> None:
        super().__init__(plant, name=f"viscous emulation, C = {coefficient:g} N s/m")
        n = plant.active_equivalent.building.n_dofs
        stories = [device.story for device in plant.experiment.devices if device.semi_active]
        self.velocity_rows = (np.eye(n) - np.eye(n, k=-1))[[story - 1 for story in stories]]
        self.n, self.coefficient = n, coefficient

    def act(self, observation: np.ndarray) -> np.ndarray:
        measured = self.update(observation)
        velocity = self.estimate[..., self.n : 2 * self.n] @ self.velocity_rows.T
        return self.switch(-self.coefficient * velocity, measured)


def viscous_excess(plant: Plant, stories: list[int], coefficient: float) -> tuple[float, float, int]:
    """Ideal viscous dampers of `coefficient` on `stories` of the bare building: the largest rise of a story's
    drift response over 0.1-20 Hz, as a share of its peak; at which frequency (Hz) and story."""
    building = plant.bare.building
    mass, stiffness, damping = building.mass, building.stiffness, building.damping
    n = mass.shape[0]
    drift = np.eye(n) - np.eye(n, k=-1)
    added = coefficient * sum(np.outer(drift[s - 1], drift[s - 1]) for s in stories)
    frequency = np.geomspace(0.1, 20.0, 3000)

    def response(extra: np.ndarray) -> np.ndarray:
        w = 2 * np.pi * frequency[:, None, None]
        dynamic = stiffness - w**2 * mass + 1j * w * (damping + extra)
        load = np.broadcast_to(-mass @ np.ones(n), (len(frequency), n))[..., None]
        return np.abs(np.linalg.solve(dynamic, load)[..., 0] @ drift.T)

    without, with_dampers = response(np.zeros((n, n))), response(added)
    excess = (with_dampers - without) / without.max(axis=0)
    k, story = np.unravel_index(np.argmax(excess), excess.shape)
    return float(excess[k, story]), float(frequency[k]), int(story) + 1


def main() -> None:
    plant = Plant(load_experiment(CONFIGS / "experiments" / "five_story_mr.yaml"))
    stories = [device.story for device in plant.experiment.devices if device.semi_active]
    coefficients = [float(value) for value in sys.argv[1:]] or [1e5, 1e6]
    for coefficient in coefficients:
        share, frequency, story = viscous_excess(plant, stories, coefficient)
        print(
            f"ideal viscous dampers, C = {coefficient:g} N s/m on stories {stories}: story {story}'s drift "
            f"rises by {share:.4f} of its peak at {frequency:.2f} Hz"
        )
    standard = load_safety_check(safety_standard(plant.experiment))
    for coefficient in coefficients:
        print(
            "\n".join(
                safety_check(plant, ViscousEmulation(plant, coefficient), standard, scenarios=[]).lines()
            )
        )


if __name__ == "__main__":
    main()
