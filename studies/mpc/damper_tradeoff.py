"""Study: MPC with passivity against clipped-optimal control for semi-active dampers, along the force weight.

Usage: python studies/mpc/damper_tradeoff.py [CONFIG] [--records ../shared/records]

Both laws are designed with the experiment's cost and its force weight times 3 ... 0.01 (the operating point
of a damper controller is how much force its cost lets it ask for); each runs on the experiment's generated
validation motions and on the records, beside passive-off and passive-on: mean J1 and J2.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from horizon_sweep import validation_motions
from suite import Suite

from rlcontroller.assets import CONFIGS
from rlcontroller.config import load_experiment
from rlcontroller.control.controllers import ClippedOptimal, ConstantCommand
from rlcontroller.control.mpc_controllers import SemiActiveMPC
from rlcontroller.evaluation.evaluation import scaled_weights
from rlcontroller.physics.motions.records import load_records
from rlcontroller.physics.plant import Plant

MULTIPLIERS = (3.0, 1.0, 0.3, 0.1, 0.03, 0.01)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "config", type=Path, nargs="?", default=CONFIGS / "experiments" / "five_story_mr.yaml"
    )
    parser.add_argument("--records", type=Path, default=Path("../shared/records"))
    arguments = parser.parse_args()
    experiment = load_experiment(arguments.config)
    plant = Plant(experiment)
    design, count = plant.design, plant.building.n_actuators
    suites = {
        "validation": Suite(plant, validation_motions(plant)),
        "records": Suite(plant, load_records(arguments.records)[0]),
    }
    print("| controller | force weight x | validation J1 | J2 | records J1 | J2 |\n|---|---|---|---|---|---|")
    for name, value in (("passive-off", -1.0), ("passive-on", 1.0)):
        rows = [suite.judge(ConstantCommand(value, count, name)) for suite in suites.values()]
        print(
            f"| {name} | – | {rows[0]['J1']:.3f} | {rows[0]['J2']:.3f} | {rows[1]['J1']:.3f} | "
            f"{rows[1]['J2']:.3f} |"
        )
    for multiplier in MULTIPLIERS:
        reward = scaled_weights(experiment.reward, {"force": multiplier})
        for law in (
            ClippedOptimal(design, "clipped-optimal", reward),
            SemiActiveMPC(design, 20, "MPC (N = 20)", reward),
        ):
            rows = [suite.judge(law) for suite in suites.values()]
            print(
                f"| {law.name} | {multiplier:g} | {rows[0]['J1']:.3f} | {rows[0]['J2']:.3f} | "
                f"{rows[1]['J1']:.3f} | "
                f"{rows[1]['J2']:.3f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
