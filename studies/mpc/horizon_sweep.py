"""MPC's horizon chosen on generated motions (never the records): J1 and J2 against N, with the solve time.

Usage: python studies/mpc/horizon_sweep.py [experiment.yaml ...]
For each experiment (default: the default experiment, every story with the faded supervisor; the paper's
layout; the roof active mass driver, whose stroke limit binds), MPC with N = 1, 2, 5, 10, 20, 40, 80 control
steps runs on the experiment's held-out validation motions (its validation generator and seed, as training
selects on: J1 and J2 against the uncontrolled building on the same motions, the largest stroke over its
limit), beside LQG + ground model; prints one Markdown table per experiment.
"""

from __future__ import annotations

import sys
import time

from suite import Suite

from rlcontroller.assets import CONFIGS
from rlcontroller.config import load_experiment
from rlcontroller.control.controllers import LQGController
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.control.mpc_controllers import MPCController
from rlcontroller.physics.motions.loads import generate_suite
from rlcontroller.physics.plant import Plant

HORIZONS = (1, 2, 5, 10, 20, 40, 80)
EXPERIMENTS = (
    CONFIGS / "experiments" / "five_story_every_story.yaml",
    CONFIGS / "five_story.yaml",
    CONFIGS / "experiments" / "five_story_amd.yaml",
)


def validation_motions(plant: Plant) -> list:
    """The experiment's held-out generated validation motions (as `learning.validation.Validator` draws
    them)."""
    excitation = plant.experiment.excitation
    return generate_suite(
        excitation.validation, excitation.validation_motions, excitation.validation_seed, plant.building
    )


def cells(row: dict[str, float]) -> str:
    stroke = row.get("stroke_max", float("nan"))
    return f"{row['J1']:.4f} | {row['J2']:.4f} | {row['J1'] + row['J2']:.4f} | {stroke:.3f}"


def main() -> None:
    for path in sys.argv[1:] or EXPERIMENTS:
        plant = Plant(load_experiment(path))
        suite = Suite(plant, validation_motions(plant))
        print(f"\n{path}: {len(suite.motions)} validation motions")
        print("| controller | J1 | J2 | J1 + J2 | peak stroke / limit | wall (s) | fallbacks |")
        print("|---|---|---|---|---|---|---|")
        row = suite.judge(LQGController(design_lqg_ground_model(plant.design), plant.design))
        print(f"| LQG + ground model | {cells(row)} | – | – |")
        for horizon in HORIZONS:
            controller = MPCController(plant.design, horizon)
            start = time.perf_counter()
            row = suite.judge(controller)
            wall = time.perf_counter() - start
            print(f"| MPC N = {horizon} | {cells(row)} | {wall:.1f} | {controller.fallbacks} |", flush=True)


if __name__ == "__main__":
    main()
