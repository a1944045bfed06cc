"""Benchmark: batched evaluation against the record-by-record loop, and at scale.

Usage: python scripts/bench_eval.py [--records DIR] [--large 207] [--skip-robustness]

1. `rlc evaluate`'s work on the records (default ../shared/records): uncontrolled, the three LQGs,
   the committed RL policy and the clairvoyant optimum (6 controllers x 7 records) through the batched
   `compare`, against the same controllers run record by record through `BuildingEnv` (`rollout`) and
   `optimal_response`, as evaluation did before batching.
2. A synthetic suite of --large records (Kanai-Tajimi, 10-100 s, PGA 0.003-1.2 g, sampled at 0.005,
   0.01 or 0.02 s) through the same batched `compare`.
3. `rlc robustness`'s work: the standard scenario set on the records, with the committed policy.
Each is run once, as a user would; the machine is named, its other load is not controlled.
"""

from __future__ import annotations

import argparse
import platform
import time
from dataclasses import replace
from pathlib import Path

from rlcontroller.config import KanaiTajimiConfig, load_experiment, load_scenarios
from rlcontroller.control.controllers import LQGController, Uncontrolled
from rlcontroller.control.lqg import design_lqg, design_lqg_ground_model
from rlcontroller.control.optimal import optimal_response
from rlcontroller.control.policy_file import read_policy
from rlcontroller.evaluation.evaluation import compare
from rlcontroller.evaluation.robustness import robustness
from rlcontroller.learning.env import BuildingEnv, rollout
from rlcontroller.physics.motions.excitation import STANDARD_GRAVITY, Load
from rlcontroller.physics.motions.generators import generate_suite
from rlcontroller.physics.motions.records import load_records
from rlcontroller.physics.plant import Plant

REPOSITORY = Path(__file__).resolve().parents[1]
MODEL = REPOSITORY / "models" / "five_story"
SCENARIOS = REPOSITORY / "configs" / "scenarios" / "standard.yaml"


def record_by_record(plant: Plant, motions: list[Load]) -> float:
    """Seconds for the six controllers run one record at a time (the loop batching replaced)."""
    design = plant.design
    controllers = [
        Uncontrolled(3),
        LQGController(design_lqg(design), design),
        LQGController(design_lqg(design, known_ground=True), design),
        LQGController(design_lqg_ground_model(design), design),
        read_policy(MODEL, "best", plant),
    ]
    env = BuildingEnv(plant)
    start = time.perf_counter()
    for number, motion in enumerate(motions):
        for controller in controllers:
            rollout(env, motion, controller, seed=number)
        optimal_response(plant, motion)
    return time.perf_counter() - start


def synthetic_records(count: int) -> list[Load]:
    """`count` Kanai-Tajimi records of 10-100 s and PGA 0.003-1.2 g, resampled to three sampling steps."""
    config = KanaiTajimiConfig(
        dt=0.005, duration=(10.0, 100.0), pga=(0.003 * STANDARD_GRAVITY, 1.2 * STANDARD_GRAVITY)
    )
    motions = generate_suite(config, count, seed=207)
    return [
        replace(
            motion,
            name=f"synthetic_{i}",
            dt=motion.dt * (1, 2, 4)[i % 3],
            acceleration=motion.acceleration[:: (1, 2, 4)[i % 3]],
        )
        for i, motion in enumerate(motions)
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=Path, default=REPOSITORY.parent / "shared" / "records")
    parser.add_argument("--large", type=int, default=207, help="size of the synthetic suite")
    parser.add_argument("--skip-robustness", action="store_true")
    arguments = parser.parse_args()
    print(f"machine: {platform.node()} ({platform.machine()}, {platform.processor() or 'cpu'})")
    experiment = load_experiment(MODEL / "config.yaml")
    plant = Plant(experiment)
    policy = read_policy(MODEL, "best", plant)
    motions, label = load_records(arguments.records)
    warm_up = [replace(motion, acceleration=motion.acceleration[:400]) for motion in motions]
    compare(plant, warm_up, label, policy=policy)  # imports, the policy's first load, numba compilation
    record_by_record(plant, warm_up)

    start = time.perf_counter()
    evaluation = compare(plant, motions, label, policy=policy)
    batched = time.perf_counter() - start
    looped = record_by_record(plant, motions)
    count = len(evaluation.controllers)
    print(
        f"{count} controllers x {len(motions)} records: batched {batched:.2f} s, record by record "
        f"{looped:.2f} s ({looped / batched:.1f}x)"
    )

    large = synthetic_records(arguments.large)
    seconds = sum(motion.duration for motion in large)
    start = time.perf_counter()
    compare(plant, large, f"{len(large)} synthetic records", policy=policy)
    print(
        f"{count} controllers x {len(large)} synthetic records ({seconds / 3600:.1f} h of ground motion): "
        f"batched {time.perf_counter() - start:.1f} s"
    )

    if not arguments.skip_robustness:
        scenarios = load_scenarios(SCENARIOS, experiment)
        _, elapsed = robustness(experiment, scenarios, motions, label, policy=policy)
        print(
            f"robustness: {len(scenarios)} scenarios x {len(motions)} records x 4 controllers in "
            f"{elapsed:.1f} s"
        )


if __name__ == "__main__":
    main()
