"""Study: the shipped default and MPC behind the faded supervisor, by PGA band, against unsupervised LQG.

Usage: python studies/safety_check/default_by_band.py

On the supervisor study's generated suites (supervisor_study.py: the same generator and seeds, never the
check's or a training seed): the shipped default (models/five_story_every_story, the learned MPC) and MPC (N =
20), both behind the experiment's faded supervisor, beside LQG + ground model with no supervisor on the drift,
shear and force cost and on the cost with the floors' accelerations. Issue 40's criterion: on motions of
0.02-0.1 g the supervised default within 15 % of unsupervised LQG + ground model's J1 (drift, shear and
force).
"""

from __future__ import annotations

from supervisor_study import COSTS, generated_suites

from rlcontroller.assets import DEFAULT_MODEL, SAFETY_STANDARD
from rlcontroller.config import RewardConfig, load_experiment, load_safety_check
from rlcontroller.config.base import read_model
from rlcontroller.control.controllers import LQGController
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.control.mpc_controllers import MPCController
from rlcontroller.control.policy_file import read_policy
from rlcontroller.evaluation.evaluation import evaluate
from rlcontroller.physics.plant import Plant


def main() -> None:
    suites = generated_suites(load_safety_check(SAFETY_STANDARD))
    # faded supervisor
    supervised = Plant(load_experiment(DEFAULT_MODEL / "config.yaml", self_contained=True))
    default = read_policy(DEFAULT_MODEL, "best", supervised, "the default (learned MPC), faded supervisor")
    mpc = MPCController(supervised.design, 20, "MPC (N = 20), faded supervisor")
    unsupervised = Plant(supervised.experiment.model_copy(update={"supervisor": None}))
    references = [
        LQGController(
            design_lqg_ground_model(unsupervised.design, reward=read_model(path, RewardConfig, "'terms'")),
            unsupervised.design,
            f"LQG + ground model ({cost}), no supervisor",
        )
        for cost, path in COSTS.items()
    ]
    rows = {}
    for suite, motions in suites.items():
        for plant, controllers in ((supervised, [default, mpc]), (unsupervised, references)):
            summary = evaluate(plant, motions, controllers, suite, include_optimal=False).summary()
            for controller in controllers:
                rows.setdefault(controller.name, []).append(
                    f"{summary.loc[controller.name, 'J1']:.3f} / {summary.loc[controller.name, 'J2']:.3f}"
                )
        print(f"evaluated {suite}", flush=True)
    print("| controller | " + " | ".join(f"{suite} J1 / J2" for suite in suites) + " |")
    print("|---|" + "---|" * len(suites))
    for name, cells in rows.items():
        print(f"| {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
