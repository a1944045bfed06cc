"""Benchmark: SAC's environment steps/s, stable-baselines3's against sbx-rl's, and rlc's fast recipe, in one
run.

Usage: python scripts/bench_sac.py [--seconds 60] [--minutes 0] [--out DIR]

1. Throughput, side by side on this machine: environment steps/s inside `model.learn()` after the learner's
   warm-up (past `learning_starts`, the JIT compiled), for
     - the paper's recipe on stable-baselines3 (torch): configs/experiments/paper_sac.yaml with backend: sb3
       (SAC 3x128, gamma 0.999, one env, one gradient step of batch 256 per env step), torch threads 1;
     - the same recipe on sbx-rl (JAX): configs/experiments/paper_sac.yaml as it stands;
     - rlc's fast recipe: studies/training/paper_sac_fast.yaml (configs/algorithms/sac_fast.yaml: 16 buildings
       as one batch, 2 gradient steps per batch step, update-to-data 1/8).
   Each is timed for about --seconds.
2. With --minutes M, each recipe also learns the paper's experiment from nothing for M minutes through `rlc
   train`'s own path (validation included), and its learning curve is written to DIR/NAME.csv: validation J1
   on generated motions (never the records) against wall time, beside LQG's on the same motions.
"""

from __future__ import annotations

import argparse
import csv
import platform
import shutil
import time
from pathlib import Path

import torch

from rlcontroller.config import Experiment, load_experiment
from rlcontroller.learning.algorithms import build_model, make_vec_env
from rlcontroller.learning.training import train
from rlcontroller.physics.plant import Plant

REPOSITORY = Path(__file__).resolve().parents[1]


def recipes() -> dict[str, Experiment]:
    paper = load_experiment(REPOSITORY / "configs" / "experiments" / "paper_sac.yaml")
    torch_paper = paper.model_copy(
        update={"algorithm": paper.algorithm.model_copy(update={"backend": "sb3"})}
    )
    fast = load_experiment(REPOSITORY / "studies" / "training" / "paper_sac_fast.yaml")
    return {
        "paper recipe, stable-baselines3": torch_paper,
        "paper recipe, sbx": paper,
        "fast recipe, sbx": fast,
    }


def steps_per_second(experiment: Experiment, seconds: float) -> float:
    """Env steps/s of learn() after a warm-up past learning_starts, over about `seconds`."""
    torch.set_num_threads(experiment.algorithm.torch_threads)
    vec_env = make_vec_env(Plant(experiment), seed=0)
    model = build_model(experiment, vec_env, seed=0, device="cpu", tensorboard=None)
    n_envs = experiment.algorithm.n_envs
    warmup = int(experiment.algorithm.kwargs.get("learning_starts", 100)) + 200 * n_envs
    model.learn(warmup)
    chunk, trained, start = 100 * n_envs, 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        model.learn(chunk, reset_num_timesteps=False)
        trained += chunk
    rate = trained / (time.perf_counter() - start)
    vec_env.close()
    return rate


def learning_curve(name: str, experiment: Experiment, minutes: float, out: Path) -> None:
    """Learn from nothing for `minutes` through rlc train's path; the curve to OUT/NAME.csv."""
    run = out / "runs" / name.replace(" ", "_").replace(",", "")
    shutil.rmtree(run, ignore_errors=True)
    summary = train(experiment=experiment, run_dir=run, time_limit_s=60.0 * minutes)
    print(f"{name}: {summary.line()}")
    path = out / f"{run.name}.csv"
    with open(run / "learning_curve.csv", newline="") as source, open(path, "w", newline="") as target:
        rows = list(csv.DictReader(source))
        columns = ["steps", "wall_time_s", "eval_J1", "eval_J2", "lqg_J1", "lqg_J2"]
        writer = csv.DictWriter(target, columns, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(rows)
    print(f"  curve: {path}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="timed learning per recipe (throughput)")
    parser.add_argument("--minutes", type=float, default=0.0, help="learn each recipe from nothing this long")
    parser.add_argument("--out", type=Path, default=Path("bench_sac"), help="folder of the learning curves")
    arguments = parser.parse_args()
    print(
        f"machine: {platform.node()} ({platform.machine()}, {torch.get_num_threads()} torch threads "
        "available)"
    )
    rates = {}
    for name, experiment in recipes().items():
        rates[name] = steps_per_second(experiment, arguments.seconds)
        print(f"{name}: {rates[name]:,.0f} env steps/s", flush=True)
    base = rates["paper recipe, stable-baselines3"]
    print(
        "ratios to stable-baselines3's paper recipe: paper recipe on sbx "
        f"{rates['paper recipe, sbx'] / base:.2f}x, "
        f"fast recipe {rates['fast recipe, sbx'] / base:.1f}x"
    )
    if arguments.minutes > 0:
        arguments.out.mkdir(parents=True, exist_ok=True)
        for name, experiment in recipes().items():
            learning_curve(name, experiment, arguments.minutes, arguments.out)


if __name__ == "__main__":
    main()
