"""Benchmark: control steps per second of the OpenSees plant (`physics.fe.opensees`) for both shipped
examples, in one process and fanned out over the cores (`simulation.batch`).

Usage: python scripts/bench_opensees.py [--seconds S]
One process: the FE model stepped alone (`OpenSeesIntegrator.step`), uncontrolled, on the first S seconds
of a generated motion sampled at 0.005 s (four ground samples per 0.02 s control step, as most records);
rlc's own exact integration of the design model on the same motion beside it. Fanned out: as many motions
as cores, each alone in its process, through `batch_rollout` (wall time and control steps per second).
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from dataclasses import replace

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from rlcontroller import api
from rlcontroller.assets import CONFIGS
from rlcontroller.control.controllers import Uncontrolled
from rlcontroller.physics.motions.excitation import on_control_grid
from rlcontroller.physics.motions.loads import generate_suite
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.rollout import batch_rollout

EXAMPLES = (
    CONFIGS.parent / "studies" / "opensees" / "five_story_opensees.yaml",  # from a checkout
    CONFIGS / "experiments" / "nine_story_frame.yaml",
)


def motions(plant: Plant, count: int, seconds: float) -> list:
    """`count` generated motions of `seconds`, resampled to 0.005 s (linear between samples)."""
    suite = generate_suite(plant.experiment.excitation.generator, count, 7, plant.building)
    resampled = []
    for motion in suite:
        time_axis = np.arange(motion.acceleration.size) * motion.dt
        fine = np.arange(0.0, min(seconds, time_axis[-1]), 0.005)
        resampled.append(
            replace(motion, acceleration=np.interp(fine, time_axis, motion.acceleration), dt=0.005)
        )
    return resampled


def one_process(plant: Plant, motion) -> float:
    """Control steps per second of the FE model alone."""
    grid = on_control_grid(motion, plant.control_dt)
    windows = sliding_window_view(grid.ground, grid.substeps + 1)[:: grid.substeps]
    state, action = np.zeros(plant.n_state), np.zeros(plant.building.n_actuators)
    start = time.perf_counter()
    for window in windows:
        state = plant.integrator.step(state, action, window, plant.control_dt)
    return len(windows) / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0, help="length of each motion (s)")
    args = parser.parse_args()
    cores = os.cpu_count() or 1
    print(
        f"# {platform.processor() or platform.machine()}, {cores} cores; motions of {args.seconds:g} s at "
        "0.005 s"
    )
    for path in EXAMPLES:
        plant, name = Plant(api.load(path)), path.stem
        suite = motions(plant, cores, args.seconds)
        alone = one_process(plant, suite[0])
        start = time.perf_counter()
        batch_rollout(plant.design, suite[:1], [Uncontrolled(plant.building.n_actuators)])
        exact = on_control_grid(suite[0], plant.control_dt).n_steps / (time.perf_counter() - start)
        start = time.perf_counter()
        batch_rollout(plant, suite, [Uncontrolled(plant.building.n_actuators)])
        wall = time.perf_counter() - start
        steps = sum(on_control_grid(m, plant.control_dt).n_steps for m in suite)
        print(
            f"{name}: one process {alone:,.0f} control steps/s (rlc's exact integration of its design model "
            f"{exact:,.0f}); {len(suite)} motions fanned out over {cores} processes: {wall:.1f} s, "
            f"{steps / wall:,.0f} control steps/s"
        )


if __name__ == "__main__":
    main()
