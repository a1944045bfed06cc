"""Study: MPC against the LQG that keeps the active mass driver's stroke, both chosen on generated motions.

Usage: python studies/mpc/mass_driver_stroke.py [--records ../shared/records]

LQG cannot be told a stroke limit; the field's way is a heavier stroke weight. This designs LQG + ground model
for the roof driver (configs/experiments/five_story_amd.yaml: 10 kN, 1 m) with the reward's stroke weight
times 1 ... 20,000, runs each on the experiment's generated validation motions and takes the lightest weight
whose largest peak stroke there stays within the limit (1 % allowed): the stroke-safe LQG. Then it runs LQG
as designed, the stroke-safe LQG and MPC (N = 20, the stroke a soft constraint) on the validation motions
and on the records: mean J1, J2, the largest and mean peak stroke / limit and the records over it.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from horizon_sweep import validation_motions
from suite import Suite

from rlcontroller.assets import CONFIGS
from rlcontroller.config import load_experiment
from rlcontroller.control.controllers import LQGController
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.control.mpc_controllers import MPCController
from rlcontroller.evaluation.evaluation import scaled_weights
from rlcontroller.physics.motions.records import load_records
from rlcontroller.physics.plant import Plant

MULTIPLIERS = (1, 10, 100, 500, 1000, 2000, 5000, 10000, 20000)
EXPERIMENT = CONFIGS / "experiments" / "five_story_amd.yaml"


def row_text(name: str, row: dict[str, float]) -> str:
    return (
        f"| {name} | {row['J1']:.3f} | {row['J2']:.3f} | {row['stroke_max']:.3f} | {row['stroke_mean']:.3f} "
        f"| {row['over_limit']} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=Path, default=Path("../shared/records"))
    arguments = parser.parse_args()
    experiment = load_experiment(EXPERIMENT)
    plant = Plant(experiment)
    design = plant.design
    validation = Suite(plant, validation_motions(plant))
    records = Suite(plant, load_records(arguments.records)[0])
    header = "| controller | J1 | J2 | largest peak stroke / limit | mean | motions over |\n"
    header += "|---|---|---|---|---|---|"

    print(f"LQG + ground model by stroke weight, {len(validation.motions)} validation motions\n{header}")
    safe = None
    for multiplier in MULTIPLIERS:
        reward = scaled_weights(experiment.reward, {"stroke": multiplier})
        controller = LQGController(
            design_lqg_ground_model(design, reward=reward), design, f"stroke x{multiplier}"
        )
        row = validation.judge(controller)
        print(row_text(controller.name, row), flush=True)
        if safe is None and row["stroke_max"] <= 1.01:
            safe = controller
    if safe is None:
        raise SystemExit("no stroke weight keeps the stroke within its limit on the validation motions")

    controllers = {
        "LQG + ground model": lambda: LQGController(design_lqg_ground_model(design), design),
        f"LQG + ground model, stroke-safe ({safe.name})": lambda: LQGController(
            safe.design, design, safe.name
        ),
        "MPC (N = 20)": lambda: MPCController(design, 20),
    }
    for label, suite in (("validation motions", validation), ("records", records)):
        print(f"\n{label} ({len(suite.motions)})\n{header}")
        for name, build in controllers.items():
            controller = build()
            print(row_text(name, suite.judge(controller)), flush=True)


if __name__ == "__main__":
    main()
