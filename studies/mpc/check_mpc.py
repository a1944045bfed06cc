"""Study: MPC through the project's safety check, as every shipped controller goes through it.

Usage: python studies/mpc/check_mpc.py [CONFIG ...]

For each experiment (default: the default experiment with every story's actuator behind the faded supervisor,
the roof active mass driver, the MR dampers) MPC (N = 20; `SemiActiveMPC` for dampers) runs the standard's
check suite against the experiment's fail-safe reference and its runs at rest
(`evaluation.safety.safety_check`, the criteria `rlc check` applies). The closed-loop stability criterion
linearises a policy at rest; MPC at rest is LQR exactly (tests/control/test_mpc.py), so its linearisation is
LQG + ground model's, which `rlc design`'s check covers; it is not repeated here.
"""

from __future__ import annotations

import sys

from rlcontroller.assets import CONFIGS
from rlcontroller.config import load_experiment, load_safety_check
from rlcontroller.config.scenarios import safety_standard
from rlcontroller.control.mpc_controllers import mpc_controller
from rlcontroller.evaluation.safety import safety_check
from rlcontroller.physics.plant import Plant

EXPERIMENTS = (
    CONFIGS / "experiments" / "five_story_every_story.yaml",
    CONFIGS / "experiments" / "five_story_amd.yaml",
    CONFIGS / "experiments" / "five_story_mr.yaml",
)


def main() -> None:
    for path in sys.argv[1:] or EXPERIMENTS:
        experiment = load_experiment(path)
        plant = Plant(experiment)
        verdict = safety_check(
            plant, mpc_controller(plant.design, 20), load_safety_check(safety_standard(experiment)), []
        )
        print(f"{experiment.name}: {'PASSED' if verdict.passed else 'FAILED'}")
        for name, criterion in verdict.criteria.items():
            print(f"  {name}: {criterion.summary}", flush=True)


if __name__ == "__main__":
    main()
