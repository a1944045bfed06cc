"""Model-free learning of a linear odd policy a = clip(W o) by random search with common random numbers.

Usage: python scripts/linear_random_search.py OUT [--config configs/five_story_model_free.yaml] [--seed 0]
           [--iterations 600] [--directions 8] [--motions 8] [--sigma 0.02] [--step 0.01] [--records DIR]

Augmented random search (Mania et al., 2018) on W (actuators x observation), started at W = 0 (no
control): each iteration draws `motions` training motions and noise seeds and `directions` random
directions d_k, runs W + sigma d_k and W - sigma d_k on the *same* motions and noise (common random
numbers: a strong motion's return is 10^4 times a weak one's, which would otherwise drown every
difference), and steps along sum_k (f(W + sigma d_k) - f(W - sigma d_k)) d_k scaled by the spread of
the f's, with f = the mean over the motions of log(-return) (each motion counts by its relative
change). The policy reads only the experiment's observation (for the model-free config: readings and
their model-free integrals); no model enters. With `plant_randomization` every motion runs on a plant
drawn with its seed (the same for + and -). Every 10 iterations W is validated on the experiment's
validation motions (and plants); the best validation J1 is kept. Writes OUT/weights.npy (the best W),
OUT/curve.csv, and the policy as a model folder `rlc evaluate`, `rlc robustness` and `rlc export`
read: OUT/best_model.zip (the experiment's own PPO policy, which must have a linear odd actor,
`policy: {actor_arch: [], odd: true}`, with W as its action layer; trained by this script, not by
PPO) and OUT/config.yaml. With --records, prints the best W's J1-J4 on them.

sb3-contrib's ARS evaluates each candidate on the environment's next episodes, so + and - never see
the same motion; hence this script rather than that class.
"""

from __future__ import annotations

import argparse
import io
import time
from pathlib import Path

import numpy as np

from rlcontroller.config import ConfigError, Experiment, load_experiment
from rlcontroller.control.controllers import LinearFeedback
from rlcontroller.evaluation.evaluation import evaluate
from rlcontroller.files import atomic_write, check_new_folder, new_folder
from rlcontroller.learning.batch import batch_rollout
from rlcontroller.learning.validation import Validator
from rlcontroller.physics.excitation import GroundMotion, MotionError, generate_suite
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.records import load_records

REPOSITORY = Path(__file__).resolve().parents[1]
POLICY = "RL (linear, random search)"


def paired_log_costs(
    plant: Plant, weights: np.ndarray, deltas: np.ndarray, motions: list[GroundMotion], seeds: list[int]
) -> tuple[np.ndarray, np.ndarray]:
    """f(W + d_k) and f(W - d_k) for every direction, all on the same motions, noise seeds and (with
    `plant_randomization`) plants drawn from those seeds."""
    policies = [LinearFeedback(weights + d) for d in deltas] + [LinearFeedback(weights - d) for d in deltas]
    runs = batch_rollout(plant, motions, policies, seeds=seeds, randomize=True)
    f = np.array([np.mean([np.log(max(-total, 1e-300)) for _, total in lane]) for lane in runs])
    return f[: len(deltas)], f[len(deltas) :]


