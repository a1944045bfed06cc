"""A classical law behind a ground trigger, the trigger (and the law's weights) chosen on a suite of the check's
family with another seed (docs/safety_check.md, "Round 6: what ships"): the check suite is the test set, so no
choice looks at it.

For each trigger [off below, full from] (m/s^2, on the peak ground reading), and each combination of the `--set`
values (experiment settings as `rlc sweep` takes them: `reward.terms.3.weight=1,10,100`), the law is designed for
the experiment behind it and judged by the standard's own suite criterion (`evaluation.safety.suite_criterion`:
levels, k, the bound, means) on the experiment's standard drawn with `--seed` (a wind standard: its wind loads and
its `also` ground motions, both with that seed). The chosen one has the lowest mean J1 + J2 among those that pass
every suite; `rlc design` then `rlc check` judges it on the check suite.

Usage (from the repository's root):
    python studies/safety_check/trigger_selection.py configs/experiments/five_story_amd.yaml \\
        --law lqg_ground_model --triggers 0.5,1.5 1,3 1.5,4 2,5 --seed 777 [--set reward.terms.3.weight=1,10]
"""

from __future__ import annotations

import argparse
import itertools
from pathlib import Path

import yaml

from rlcontroller.api.common import safety_standard
from rlcontroller.config import SupervisorConfig, load_experiment, with_overrides
from rlcontroller.config.scenarios import load_safety_check
from rlcontroller.control.classical import classical_policy
from rlcontroller.evaluation.safety import drift_bounds, suite_criterion
from rlcontroller.physics.plant import Plant


def judged(config: Path, law: str, trigger: tuple[float, float], seed: int, settings: dict | None = None) -> list[dict]:
    """The suite criteria of `law` behind `trigger` on the experiment's standard(s) drawn with `seed`, the
    experiment's `settings` changed (dotted paths to values)."""
    base = load_experiment(config)
    if settings:
        base = with_overrides(base, settings, "--set")
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
    parser.add_argument("--set", action="append", default=[], help="KEY=V1,V2,...: experiment settings to try")
    arguments = parser.parse_args()
    check = load_safety_check(safety_standard(load_experiment(arguments.config)))
    if arguments.seed == check.seed:
        parser.error(f"seed {arguments.seed} is the check suite's: pick another")
    keys = [text.split("=", 1)[0] for text in arguments.set]
    values = [[yaml.safe_load(value) for value in text.split("=", 1)[1].split(",")] for text in arguments.set]
    best = None
    for text in arguments.triggers:
        trigger = tuple(float(value) for value in text.split(","))
        for chosen in itertools.product(*values):
            settings = dict(zip(keys, chosen, strict=True))
            criteria = judged(arguments.config, arguments.law, trigger, arguments.seed, settings)
            passed = all(criterion["passed"] for criterion in criteria)
            score = criteria[0]["mean_J1"] + criteria[0]["mean_J2"]
            label = f"trigger {list(trigger)}" + "".join(f", {key}={value}" for key, value in settings.items())
            for criterion in criteria:
                print(f"{label}: {'pass' if criterion['passed'] else 'FAIL'} - {criterion['summary']}", flush=True)
            if passed and (best is None or score < best[1]):
                best = (label, score)
    print(f"chosen: {best[0]} (mean J1 + J2 {best[1]:.3f})" if best else "none passes")


if __name__ == "__main__":
    main()
