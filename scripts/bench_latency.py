"""Benchmark: one control step's latency of the exported controller (onnxruntime) and of the Python one.

Usage: python scripts/bench_latency.py [--calls 10000] [--model models/five_story_every_story]

The committed policy is exported to ONNX; one control step is one call with a single building's
readings: for onnxruntime, `OnnxController.step` (one session.run on one core: intra- and inter-op
threads 1, the process pinned to one CPU); for Python, what the env and `PolicyController` do for the
controller in a step: push the readings into the observation, update the Kalman estimate and act
(numpy actor, LQG prior). Median and 99th percentile over --calls calls after 500 warm-up calls.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from rlcontroller.config import load_experiment
from rlcontroller.control.estimation import observation_filter
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.control.policy_file import read_policy
from rlcontroller.deployment.export import export_onnx
from rlcontroller.deployment.runtime import OnnxController
from rlcontroller.physics.plant import Plant

REPOSITORY = Path(__file__).resolve().parents[1]


def latencies(step, inputs: list) -> np.ndarray:
    """Microseconds of each call of step(*input)."""
    for arguments in inputs[:500]:
        step(*arguments)
    times = np.empty(len(inputs) - 500)
    for i, arguments in enumerate(inputs[500:]):
        start = time.perf_counter_ns()
        step(*arguments)
        times[i] = time.perf_counter_ns() - start
    return times / 1000.0


def python_step(plant: Plant, controller: PolicyController):
    """The Python controller's work in one control step, as the env and PolicyController do it."""
    layout, block = plant.layout, plant.layout.ground + 1
    kalman = observation_filter(plant)
    observation = np.zeros(layout.size, dtype=np.float32)
    memory = {"estimate": np.zeros(kalman.size), "ground": 0.0}

    def step(readings: np.ndarray, ground: np.ndarray) -> np.ndarray:
        held = observation[layout.action].astype(float)
        observation[block : layout.action.start] = observation[: layout.action.start - block]
        observation[layout.readings] = readings[0] / layout.reading_scale
        observation[layout.ground] = ground[0, 0] / layout.ground_scale
        memory["estimate"] = kalman.update(
            memory["estimate"],
            readings[0],
            held_action=held,
            ground=ground[0, 0],
            previous_ground=memory["ground"],
        )
        memory["ground"] = ground[0, 0]
        observation[layout.estimate] = memory["estimate"] / layout.estimate_scale
        action = controller.act(observation)
        observation[layout.action] = action
        return action * plant.force_limits

    return step


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=10_000)
    parser.add_argument(
        "--model", type=Path, default=REPOSITORY / "models" / "five_story_every_story", help="model folder"
    )
    arguments = parser.parse_args()
    os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    import torch

    torch.set_num_threads(1)
    print(f"machine: {platform.node()} ({platform.machine()}), pinned to one CPU")
    plant = Plant(load_experiment(arguments.model / "config.yaml"))
    rng = np.random.default_rng(0)
    p = plant.sensors.c.shape[0]
    inputs = [
        (rng.normal(0.0, 1.0, (1, p)), rng.normal(0.0, 1.0, (1, 1))) for _ in range(arguments.calls + 500)
    ]
    with tempfile.TemporaryDirectory() as folder:
        path = export_onnx(arguments.model, "best", Path(folder) / "controller.onnx")
        exported = OnnxController(path)
        results = {
            "onnxruntime": latencies(exported.step, inputs),
            "Python (numpy)": latencies(
                python_step(plant, read_policy(arguments.model, "best", plant)), inputs
            ),
        }
    for name, times in results.items():
        print(
            f"{name:15s} one control step: median {np.median(times):6.1f} us, "
            f"99th percentile {np.percentile(times, 99):6.1f} us ({len(times):,} calls)"
        )


if __name__ == "__main__":
    main()