def random_search(
    experiment: Experiment,
    seed: int,
    iterations: int,
    directions: int,
    motions: int,
    sigma: float,
    step: float,
    log=print,
) -> tuple[np.ndarray, list[dict[str, float]]]:
    """The best-validated W and the learning curve (iteration, seconds, validation J1 and J2)."""
    plant = Plant(experiment)
    validator = Validator(plant)
    rng = np.random.default_rng(seed)
    weights = np.zeros((plant.building.n_actuators, plant.layout.size))
    best_j1, best = np.inf, weights.copy()
    curve: list[dict[str, float]] = []
    start = time.perf_counter()
    for iteration in range(1, iterations + 1):
        batch = generate_suite(experiment.excitation.generator, motions, int(rng.integers(2**31)))
        seeds = [int(s) for s in rng.integers(2**31, size=motions)]
        deltas = sigma * rng.standard_normal((directions, *weights.shape))
        plus, minus = paired_log_costs(plant, weights, deltas, batch, seeds)
        spread = float(np.std(np.concatenate([plus, minus]))) or 1.0
        weights = weights - step / (directions * spread * sigma) * np.tensordot(plus - minus, deltas, axes=1)
        if iteration % 10 == 0:
            result = validator.run(LinearFeedback(weights))
            j1, j2 = result["eval_J1"], result["eval_J2"]
            if j1 < best_j1:
                best_j1, best = j1, weights.copy()
            curve.append({"iteration": iteration, "seconds": time.perf_counter() - start, "J1": j1, "J2": j2})
            log(f"iteration {iteration}: validation J1 {j1:.3f}, J2 {j2:.3f} ({curve[-1]['seconds']:.0f} s)")
    return best, curve


def as_model(experiment: Experiment, weights: np.ndarray):
    """The experiment's PPO model with the linear odd actor's action layer set to W (bias 0)."""
    import torch

    from rlcontroller.learning.algorithms import build_model, make_vec_env

    policy = experiment.algorithm.policy
    if experiment.algorithm.name != "PPO" or policy.actor_arch != [] or not policy.odd:
        raise SystemExit("the experiment's algorithm must be PPO with policy: {actor_arch: [], odd: true}")
    model = build_model(experiment, make_vec_env(Plant(experiment), experiment.seed), experiment.seed, "cpu", None)
    with torch.no_grad():
        model.policy.action_net.weight.copy_(torch.as_tensor(weights, dtype=torch.float32))
        model.policy.action_net.bias.zero_()
    return model


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="a new folder")
    parser.add_argument("--config", type=Path, default=REPOSITORY / "configs" / "five_story_model_free.yaml")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--iterations", type=int, default=600)
    parser.add_argument("--directions", type=int, default=8)
    parser.add_argument("--motions", type=int, default=8)
    parser.add_argument("--sigma", type=float, default=0.02)
    parser.add_argument("--step", type=float, default=0.01)
    parser.add_argument("--records", type=Path, default=None)
    arguments = parser.parse_args()

    experiment = load_experiment(arguments.config)
    check_new_folder(arguments.out)
    records = load_records(arguments.records) if arguments.records is not None else None  # before the search
    weights, curve = random_search(
        experiment,
        arguments.seed,
        arguments.iterations,
        arguments.directions,
        arguments.motions,
        arguments.sigma,
        arguments.step,
    )
    buffer = io.BytesIO()
    np.save(buffer, weights)
    rows = [f"{r['iteration']},{r['seconds']:.1f},{r['J1']:.6f},{r['J2']:.6f}" for r in curve]
    model = as_model(experiment, weights)
    with new_folder(arguments.out) as staging:
        atomic_write(staging / "weights.npy", buffer.getvalue())
        atomic_write(staging / "curve.csv", "\n".join(["iteration,seconds,J1,J2", *rows]) + "\n")
        atomic_write(staging / "config.yaml", experiment.model_copy(update={"seed": arguments.seed}).to_yaml())
        model.save(staging / "best_model.zip")
    best = min(curve, key=lambda row: row["J1"])
    print(f"best validation J1 {best['J1']:.3f} (J2 {best['J2']:.3f}) at iteration {best['iteration']}")
    print(f"weights and learning curve in {arguments.out}")
    if records is not None:
        motions, label = records
        summary = evaluate(
            Plant(experiment), motions, [LinearFeedback(weights, POLICY)], label, include_optimal=False
        ).summary()
        print(f"{label}\n{summary[['J1', 'J2', 'J3', 'J4']].round(3).to_string()}")


if __name__ == "__main__":
    try:
        main()
    except (ConfigError, MotionError) as error:  # a bad config, records or output folder: one line
        raise SystemExit(f"error: {error}") from None
