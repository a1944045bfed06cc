"""A classical law behind a ground trigger, the trigger (and the law's weights) chosen on a suite of the
check's family with another seed (docs/safety_check.md, "Round 6: what ships"): the check suite is the test
set, so no choice looks at it.

For each trigger [off below, full from] (m/s^2, on the peak ground reading), and each combination of the
`--set` values (experiment settings as `rlc sweep` takes them: `reward.terms.3.weight=1,10,100`), the law is
designed for the experiment behind it and judged by the standard's own suite criterion
(`evaluation.safety.suite_criterion`: levels, k, the bound, means) on the experiment's standard drawn with
`--seed` (a wind standard: its wind loads and its `also` ground motions, both with that seed). The chosen one
has the lowest mean J1 + J2 among those that pass every suite and, with `--rest-margin`, is quiet at rest with
that share of the bound to spare (the standard's at-rest run with 64 noise realisations of seeds of its own: a
quiet motion's drift adds to what the sensors' noise drives, so a law the noise alone takes near the bound
fails quiet motions by the draw); `rlc design` then `rlc check` judges it on the check suite. Several
`--seed`s pool their suites: a choice must pass each. With `--model FOLDER` the folder's saved policy (a
learned one) is judged behind each trigger instead of a designed law, in the folder's own experiment.

Usage (from the repository's root):
    python studies/safety_check/trigger_selection.py configs/experiments/five_story_amd.yaml \\
        --law lqg_ground_model --triggers 0.5,1.5 1,3 1.5,4 2,5 --seed 777 [--set reward.terms.3.weight=1,10]
    python studies/safety_check/trigger_selection.py models/five_story_every_story/config.yaml \
        --model models/five_story_every_story --triggers 0.1,0.3 0.15,0.45 --seed 777
"""

from __future__ import annotations

import argparse
import itertools
from pathlib import Path

import yaml

from rlcontroller.config import SupervisorConfig, load_experiment, with_overrides
from rlcontroller.config.scenarios import load_safety_check, safety_standard
from rlcontroller.control.classical import classical_policy
from rlcontroller.control.policy_file import read_policy
from rlcontroller.evaluation.safety import drift_bounds, rest_criterion, suite_criterion
from rlcontroller.physics.plant import Plant


def judged(
    config: Path,
    law: str,
    trigger: tuple[float, float],
    seed: int,
    settings: dict | None = None,
    model: Path | None = None,
) -> list[dict]:
    """The suite criteria of `law` (or `model`'s saved best policy) behind `trigger` on the experiment's
    standard(s) drawn with `seed`, the experiment's `settings` changed (dotted paths to values)."""
    base = load_experiment(config)
    if settings:
        base = with_overrides(base, settings, "--set")
    supervisor = (base.supervisor or SupervisorConfig()).model_copy(update={"trigger": trigger})
    plant = Plant(base.model_copy(update={"supervisor": supervisor}))
    standard = load_safety_check(safety_standard(base))
    suites = [standard.model_copy(update={"seed": seed})]
    if standard.also is not None:
        suites.append(standard.also.model_copy(update={"seed": seed}))
    controller = classical_policy(plant, law) if model is None else read_policy(model, "best", plant)
    criteria = [suite_criterion(plant, controller, suite, drift_bounds(plant, suite)) for suite in suites]
    rest = suites[0].model_copy(update={"rest_runs": REST_RUNS})
    return criteria + [rest_criterion(plant, controller, rest, drift_bounds(plant, rest))]


REST_RUNS = 64


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", type=Path, help="an experiment YAML")
    parser.add_argument("--law", default="lqg_ground_model", help="a classical law (`rlc design --law`)")
    parser.add_argument("--triggers", nargs="+", required=True, help="OFF,FULL pairs in m/s^2")
    parser.add_argument(
        "--seed", type=int, nargs="+", default=[777], help="selection suites (never the check)"
    )
    parser.add_argument(
        "--set", action="append", default=[], help="KEY=V1,V2,...: experiment settings to try"
    )
    parser.add_argument(
        "--model", type=Path, default=None, help="a folder whose saved policy is judged instead"
    )
    parser.add_argument("--rest-margin", type=float, default=0.0, help="share of the bound to spare at rest")
    arguments = parser.parse_args()
    check = load_safety_check(safety_standard(load_experiment(arguments.config)))
    if check.seed in arguments.seed:
        parser.error(f"seed {check.seed} is the check suite's: pick another")
    keys = [text.split("=", 1)[0] for text in arguments.set]
    values = [[yaml.safe_load(value) for value in text.split("=", 1)[1].split(",")] for text in arguments.set]
    best = None
    for text in arguments.triggers:
        trigger = tuple(float(value) for value in text.split(","))
        for chosen in itertools.product(*values):
            settings = dict(zip(keys, chosen, strict=True))
            label = f"trigger {list(trigger)}" + "".join(
                f", {key}={value}" for key, value in settings.items()
            )
            passed, scores = True, []
            for seed in arguments.seed:
                *suites, rest = judged(
                    arguments.config, arguments.law, trigger, seed, settings, arguments.model
                )
                quiet = rest.peak_drift_over_bound <= 1.0 - arguments.rest_margin
                passed = passed and quiet and all(criterion.passed for criterion in suites)
                scores.append(suites[0].mean_J1 + suites[0].mean_J2)
                for criterion in suites:
                    outcome = "pass" if criterion.passed else "FAIL"
                    print(f"{label}, seed {seed}: {outcome} - {criterion.summary}")
                print(f"{label}, seed {seed}: at rest {rest.summary}", flush=True)
            score = float(sum(scores) / len(scores))
            if passed and (best is None or score < best[1]):
                best = (label, score)
    print(f"chosen: {best[0]} (mean J1 + J2 {best[1]:.3f})" if best else "none passes")


if __name__ == "__main__":
    main()
