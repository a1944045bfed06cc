"""Study: LQG + ground model with the floors' absolute accelerations added to its cost.

Usage: python studies/benchmark/lqg_acceleration_sweep.py [CONFIG] [--records ../shared/records ...]
                                                [--weights 0 0.01 0.03 0.1 0.3 1] [--scale 5.0]

`rlc compare lqg --sweep` moves LQG along its force weight, which hardly changes J2 (peak absolute
acceleration). This adds a quadratic term on the absolute floor accelerations (weight w, scale in
m/s^2) to the experiment's quadratic reward terms, designs LQG + ground model on that cost for each
weight, and prints its mean J1, J2 and J3 on each suite of records (folders of records, as `rlc
evaluate --records` takes; e.g. the seven records and `scripts/generated_records.py`'s 200 motions).
docs/benchmark.md's table is this script's output for configs/five_story.yaml.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rlcontroller.config import ConfigError, Experiment, RewardConfig, load_experiment
from rlcontroller.control.controllers import LQGController
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.evaluation.evaluation import evaluate, mean_metric
from rlcontroller.physics.motions.excitation import Load
from rlcontroller.physics.motions.records import choose_motions
from rlcontroller.physics.plant import Plant

REPOSITORY = Path(__file__).resolve().parents[2]


def with_acceleration_term(experiment: Experiment, weight: float, scale: float) -> RewardConfig:
    """The experiment's quadratic reward terms plus `weight` * (absolute acceleration / `scale`)^2."""
    terms = [term.model_dump() for term in experiment.reward.terms if term.quadratic]
    if weight > 0.0:
        terms.append({"quantity": "absolute_acceleration", "weight": weight, "scale": scale})
    return RewardConfig.model_validate({"terms": terms})


def mean_metrics(plant: Plant, reward: RewardConfig, motions: list[Load]) -> dict[str, float]:
    """Mean J1, J2, J3 over the motions of LQG + ground model designed on `reward`."""
    controller = LQGController(design_lqg_ground_model(plant.design, reward=reward), plant.design, "LQG")
    evaluation = evaluate(plant, motions, [controller], "", include_optimal=False)
    return {metric: mean_metric(evaluation, "LQG", metric) for metric in ("J1", "J2", "J3")}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", type=Path, nargs="?", default=REPOSITORY / "configs/five_story.yaml")
    parser.add_argument("--records", type=Path, nargs="+", default=[REPOSITORY.parent / "shared" / "records"])
    parser.add_argument("--weights", type=float, nargs="+", default=[0.0, 0.01, 0.03, 0.1, 0.3, 1.0])
    parser.add_argument("--scale", type=float, default=5.0, help="m/s^2")
    arguments = parser.parse_args()
    try:
        experiment = load_experiment(arguments.config)
        suites = {str(folder): choose_motions(folder)[0] for folder in arguments.records}
    except ConfigError as error:
        sys.exit(f"error: {error}")
    plant = Plant(experiment)
    print("| weight | " + " | ".join(f"{name} J1 | J2 | J3" for name in suites) + " |")
    print("|---|" + "---|---|---|" * len(suites))
    for weight in arguments.weights:
        reward = with_acceleration_term(experiment, weight, arguments.scale)
        cells = []
        for motions in suites.values():
            means = mean_metrics(plant, reward, motions)
            cells.append(f"{means['J1']:.3f} | {means['J2']:.3f} | {means['J3']:.3f}")
        print(f"| {weight:g} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
