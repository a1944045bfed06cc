"""Designs for the nine-story frame judged on its nonlinear reduced model (docs/opensees.md, "Designs on the
nonlinear reduced model"): a classical law (LQG + ground model by default, designed on the linear reduced
model, with the cost's weights scaled by --weights) alone or behind a supervisor (a trigger, the dissipative
rule on the estimate or on measured stroke velocities, stiffness-proportional dampers past a hand-over drift),
judged by the safety check's own criterion on suites of the check's family drawn with other seeds (never the
check suite's 31337), optionally with every PGA drawn log-uniform in [--pga-low, --pga-high] (m/s^2).

Usage (from the repository's root; 2-4 min per suite of 320 on one of this project's 2 shared cores):
    python studies/opensees/frame_supervisor.py --no-trigger --no-fallback --weights force=0.3
absolute_acceleration=30 Prints, per suite, the check's summary line, each failing motion, and the mean J1 and
J2 by PGA.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from rlcontroller.config import SupervisorConfig, load_experiment
from rlcontroller.config.scenarios import load_safety_check, safety_standard
from rlcontroller.control.classical import classical_policy
from rlcontroller.evaluation.evaluation import scaled_weights
from rlcontroller.evaluation.safety import drift_bounds, suite_criterion
from rlcontroller.physics.hysteresis import story_springs
from rlcontroller.physics.plant import Plant

REPOSITORY = Path(__file__).resolve().parents[2]
EXPERIMENT = REPOSITORY / "studies" / "opensees" / "nine_story_frame_reduced" / "config.yaml"
PGA_BINS = [(0.0, 0.01), (0.01, 0.05), (0.05, 0.15), (0.15, 0.5), (0.5, 2.0)]  # g
DISSIPATIVE = {"measured": "measured", "estimate": True}


def supervisor(arguments: argparse.Namespace, springs: np.ndarray) -> SupervisorConfig | None:
    """The supervisor the arguments describe (None: the controller alone)."""
    if arguments.no_supervisor:
        return None
    fallback = None
    if not arguments.no_fallback:
        damping = [arguments.beta * k for k in springs]  # N s/m: stiffness-proportional
        fallback = {"drift": arguments.drift, "damping": damping, "deadband": 0.01}
    fields = {"trigger": None if arguments.no_trigger else arguments.trigger, "fallback": fallback}
    if arguments.dissipative != "none":
        fields |= {"dissipative": DISSIPATIVE[arguments.dissipative], "fade_velocity": 0.1}
    return SupervisorConfig.model_validate(fields)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--experiment", type=Path, default=EXPERIMENT)
    parser.add_argument("--law", default="lqg_ground_model")
    parser.add_argument(
        "--weights", nargs="*", default=[], help="QUANTITY=M: the cost's QUANTITY weight times M"
    )
    parser.add_argument("--no-supervisor", action="store_true", help="the controller alone")
    parser.add_argument("--trigger", type=float, nargs=2, default=[0.2, 0.6], help="m/s^2")
    parser.add_argument("--no-trigger", action="store_true", help="full authority from the first step")
    parser.add_argument("--dissipative", default="measured", choices=[*DISSIPATIVE, "none"])
    parser.add_argument("--no-fallback", action="store_true", help="no dampers past the hand-over drift")
    parser.add_argument("--beta", type=float, default=0.05, help="s: damping = beta x each story's stiffness")
    parser.add_argument("--drift", type=float, default=0.02, help="m: the hand-over's estimated story drift")
    parser.add_argument("--seeds", type=int, nargs="+", default=[777, 778])
    parser.add_argument("--motions", type=int, default=320)
    parser.add_argument("--pga-low", type=float, default=None, help="m/s^2; default: the check's own range")
    parser.add_argument("--pga-high", type=float, default=14.71, help="m/s^2 (1.5 g, the check's largest)")
    arguments = parser.parse_args()
    base = load_experiment(arguments.experiment)
    springs = story_springs(np.asarray(base.building.mass_matrix), np.asarray(base.building.stiffness_matrix))
    multipliers = {item.split("=")[0]: float(item.split("=")[1]) for item in arguments.weights}
    layer = supervisor(arguments, springs)
    plant = Plant(
        base.model_copy(update={"supervisor": layer, "reward": scaled_weights(base.reward, multipliers)})
    )
    check = load_safety_check(safety_standard(base))
    controller = classical_policy(plant, arguments.law)
    print(f"{arguments.law}, weights x{multipliers or 1}, supervisor {layer.model_dump() if layer else None}")
    for seed in arguments.seeds:
        if seed == check.seed:
            parser.error(f"seed {seed} is the check suite's: pick another")
        generator = check.generator.model_dump()
        if arguments.pga_low is not None:
            for component in generator["components"]:
                component["generator"]["pga"] = [arguments.pga_low, arguments.pga_high]
        suite = type(check).model_validate(
            check.model_dump() | {"generator": generator, "seed": seed, "motions": arguments.motions}
        )
        verdict = suite_criterion(plant, controller, suite, drift_bounds(plant, suite))
        print(f"seed {seed}: {verdict.summary}", flush=True)
        motions = verdict.per_motion
        for name in verdict.failures:
            print(f"  {name}: {motions[name].row()}")
        rows = np.array([[row.pga_g, row.J1, row.J2] for row in motions.values() if row.significant])
        for low, high in PGA_BINS:
            inside = rows[(rows[:, 0] >= low) & (rows[:, 0] < high)]
            if inside.size:
                j1, j2 = inside[:, 1].mean(), inside[:, 2].mean()
                print(
                    f"  PGA {low}-{high} g: {len(inside)} motions, mean J1 {j1:.3f}, J2 {j2:.3f}", flush=True
                )


if __name__ == "__main__":
    main()
