"""Diagnostic: can a fixed linear map of the model-free observation control as well as LQG?

Usage: python studies/model_free/linear_clone.py [--config studies/model_free/five_story_model_free.yaml]
                                      [--motions 96] [--seed 777] [--records ../shared/records]

LQG + measured ground (designed on the design model; the teacher) runs on `--motions` training
motions (the experiment's generator, its own seed); a linear map W (no bias, so odd) from the
experiment's observation to the teacher's action is fitted by ridge regression; the clone a = clip(W o)
is then run like any controller on the validation motions and, if given, the records. The clone is
not a model-free controller (W distils the teacher's model); it measures whether the observation
holds what LQG-level control needs, i.e. whether a learner that falls short lacks information or
optimisation.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from rlcontroller.config import ConfigError, load_experiment
from rlcontroller.control.controllers import LinearFeedback, LQGController
from rlcontroller.control.lqg import design_lqg
from rlcontroller.evaluation.evaluation import evaluate
from rlcontroller.learning.env import BuildingEnv
from rlcontroller.physics.motions.excitation import MotionError
from rlcontroller.physics.motions.generators import generate_suite
from rlcontroller.physics.motions.records import load_records
from rlcontroller.physics.plant import Plant

REPOSITORY = Path(__file__).resolve().parents[2]


def fit_linear(observations: np.ndarray, actions: np.ndarray, ridge: float) -> np.ndarray:
    """W (m, n) minimising |observations W' - actions|^2 + ridge * samples * |W|^2."""
    x = np.asarray(observations, dtype=float)
    gram = x.T @ x + ridge * len(x) * np.eye(x.shape[1])
    return np.linalg.solve(gram, x.T @ np.asarray(actions, dtype=float)).T


def teacher_data(
    plant: Plant, teacher: LQGController, count: int, seed: int
) -> tuple[np.ndarray, np.ndarray]:
    """(observations, teacher actions) of every step of `count` training motions."""
    env = BuildingEnv(plant)
    observations, actions = [], []
    for index, motion in enumerate(generate_suite(plant.experiment.excitation.generator, count, seed)):
        observation, _ = env.reset(seed=seed + index, options={"motion": motion})
        teacher.reset()
        ended = False
        while not ended:
            action = teacher.act(observation)
            observations.append(observation)
            actions.append(action)
            observation, _, terminated, truncated, _ = env.step(action)
            ended = terminated or truncated
    return np.array(observations, dtype=float), np.array(actions)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--config", type=Path, default=REPOSITORY / "studies" / "model_free" / "five_story_model_free.yaml"
    )
    parser.add_argument("--motions", type=int, default=96)
    parser.add_argument("--seed", type=int, default=777)
    parser.add_argument("--ridge", type=float, default=1e-3)
    parser.add_argument("--records", type=Path, default=None)
    arguments = parser.parse_args()

    plant = Plant(load_experiment(arguments.config))
    records = load_records(arguments.records)[0] if arguments.records is not None else None  # before the work
    teacher = LQGController(
        design_lqg(plant.design, known_ground=True), plant.design, "LQG + ground (teacher)"
    )
    observations, actions = teacher_data(plant, teacher, arguments.motions, arguments.seed)
    weights = fit_linear(observations, actions, arguments.ridge)
    fit = 1.0 - (actions - observations @ weights.T).var() / actions.var()
    print(f"{len(observations)} steps of {arguments.motions} training motions; fit R^2 {fit:.3f}")
    excitation = plant.experiment.excitation
    suites = {
        "validation motions": generate_suite(
            excitation.validation, excitation.validation_motions, excitation.validation_seed
        )
    }
    if records is not None:
        suites["records"] = records
    for label, motions in suites.items():
        summary = evaluate(
            plant,
            motions,
            [teacher, LinearFeedback(weights, "linear clone of LQG + ground")],
            label,
            include_optimal=False,
        ).summary()
        print(f"\n{label} (mean J1, J2, J3)\n{summary[['J1', 'J2', 'J3']].round(3).to_string()}")


if __name__ == "__main__":
    try:
        main()
    except (ConfigError, MotionError) as error:  # a bad config, records or output folder: one line
        raise SystemExit(f"error: {error}") from None
