"""Benchmark: control steps per second of a nonlinear reduced model (`rlc reduce`: Bouc-Wen stories or a
fishbone on an FE model's condensed stiffness; the FE model's own rate: scripts/bench_opensees.py).

Usage: python scripts/bench_reduced.py [REDUCED_FOLDER] [--seconds S]
REDUCED_FOLDER is what `rlc reduce configs/experiments/nine_story_frame.yaml --out FOLDER` wrote (default:
studies/opensees/nine_story_frame_reduced). Four rates on the first S seconds of one calibration motion
(0.02 s samples, one per control step): the whole record in one compiled call (what calibration runs), the
plant's step one control step a call, the env's step() (what training runs, observation and reward
included), and a batch of 16 members stepped together.
"""

from __future__ import annotations

import argparse
import platform
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from rlcontroller.config import load_experiment
from rlcontroller.identification.hysteretic import FIT_SEED, calibration_motions
from rlcontroller.learning.env import BuildingEnv
from rlcontroller.physics.motions.excitation import on_control_grid
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.batch import BuildingBatch, episode_generator

DEFAULT = Path(__file__).resolve().parents[1] / "studies" / "opensees" / "nine_story_frame_reduced"


def whole_record(plant: Plant, motion, repeats: int = 5) -> float:
    grid = on_control_grid(motion, plant.control_dt)
    plant.yielding.history(grid.ground, grid.substeps, plant.control_dt)  # compiled once
    start = time.perf_counter()
    for _ in range(repeats):
        plant.yielding.history(grid.ground, grid.substeps, plant.control_dt)
    return repeats * grid.n_steps / (time.perf_counter() - start)


def step_by_step(plant: Plant, motion) -> float:
    """The plant's own step, one control step a call (what the env and the batch call)."""
    grid = on_control_grid(motion, plant.control_dt)
    state, action = np.zeros(plant.n_state), np.zeros(plant.building.n_actuators)
    start = time.perf_counter()
    for k in range(grid.n_steps):
        window = grid.ground[k * grid.substeps : (k + 1) * grid.substeps + 1]
        state = plant.integrator.step(state, action, window, plant.control_dt)
    return grid.n_steps / (time.perf_counter() - start)


def env_steps(plant: Plant, motion) -> float:
    env = BuildingEnv(plant)
    env.reset(seed=0, options={"motion": motion})
    action, steps = np.zeros(env.action_space.shape, dtype=np.float32), 0
    start = time.perf_counter()
    done = False
    while not done:
        _, _, terminated, truncated, _ = env.step(action)
        done, steps = terminated or truncated, steps + 1
    return steps / (time.perf_counter() - start)


def batch_steps(plant: Plant, motion, members: int = 16) -> float:
    batch = BuildingBatch(plant, members)
    grid = on_control_grid(motion, plant.control_dt)
    for member in range(members):
        batch.start(member, episode_generator(member), motion, grid)
    actions = np.zeros((members, batch.m))
    start = time.perf_counter()
    for _ in range(grid.n_steps):
        batch.step(actions)
    return members * grid.n_steps / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", nargs="?", type=Path, default=DEFAULT, help="what rlc reduce wrote")
    parser.add_argument("--seconds", type=float, default=40.0, help="length of the motion (s)")
    arguments = parser.parse_args()
    plant = Plant(load_experiment(arguments.folder / "config.yaml", self_contained=True))
    motion = calibration_motions(1, FIT_SEED)[0]
    keep = round(arguments.seconds / motion.dt) + 1
    motion = replace(motion, acceleration=motion.acceleration[:keep])
    print(
        f"{platform.node()} ({platform.processor() or platform.machine()}); {plant.building.n_floors} "
        f"floors, {plant.yielding.substeps} RK4 sub-steps per sample"
    )
    print(f"whole record, one compiled call: {whole_record(plant, motion):,.0f} control steps/s")
    print(f"the plant's step, a call a step:   {step_by_step(plant, motion):,.0f} control steps/s")
    print(f"env step() (observation, reward): {env_steps(plant, motion):,.0f} control steps/s")
    print(f"batch of 16, all members:         {batch_steps(plant, motion):,.0f} control steps/s")


if __name__ == "__main__":
    main()
