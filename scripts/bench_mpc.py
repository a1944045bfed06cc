"""Benchmark: MPC's solve time per control step (OSQP, warm-started) for the five-story building, horizons of
10, 20 and 50 control steps, against the 20 ms control step; and the seven records' evaluation time with it.

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
from rlcontroller.control.mpc import MPCController
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.records import load_records
from rlcontroller.simulation.batch import batch_rollout


class TimedMPC(MPCController):
    """MPC that keeps the time of each QP solve (s)."""

    def __init__(self, plant: Plant, horizon: int) -> None:
        super().__init__(plant, horizon)
        self.times: list[float] = []

    def _solver(self, row: int):
        solver = super()._solver(row)
        timed = self

        class Timed:
            def update(self, **arguments):
                solver.update(**arguments)

            def solve(self, **arguments):
                result = solver.solve(**arguments)
                timed.times.append(result.info.solve_time)
                return result

        return Timed()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=Path, default=Path("../shared/records"))
    arguments = parser.parse_args()
    plant = Plant(load_experiment(CONFIGS / "five_story.yaml"))
    motions, _ = load_records(arguments.records)
    print(f"{platform.processor() or platform.machine()}, {platform.python_version()}; seven records, five-story")
    print("| horizon | QP solve median (ms) | p99 (ms) | steps | fallbacks | seven records (s) |")
    print("|---|---|---|---|---|---|")
    for horizon in (10, 20, 50):
        controller = TimedMPC(plant.design, horizon)
        start = time.perf_counter()
        batch_rollout(plant, motions, [controller])
        wall = time.perf_counter() - start
        times = 1e3 * np.array(controller.times)
        print(
            f"| {horizon} | {np.median(times):.3f} | {np.percentile(times, 99):.3f} | {times.size} | "
            f"{controller.fallbacks} | {wall:.1f} |"
        )


if __name__ == "__main__":
    main()
