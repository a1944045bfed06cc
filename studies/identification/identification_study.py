"""The study of docs/identification.md: LQG designed on a model identified from D seconds of a vibration test,
against LQG on the true matrices and the uncontrolled building, on the true building (linear, and with
yielding stories), on the seven records and a generated suite.

Usage: python studies/identification/identification_study.py [--records ../shared/records] [--out FOLDER]
For each plant, budget D and seed: `rlc simulate-test` of the paper's experiment (configs/five_story.yaml;
ambient white-noise ground of 0.1 m/s^2 RMS, actuators shaking at 5 % of their limits, the experiment's sensor
noise), `rlc identify` with the floor masses from the drawings, then the experiment designed on that model
(its `building`) and simulated as the true building (its plant part's `building`), evaluated like `rlc compare
lqg`. Writes identified.csv (frequencies and damping ratios per run), controllers.csv (mean J1-J4 per run and
controller) and summary.md to the new folder --out.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from rlcontroller import api
from rlcontroller.assets import CONFIGS
from rlcontroller.config import load_experiment
from rlcontroller.evaluation.evaluation import classical_controllers, evaluate
from rlcontroller.evaluation.tables import markdown_table
from rlcontroller.physics.motions.loads import generate_suite
from rlcontroller.physics.motions.records import load_records
from rlcontroller.physics.plant import Plant

EXPERIMENT = CONFIGS / "five_story.yaml"
MASSES = [25e3, 20e3, 20e3, 18e3, 15e3]  # kg, the floor masses an engineer reads from the drawings
PLANTS = {
    "linear": {},
    "yielding": {"hysteresis": {"yield_drift": 0.03, "post_yield_ratio": 0.1, "exponent": 2.0}},
}
BUDGETS = (150.0, 600.0, 3600.0)  # s of recorded response
SEEDS = (0, 1, 2)
SUITE_SEED, SUITE_SIZE = 2027, 20  # generated motions, a seed no training or check uses


def experiment_file(folder: Path, plant_part: dict, model: Path | None) -> Path:
    """The paper's experiment as a file in `folder`: designed on the identified `model` (None: the true
    matrices) and simulated as the true building with `plant_part` (yielding stories)."""
    raw = load_experiment(EXPERIMENT).model_dump(mode="json")
    truth = raw["building"]
    if model is not None:
        raw["building"] = str(model / "building.yaml")
        plant_part = plant_part | {"building": truth}
    raw["plant"] = plant_part or None
    path = folder / ("identified.yaml" if model is not None else "true.yaml")
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    return path


def judged(path: Path, suites: dict[str, list]) -> list[dict]:
    """Mean J1-J4 of the uncontrolled building and each LQG variant on each suite."""
    plant = Plant(load_experiment(path))
    rows = []
    for suite, motions in suites.items():
        summary = evaluate(
            plant, motions, classical_controllers(plant), suite, include_optimal=False
        ).summary()
        for controller, values in summary.iterrows():
            rows.append(
                {"suite": suite, "controller": controller, **{j: values[j] for j in ("J1", "J2", "J3", "J4")}}
            )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=Path, default=Path("../shared/records"))
    parser.add_argument("--out", type=Path, default=Path("results/identification"), help="a new folder")
    arguments = parser.parse_args()
    arguments.out.mkdir(parents=True)
    experiment = load_experiment(EXPERIMENT)
    truth = Plant(experiment).building
    suites = {
        "seven records": load_records(arguments.records)[0],
        f"generated ({SUITE_SIZE})": generate_suite(
            experiment.excitation.generator, SUITE_SIZE, SUITE_SEED, truth
        ),
    }
    true_frequencies, true_damping = 1 / truth.periods(), truth.modal_damping_ratios()
    identified, controllers = [], []
    for plant_name, plant_part in PLANTS.items():
        folder = arguments.out / plant_name
        folder.mkdir()
        for row in judged(experiment_file(folder, plant_part, None), suites):
            controllers.append(
                {"plant": plant_name, "design": "true matrices", "budget_s": np.nan, "seed": -1, **row}
            )
        for budget in BUDGETS:
            for seed in SEEDS:
                run = folder / f"D{budget:.0f}_seed{seed}"
                run.mkdir()
                test = api.simulate_test(
                    experiment_file(run, plant_part, None), run / "test.csv", duration=budget, seed=seed
                )
                model = api.identify([test], run / "model", masses=MASSES)
                building = Plant(load_experiment(experiment_file(run, plant_part, model))).design.building
                omega, damping = building.poles()
                identified.append(
                    {"plant": plant_name, "budget_s": budget, "seed": seed}
                    | {
                        f"f{i + 1}_error_%": 100 * (w / (2 * np.pi) / f - 1)
                        for i, (w, f) in enumerate(zip(omega, true_frequencies, strict=True))
                    }
                    | {
                        f"zeta{i + 1}_error_%": 100 * (z / t - 1)
                        for i, (z, t) in enumerate(zip(damping, true_damping, strict=True))
                    }
                )
                for row in judged(run / "identified.yaml", suites):
                    controllers.append(
                        {"plant": plant_name, "design": "identified", "budget_s": budget, "seed": seed, **row}
                    )
                print(f"{plant_name} D = {budget:.0f} s seed {seed}: done", flush=True)
    identified_table, controller_table = pd.DataFrame(identified), pd.DataFrame(controllers)
    identified_table.to_csv(arguments.out / "identified.csv", index=False)
    controller_table.to_csv(arguments.out / "controllers.csv", index=False)
    errors = (
        identified_table.groupby(["plant", "budget_s"]).agg(lambda x: np.abs(x).max()).drop(columns="seed")
    )
    keys = ["plant", "suite", "controller", "design", "budget_s"]
    means = controller_table.groupby(keys, dropna=False, sort=False)[["J1", "J2", "J3", "J4"]]
    table = means.mean().join(means.std(), rsuffix=" std").reset_index().set_index("plant")
    (arguments.out / "summary.md").write_text(
        "# Largest identification error over seeds (%)\n\n"
        + markdown_table(errors.reset_index().set_index("plant"), digits=2)
        + "\n\n# J1-J4 (mean and std over seeds)\n\n"
        + markdown_table(table)
        + "\n"
    )
    print((arguments.out / "summary.md").read_text())


if __name__ == "__main__":
    main()
