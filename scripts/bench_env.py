"""Benchmark: environment step() rate against Gymnasium's Pendulum-v1, whole-record simulation, the
five-story building with yielding (Bouc-Wen) stories and with three MR dampers, single and batched,
and the 76-story wind benchmark with its active tuned mass damper.

Usage: python scripts/bench_env.py [--steps N]
Both environments are built with gymnasium.make (the same wrappers) and driven by a random
policy in the same process, alternately, three rounds; the best round of each is reported. The
yielding env is measured with its numba-compiled step and, in a child process with
NUMBA_DISABLE_JIT=1, with the same code run by the interpreter. The batched rates are control steps
of 16 buildings stepped together (`simulation.batch`), per second, on 16 generated motions.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import time

import gymnasium as gym
import numpy as np

import rlcontroller
from rlcontroller.assets import CONFIGS
from rlcontroller.config import Experiment, load_experiment
from rlcontroller.control.controllers import ConstantCommand
from rlcontroller.physics.motions.excitation import on_control_grid
from rlcontroller.physics.motions.generators import generate_suite
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.rollout import batch_rollout


def steps_per_second(env: gym.Env, steps: int, seed: int = 0) -> float:
    env.reset(seed=seed)
    actions = np.random.default_rng(seed).uniform(-1, 1, (1000,) + env.action_space.shape).astype(np.float32)
    start = time.perf_counter()
    for i in range(steps):
        _, _, terminated, truncated, _ = env.step(actions[i % 1000])
        if terminated or truncated:
            env.reset()
    return steps / (time.perf_counter() - start)


def whole_record_rate(repeats: int = 5) -> float:
    experiment = Experiment()
    sampled = Plant(experiment).sampled(1)
    motions = generate_suite(experiment.excitation.generator, repeats, seed=1)
    start = time.perf_counter()
    total = 0
    for motion in motions:
        total += sampled.simulate(on_control_grid(motion, experiment.simulation.control_dt)).time.size - 1
    return total / (time.perf_counter() - start)


YIELDING = {"hysteresis": {"yield_drift": 0.03, "post_yield_ratio": 0.1, "exponent": 2.0}}  # 4 RK4 sub-steps


def yielding_rate(steps: int) -> float:
    env = gym.make(rlcontroller.ENV_ID, config=Experiment(plant=YIELDING))
    steps_per_second(env, 100)  # compile (numba caches the machine code on disk)
    return max(steps_per_second(env, steps) for _ in range(3))


def mr_experiment() -> Experiment:
    return load_experiment(CONFIGS / "experiments" / "five_story_mr.yaml")


def mr_rate(steps: int) -> float:
    env = gym.make(rlcontroller.ENV_ID, config=mr_experiment())
    steps_per_second(env, 100)
    return max(steps_per_second(env, steps) for _ in range(3))


def tower_rate(steps: int) -> float:
    """The 76-story benchmark with its active tuned mass damper (77 degrees of freedom) and the
    wind-model Kalman estimate (230 states) in the observation, single env."""
    experiment = load_experiment(CONFIGS / "experiments" / "seventy_six_story_atmd.yaml")
    env = gym.make(rlcontroller.ENV_ID, config=experiment)
    return max(steps_per_second(env, steps) for _ in range(3))


def batch_rate(experiment: Experiment, members: int = 16) -> float:
    """Control steps per second of `members` buildings stepped together, on as many generated motions."""
    plant = Plant(experiment)
    motions = generate_suite(experiment.excitation.generator, members, seed=2)
    controller = ConstantCommand(0.0, plant.building.n_actuators, "half")
    batch_rollout(plant, motions[:1], [controller])  # compile
    start = time.perf_counter()
    runs = batch_rollout(plant, motions, [controller])[0]
    return sum(response.time.size - 1 for response, _ in runs) / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=50_000)
    parser.add_argument("--yielding-only", action="store_true", help=argparse.SUPPRESS)
    arguments = parser.parse_args()
    if arguments.yielding_only:
        print(f"{yielding_rate(arguments.steps):.0f}")
        return
    ours = gym.make(rlcontroller.ENV_ID)
    pendulum = gym.make("Pendulum-v1")
    rates: dict[str, list[float]] = {"building": [], "pendulum": []}
    for _ in range(3):
        rates["building"].append(steps_per_second(ours, arguments.steps))
        rates["pendulum"].append(steps_per_second(pendulum, arguments.steps))
    building_rate, pendulum_rate = max(rates["building"]), max(rates["pendulum"])
    print(
        f"machine: {platform.node()} ({platform.processor() or platform.machine()}), python "
        f"{platform.python_version()}"
    )
    print(f"rlcontroller/Building-v0 step(): {building_rate:,.0f} steps/s")
    print(f"Pendulum-v1 step():              {pendulum_rate:,.0f} steps/s")
    print(f"ratio building / pendulum:       {building_rate / pendulum_rate:.2f}")
    print(f"whole-record simulation:         {whole_record_rate():,.0f} control steps/s")
    compiled = yielding_rate(arguments.steps)
    command = [sys.executable, __file__, "--yielding-only", "--steps", str(max(arguments.steps // 50, 200))]
    interpreted = float(
        subprocess.check_output(command, env={**os.environ, "NUMBA_DISABLE_JIT": "1"}, text=True)
    )
    print(f"yielding stories step() (numba):  {compiled:,.0f} steps/s")
    print(
        f"yielding stories, interpreted:    {interpreted:,.0f} steps/s ({compiled / interpreted:.0f}x slower)"
    )
    print(f"3 MR dampers step() (numba):      {mr_rate(arguments.steps):,.0f} steps/s")
    print(f"76-story + ATMD, wind estimate:   {tower_rate(arguments.steps):,.0f} steps/s")
    print(f"yielding stories, batch of 16:    {batch_rate(Experiment(plant=YIELDING)):,.0f} steps/s")
    print(f"3 MR dampers, batch of 16:        {batch_rate(mr_experiment()):,.0f} steps/s")


if __name__ == "__main__":
    main()
