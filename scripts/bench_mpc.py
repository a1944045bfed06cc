"""Benchmark: MPC's solve time per control step (OSQP, warm-started) for the five-story building (the paper's
layout) and the roof active mass driver (its stroke limit a soft constraint), horizons of 10, 20 and 50
control steps, against the 20 ms control step; and the seven records' evaluation time with it.

Usage: python scripts/bench_mpc.py [--records ../shared/records]
Each horizon runs MPC alone on the seven records (one building per record, in the batch) and times every QP
solve; reports the median and 99th percentile per step, and the wall time of the whole evaluation.
"""

from __future__ import annotations

import argparse
import platform
import time
from pathlib import Path

import numpy as np

from rlcontroller.assets import CONFIGS
from rlcontroller.config import load_experiment
from rlcontroller.control.mpc import MPCPlanner
from rlcontroller.control.mpc_controllers import MPCController
from rlcontroller.physics.motions.records import load_records
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.rollout import batch_rollout


class TimedPlanner(MPCPlanner):
    """MPC's planner that keeps the time of each QP solve (s), OSQP's own."""

    def __init__(self, problem) -> None:
        super().__init__(problem)
        self.times: list[float] = []

    def plan(self, row, estimate, action_bounds=None):
        solution = super().plan(row, estimate, action_bounds)
        self.times.append(self.last_solve_time)
        return solution


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=Path, default=Path("../shared/records"))
    arguments = parser.parse_args()
    motions, _ = load_records(arguments.records)
    print(f"{platform.processor() or platform.machine()}, {platform.python_version()}; seven records")
    print(
        "| experiment | horizon | QP solve median (ms) | p99 (ms) | steps | fallbacks | seven records (s) |"
    )
    print("|---|---|---|---|---|---|---|")
    for config in ("five_story.yaml", "experiments/five_story_amd.yaml"):
        plant = Plant(load_experiment(CONFIGS / config))
        for horizon in (10, 20, 50):
            controller = MPCController(plant.design, horizon)
            controller.planner = TimedPlanner(controller.problem)
            start = time.perf_counter()
            batch_rollout(plant, motions, [controller])
            wall = time.perf_counter() - start
            times = 1e3 * np.array(controller.planner.times)
            print(
                f"| {plant.experiment.name} | {horizon} | {np.median(times):.3f} | "
                f"{np.percentile(times, 99):.3f} | "
                f"{times.size} | {controller.fallbacks} | {wall:.1f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
