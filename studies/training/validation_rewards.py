"""A training run's policies and the classical laws on its validation motions, by its reward and by J1, J2.

    python studies/training/validation_rewards.py RUN_DIR

What docs/training.md ("From nothing") uses to tell a learner that drifts from one whose reward does not
rank policies as J1 and J2 do: the run's best and final policies beside LQG and LQG + ground model with the
same cost, each on the run's validation motions (`learning.validation.Validator`: generated motions, never
the records), by the mean validation reward (higher is better) and the mean J1 and J2.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rlcontroller.config import load_experiment
from rlcontroller.control.controllers import LQGController
from rlcontroller.control.lqg import design_lqg, design_lqg_ground_model
from rlcontroller.control.policy_file import read_policy
from rlcontroller.learning.validation import Validator
from rlcontroller.physics.plant import Plant


def validation_rows(run_dir: Path) -> dict[str, dict[str, float]]:
    """Each controller's validation row (`Validator.run`): LQG, LQG + ground model, the run's best and
    final."""
    plant = Plant(load_experiment(run_dir / "config.yaml"))
    validator = Validator(plant)
    rows = {
        "LQG": validator.run(LQGController(design_lqg(plant.design), plant.design)),
        "LQG + ground model": validator.run(
            LQGController(design_lqg_ground_model(plant.design), plant.design)
        ),
    }
    for model in ("best", "final"):
        if (run_dir / f"{model}_policy.yaml").is_file():
            rows[f"run's {model}"] = validator.run(read_policy(run_dir, model, plant))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run_dir", type=Path)
    rows = validation_rows(parser.parse_args().run_dir)
    print("| controller | validation reward | J1 | J2 |\n|---|---|---|---|")
    for name, row in rows.items():
        print(f"| {name} | {row['eval_reward']:.1f} | {row['eval_J1']:.3f} | {row['eval_J2']:.3f} |")


if __name__ == "__main__":
    main()
