"""The nine-story FE frame at two analysis steps (docs/opensees.md, "Speed"): LQG + ground model and the
uncontrolled frame on motions of the check's family drawn with another seed (777; never the check suite), each
motion's uncontrolled peak drift, the check's ratio (`metrics.ratio_to_reference`) and peak floor
accelerations, and the wall time of each step's runs (fanned out over the cores).

Usage (from the repository's root; about 4 and 6 min on this project's 2 shared cores):
    python studies/opensees/frame_step.py --steps 0.01 0.005
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from rlcontroller.api.common import load
from rlcontroller.config.scenarios import load_safety_check, safety_standard
from rlcontroller.control.classical import classical_policy
from rlcontroller.evaluation.evaluation import evaluate
from rlcontroller.evaluation.safety import check_suite
from rlcontroller.physics.metrics import ratio_to_reference
from rlcontroller.physics.plant import Plant

REPOSITORY = Path(__file__).resolve().parents[2]
EXPERIMENT = REPOSITORY / "configs" / "experiments" / "nine_story_frame.yaml"
MOTIONS = [199, 246, 71, 91, 277, 24, 185, 299]  # of seed 777: 0.04-1.3 g, elastic to 6 % drift


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=float, nargs="+", default=[0.01, 0.005], help="analysis steps (s)")
    parser.add_argument("--seed", type=int, default=777)
    arguments = parser.parse_args()
    base = load(EXPERIMENT)
    check = load_safety_check(safety_standard(base))
    if arguments.seed == check.seed:
        parser.error(f"seed {arguments.seed} is the check suite's: pick another")
    standard = check.model_copy(update={"seed": arguments.seed})
    names = {f"mixture_{arguments.seed}_{i}" for i in MOTIONS}
    for step in arguments.steps:
        opensees = base.plant.opensees.model_copy(update={"analysis_dt": step})
        plant = Plant(base.model_copy(update={"plant": base.plant.model_copy(update={"opensees": opensees})}))
        motions = [motion for motion in check_suite(plant, standard) if motion.name in names]
        controller = classical_policy(plant, "lqg_ground_model")
        start = time.perf_counter()
        evaluation = evaluate(plant, motions, [controller], "step", include_optimal=False)
        print(f"analysis step {step} s: {time.perf_counter() - start:.0f} s", flush=True)
        for motion in motions:
            reference = evaluation.responses["uncontrolled", motion.name]
            controlled = evaluation.responses[controller.name, motion.name]
            ratio = ratio_to_reference(controlled, reference)
            print(
                f"  {motion.name} ({np.max(np.abs(motion.acceleration)) / 9.80665:.2f} g): uncontrolled peak "
                f"drift {1000 * np.max(np.abs(reference.drift)):.2f} mm, ratio {ratio:.4f}, "
                f"peak floor acceleration {np.max(np.abs(reference.absolute_acceleration)):.3f} / "
                f"{np.max(np.abs(controlled.absolute_acceleration)):.3f} m/s^2"
            )


if __name__ == "__main__":
    main()
