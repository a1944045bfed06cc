"""Diagnostic: how little does it take to make a motion worse than the roof driver switched off?

Usage: python studies/devices/driver_sensitivity.py [CONFIG] [--policy RUN_DIR] [--levels 2,4]

On the safety check's suite (`rlc check`'s own code, `evaluation.safety.suite_criterion`), against the
driver switched off (the tuned mass it is, on the same end-stops), counts the significant motions made worse
beyond the standard's tolerance by

- a constant command of 0.1 % and 1 % of the force limit (10 N and 100 N for the roof driver): what the
  tolerance sees of a force that carries no information;
- LQG + ground model (and with `--policy` a run's best policy) as designed, then the same switched off for
  good once the ground reading (noise included) first reaches each level (m/s^2): on a strong motion the law
  then acts only in its first seconds, before the mass meets its stops.

Prints one line per row: k worse, the mean J1 and the PGA (g) of the motions made worse. Issue 78, target 2
(docs/devices.md, "Round 7: the roof driver with its stops").
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from rlcontroller.config import load_experiment
from rlcontroller.config.scenarios import load_safety_check, safety_standard
from rlcontroller.control.controllers import ConstantCommand, Controller
from rlcontroller.control.policy_file import read_policy
from rlcontroller.evaluation.evaluation import classical_controllers
from rlcontroller.evaluation.safety import drift_bounds, suite_criterion
from rlcontroller.physics.plant import Plant

DEFAULT = Path(__file__).resolve().parents[2] / "configs/experiments/five_story_amd.yaml"


class OffAbove:
    """`controller` until the ground reading first reaches `level` (m/s^2), then no command for good."""

    def __init__(self, controller: Controller, plant: Plant, level: float) -> None:
        self.controller, self.level = controller, level
        self.ground, self.scale = plant.layout.ground, plant.layout.ground_scale
        self.name = f"{controller.name}, off from {level:g} m/s^2"
        self.peak: np.ndarray | None = None

    def reset(self) -> None:
        self.controller.reset()
        self.peak = None

    def act(self, observation: np.ndarray) -> np.ndarray:
        ground = np.abs(observation[..., self.ground]) * self.scale
        self.peak = ground if self.peak is None else np.maximum(self.peak, ground)
        return self.controller.act(observation) * (self.peak < self.level)[..., None]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "config", type=Path, nargs="?", default=DEFAULT, help="an experiment with a mass driver"
    )
    parser.add_argument("--policy", type=Path, default=None, help="a run folder of the same experiment")
    parser.add_argument("--levels", default="2,4", help="ground readings (m/s^2) to switch off at")
    arguments = parser.parse_args()
    plant = Plant(load_experiment(arguments.config))
    check = load_safety_check(safety_standard(plant.experiment))
    bounds = drift_bounds(plant, check)
    limit = float(plant.force_limits[0])
    laws = [c for c in classical_controllers(plant) if c.name == "LQG + ground model"]
    if arguments.policy is not None:
        laws.append(read_policy(arguments.policy, "best", plant))
    m = plant.building.n_actuators
    rows: list[Controller] = [
        ConstantCommand(share, m, f"constant {share * limit:g} N") for share in (1e-3, 1e-2)
    ]
    for law in laws:
        rows += [law, *(OffAbove(law, plant, float(level)) for level in arguments.levels.split(","))]
    for controller in rows:
        suite = suite_criterion(plant, controller, check, bounds)
        worse = sorted(suite.per_motion[name].pga_g for name in suite.failures)
        print(
            f"{controller.name}: {suite.failure_count} of {suite.significant_motions} worse, "
            f"J1 {suite.mean_J1:.3f}; PGA of the worse (g): {', '.join(f'{pga:.2f}' for pga in worse)}",
            flush=True,
        )


if __name__ == "__main__":
    main()
