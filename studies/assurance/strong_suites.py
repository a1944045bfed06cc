"""The yielding building's fallback on strong motions of the check's family (docs/assurance.md, "A building
that yields", step 4): LQG + ground model behind configs/supervisors/yielding.yaml with its
stiffness-proportional dampers' beta (s) and hand-over drift (m) set here, judged by the check's own criterion
on suites whose every PGA is drawn log-uniform in [--pga-low, --pga-high] (m/s^2), seeds other than the check
suite's.

Usage (from the repository's root; about 1.5 min per suite of 320 on 2 cores):
    python studies/assurance/strong_suites.py --beta 0.05 --drift 0.02 --seeds 779 780 781
Prints, per suite, the check's summary line and each failing motion with its reference's peak drift.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rlcontroller.config import SafetyCheckConfig, load_experiment
from rlcontroller.config.scenarios import load_safety_check, safety_standard
from rlcontroller.control.classical import classical_policy
from rlcontroller.evaluation.safety import drift_bounds, suite_criterion
from rlcontroller.physics.plant import Plant

REPOSITORY = Path(__file__).resolve().parents[2]
EXPERIMENT = REPOSITORY / "configs" / "experiments" / "five_story_yielding.yaml"


def strong_suite(
    check: SafetyCheckConfig, seed: int, motions: int, low: float, high: float
) -> SafetyCheckConfig:
    """The check's standard with its motions drawn from its own generator family, every PGA log-uniform in
    [low, high] (m/s^2), `motions` of them with `seed`."""
    generator = check.generator.model_dump()
    for source in (
        [part["generator"] for part in generator["components"]] if "components" in generator else [generator]
    ):
        source["pga"] = [low, high]
    return type(check).model_validate(
        check.model_dump() | {"generator": generator, "seed": seed, "motions": motions}
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--beta", type=float, default=0.05, help="s: damping = beta x each story's stiffness")
    parser.add_argument("--drift", type=float, default=0.02, help="m: the hand-over's estimated story drift")
    parser.add_argument("--seeds", type=int, nargs="+", default=[779, 780, 781])
    parser.add_argument("--motions", type=int, default=320)
    parser.add_argument("--pga-low", type=float, default=4.9, help="m/s^2 (0.5 g)")
    parser.add_argument("--pga-high", type=float, default=14.71, help="m/s^2 (1.5 g, the check's largest)")
    arguments = parser.parse_args()
    base = load_experiment(EXPERIMENT)
    stiffness = base.building.stiffnesses  # N/m, stories 1-5
    fallback = base.supervisor.fallback.model_copy(
        update={"drift": arguments.drift, "damping": [arguments.beta * k for k in stiffness]}
    )
    plant = Plant(
        base.model_copy(update={"supervisor": base.supervisor.model_copy(update={"fallback": fallback})})
    )
    check = load_safety_check(safety_standard(base))
    controller = classical_policy(plant, "lqg_ground_model")
    for seed in arguments.seeds:
        if seed == check.seed:
            parser.error(f"seed {seed} is the check suite's: pick another")
        suite = strong_suite(check, seed, arguments.motions, arguments.pga_low, arguments.pga_high)
        verdict = suite_criterion(plant, controller, suite, drift_bounds(plant, suite))
        print(f"seed {seed}: {verdict.summary}")
        for name in verdict.failures:
            print(f"  {name}: {verdict.per_motion[name].row()}")


if __name__ == "__main__":
    main()
