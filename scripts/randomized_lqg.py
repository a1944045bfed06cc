"""The three LQGs, designed on the design model, on generated motions each run on its own random plant.

Usage: python scripts/randomized_lqg.py [--config configs/five_story_robust.yaml] [--count 200] [--seed 20000]

Motion i is a draw of the experiment's validation generator with seed `seed`; its plant is drawn from
the experiment's `plant_randomization` with seed `seed + i`, its sensor noise with seed i. This is how
the robust controller's prior was chosen without looking at the records: per LQG the mean, median
and largest J1 over the motions, the number of motions with J1 > 1 (worse than no control), the mean
J2, and the mean J1 by the drawn actuator delay.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from rlcontroller.config import ConfigError, Experiment, load_experiment
from rlcontroller.control.controllers import LQGController, Uncontrolled
from rlcontroller.control.lqg import design_lqg, design_lqg_ground_model
from rlcontroller.learning.batch import batch_rollout
from rlcontroller.physics.excitation import MotionError, generate_suite
from rlcontroller.physics.metrics import j_metrics
from rlcontroller.physics.plant import Plant, draw_plant

REPOSITORY = Path(__file__).resolve().parents[1]


def randomized_lqg(
    experiment: Experiment, count: int, seed: int
) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
    """(names, J1, J2, delays): J1 and J2 (LQG x motion, means over stories) and each motion's
    drawn actuator delay (control steps)."""
    design = Plant(experiment.model_copy(update={"plant_randomization": None}))
    controllers = [
        LQGController(design_lqg(design), design, "LQG"),
        LQGController(design_lqg(design, known_ground=True), design, "LQG + ground"),
        LQGController(design_lqg_ground_model(design), design, "LQG + ground model"),
    ]
    motions = generate_suite(experiment.excitation.validation, count, seed)
    j1 = np.zeros((len(controllers), count))
    j2 = np.zeros_like(j1)
    delays = np.zeros(count, dtype=int)
    for i, motion in enumerate(motions):
        part = draw_plant(experiment.plant_randomization, experiment.plant, np.random.default_rng(seed + i))
        plant = Plant(experiment.model_copy(update={"plant": part, "plant_randomization": None}))
        delays[i] = plant.delay_steps
        bare = batch_rollout(plant, [motion], [Uncontrolled(plant.building.n_actuators)], seeds=[i])[0][0][0]
        for c, runs in enumerate(batch_rollout(plant, [motion], controllers, seeds=[i])):
            metrics = j_metrics(runs[0][0], bare)
            j1[c, i], j2[c, i] = np.mean(metrics["J1"]), np.mean(metrics["J2"])
    return [controller.name for controller in controllers], j1, j2, delays


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", type=Path, default=REPOSITORY / "configs" / "five_story_robust.yaml")
    parser.add_argument("--count", type=int, default=200)
    parser.add_argument("--seed", type=int, default=20_000)
    arguments = parser.parse_args()
    experiment = load_experiment(arguments.config)
    if experiment.plant_randomization is None:
        raise SystemExit(f"{arguments.config}: needs a plant_randomization part")
    names, j1, j2, delays = randomized_lqg(experiment, arguments.count, arguments.seed)
    print(f"{arguments.count} motions, each on its own plant drawn from {arguments.config}")
    print("| LQG | mean J1 | median J1 | largest J1 | motions J1 > 1 | mean J2 | mean J1 by delay (steps) |")
    print("|---|---|---|---|---|---|---|")
    for c, name in enumerate(names):
        by_delay = ", ".join(f"{d}: {j1[c, delays == d].mean():.3f}" for d in np.unique(delays))
        print(
            f"| {name} | {j1[c].mean():.3f} | {np.median(j1[c]):.3f} | {j1[c].max():.3f} | "
            f"{int((j1[c] > 1).sum())} | {j2[c].mean():.3f} | {by_delay} |"
        )


if __name__ == "__main__":
    try:
        main()
    except (ConfigError, MotionError) as error:  # a bad config, records or output folder: one line
        raise SystemExit(f"error: {error}") from None
