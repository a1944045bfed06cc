"""The three LQGs, designed on the design model, on generated motions each run on its own random plant.

Usage: python studies/robustness/randomized_lqg.py [--config studies/robustness/five_story_robust.yaml]
                                        [--count 200] [--seed 20000]

The motions are `count` draws of the experiment's validation generator with seed `seed`; motion i
runs on a plant drawn from the experiment's `plant_randomization` with seed i, noise included, as
validation draws them: the learning curves' LQG references on `count` motions instead of
`validation_motions`. This is how the robust controller's prior was
chosen without looking at the records: per LQG the mean, median and largest J1 over the motions,
the number of motions with J1 > 1 (worse than no control) and the mean J2.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from rlcontroller.config import ConfigError, Experiment, load_experiment
from rlcontroller.control.controllers import LQGController, Uncontrolled
from rlcontroller.control.lqg import design_lqg, design_lqg_ground_model
from rlcontroller.physics.metrics import j_metrics
from rlcontroller.physics.motions.excitation import MotionError
from rlcontroller.physics.motions.generators import generate_suite
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.rollout import batch_rollout

REPOSITORY = Path(__file__).resolve().parents[2]


def randomized_lqg(experiment: Experiment, count: int, seed: int) -> tuple[list[str], np.ndarray, np.ndarray]:
    """(names, J1, J2): J1 and J2 per LQG and motion (means over stories)."""
    design = Plant(experiment.model_copy(update={"plant_randomization": None})).design
    controllers = [
        LQGController(design_lqg(design), design, "LQG"),
        LQGController(design_lqg(design, known_ground=True), design, "LQG + ground"),
        LQGController(design_lqg_ground_model(design), design, "LQG + ground model"),
    ]
    motions = generate_suite(experiment.excitation.validation, count, seed)
    lanes = [Uncontrolled(design.building.n_actuators), *controllers]
    bare, *runs = batch_rollout(Plant(experiment), motions, lanes, randomize=True)
    metrics = [
        [j_metrics(run, free) for (run, _), (free, _) in zip(lane, bare, strict=True)] for lane in runs
    ]
    j1 = np.array([[np.mean(m["J1"]) for m in lane] for lane in metrics])
    j2 = np.array([[np.mean(m["J2"]) for m in lane] for lane in metrics])
    return [controller.name for controller in controllers], j1, j2


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--config", type=Path, default=REPOSITORY / "studies" / "robustness" / "five_story_robust.yaml"
    )
    parser.add_argument("--count", type=int, default=200)
    parser.add_argument("--seed", type=int, default=20_000)
    arguments = parser.parse_args()
    experiment = load_experiment(arguments.config)
    if experiment.plant_randomization is None:
        raise SystemExit(f"{arguments.config}: needs a plant_randomization part")
    names, j1, j2 = randomized_lqg(experiment, arguments.count, arguments.seed)
    print(f"{arguments.count} motions, each on its own plant drawn from {arguments.config}")
    print("| LQG | mean J1 | median J1 | largest J1 | motions J1 > 1 | mean J2 |")
    print("|---|---|---|---|---|---|")
    for c, name in enumerate(names):
        print(
            f"| {name} | {j1[c].mean():.3f} | {np.median(j1[c]):.3f} | {j1[c].max():.3f} | "
            f"{int((j1[c] > 1).sum())} | {j2[c].mean():.3f} |"
        )


if __name__ == "__main__":
    try:
        main()
    except (ConfigError, MotionError) as error:  # a bad config, records or output folder: one line
        raise SystemExit(f"error: {error}") from None
