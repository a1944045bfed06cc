"""A classical law behind a ground trigger, the trigger chosen on a suite of the check's family with another seed
(docs/safety_check.md, "Round 6: what ships"): the check suite is the test set, so no choice looks at it.

For each trigger [off below, full from] (m/s^2, on the peak ground reading) the law is designed for the experiment
behind it and judged by the standard's own suite criterion (`evaluation.safety.suite_criterion`: levels, k, the
bound, means) on the experiment's standard drawn with `--seed` (a wind standard: its wind loads and its `also`
ground motions, both with that seed). The chosen trigger is the one with the lowest mean J1 + J2 among those that
pass every suite; `rlc design` then `rlc check` judges it on the check suite.

Usage (from the repository's root):
    python studies/safety_check/trigger_selection.py configs/experiments/five_story_amd.yaml \\
        --law lqg_ground_model --triggers 0.5,1.5 1,3 1.5,4 2,5 --seed 777
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rlcontroller.api.common import safety_standard
from rlcontroller.config import SupervisorConfig, load_experiment
from rlcontroller.config.scenarios import load_safety_check
from rlcontroller.control.classical import classical_policy
from rlcontroller.evaluation.safety import drift_bounds, suite_criterion
from rlcontroller.physics.plant import Plant


def judged(config: Path, law: str, trigger: tuple[float, float], seed: int) -> list[dict]:
    """The suite criteria of `law` behind `trigger` on the experiment's standard(s) drawn with `seed`."""
    base = load_experiment(config)
    supervisor = (base.supervisor or SupervisorConfig()).model_copy(update={"trigger": trigger})
    plant = Plant(base.model_copy(update={"supervisor": supervisor}))
    standard = load_safety_check(safety_standard(base))
    suites = [standard.model_copy(update={"seed": seed})]
    if standard.also is not None:
        suites.append(standard.also.model_copy(update={"seed": seed}))
    controller = classical_policy(plant, law)
    return [suite_criterion(plant, controller, suite, drift_bounds(plant, suite)) for suite in suites]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", type=Path, help="an experiment YAML")
    parser.add_argument("--law", default="lqg_ground_model", help="a classical law (`rlc design --law`)")
    parser.add_argument("--triggers", nargs="+", required=True, help="OFF,FULL pairs in m/s^2")
    parser.add_argument("--seed", type=int, default=777, help="the selection suite's seed (not the check's)")
    arguments = parser.parse_args()
    check = load_safety_check(safety_standard(load_experiment(arguments.config)))
    if arguments.seed == check.seed:
        parser.error(f"seed {arguments.seed} is the check suite's: pick another")
    best = None
    for text in arguments.triggers:
        trigger = tuple(float(value) for value in text.split(","))
        criteria = judged(arguments.config, arguments.law, trigger, arguments.seed)
        passed = all(criterion["passed"] for criterion in criteria)
        score = criteria[0]["mean_J1"] + criteria[0]["mean_J2"]
        for criterion in criteria:
            print(f"trigger {list(trigger)}: {'pass' if criterion['passed'] else 'FAIL'} - {criterion['summary']}")
        if passed and (best is None or score < best[1]):
            best = (trigger, score)
    print(f"chosen: trigger {list(best[0])} (mean J1 + J2 {best[1]:.3f})" if best else "none passes")


if __name__ == "__main__":
    main()
