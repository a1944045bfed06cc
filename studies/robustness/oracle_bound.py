"""Study: how far any controller of the default's family could go on the 14 standard scenarios (issue 68's
robustness target: mean J1 <= 0.260 over them on the seven records).

Usage: python studies/robustness/oracle_bound.py [--model models/five_story_every_story] [--records
../shared/records]

Per scenario, on the seven records (mean J1 over stories and records): the shipped model, LQG + ground model
designed on the design model (as deployed), and LQG + ground model re-designed on the scenario's own plant
(its stiffness, mass, damping, damage, sensor faults; the oracle of that family, which knows what no deployed
controller knows). Actuator lag and delay are not states of LQG + ground model's design, so there it has no
oracle and the best of the other two stands in. The last line is the mean over the scenarios of the best of
the three per scenario: a lower bound for these controllers, not for every controller. About 2 min on one
core.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd

from rlcontroller.config import load_experiment, load_scenarios
from rlcontroller.config.scenarios import standard_scenarios
from rlcontroller.control.controllers import LQGController
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.control.policy_file import read_policy
from rlcontroller.evaluation.evaluation import evaluate
from rlcontroller.physics.motions.records import load_records
from rlcontroller.physics.plant import Plant

REPOSITORY = Path(__file__).resolve().parents[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", type=Path, default=REPOSITORY / "models" / "five_story_every_story")
    parser.add_argument("--records", type=Path, default=REPOSITORY.parent / "shared" / "records")
    arguments = parser.parse_args()
    experiment = load_experiment(arguments.model / "config.yaml")
    motions = load_records(arguments.records)[0]
    design = Plant(experiment.model_copy(update={"plant": None, "plant_randomization": None}))
    nominal = LQGController(design_lqg_ground_model(design), design, "LQG + ground model (nominal)")
    rows = {}
    for scenario in load_scenarios(standard_scenarios(experiment), experiment):
        plant = Plant(experiment.model_copy(update={"plant": scenario.plant}))
        shipped = read_policy(arguments.model, "best", plant)
        controllers = [nominal, shipped]
        if not _has_actuator_dynamics(plant):
            controllers.append(LQGController(design_lqg_ground_model(plant.elastic), plant.elastic, "oracle"))
        metrics = evaluate(plant, motions, controllers, "records", include_optimal=False).metrics
        j1 = metrics[metrics["metric"] == "J1"].groupby("controller")["value"].mean().drop("uncontrolled")
        rows[scenario.name] = j1.rename({shipped.name: "shipped"})
        print(
            f"{scenario.name}: "
            + ", ".join(f"{name} {value:.3f}" for name, value in rows[scenario.name].items())
        )
    table = pd.DataFrame(rows).T
    means = ", ".join(f"{name} {table[name].mean():.3f} ({table[name].count()})" for name in table.columns)
    print(f"\nmean over the scenarios each has (how many): {means}")
    print(f"mean of the best per scenario: {table.min(axis=1).mean():.3f}")


def _has_actuator_dynamics(plant: Plant) -> bool:
    """Whether the scenario's actuators lag or are delayed (not states of LQG + ground model's design)."""
    part = plant.experiment.plant
    return part is not None and (part.actuators.time_constant > 0.0 or part.actuators.delay_steps > 0)


if __name__ == "__main__":
    main()
