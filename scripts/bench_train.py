"""Benchmark: training throughput and time-to-quality, plain paper SAC against the new default.

Usage: python scripts/bench_train.py [--minutes 15] [--skip-quality] [--vec-env-only]

1. The batched vector env against DummyVecEnv, side by side in this one run, for n_envs 8, 32 and
   128 on the default experiment (PPO residual on LQG): env steps/s of rollout collection alone
   (PPO's collect_rollouts: policy forward, env step, buffer) and of whole PPO training (collection
   plus 10 epochs of updates on 256 steps per env).
2. Environment steps per second inside model.learn(): the paper's SAC (MLP 3x128, batch 256,
   one gradient step per env step) and PPO with 8 envs, torch threads 1 and 2.
3. Time-to-quality, side by side in this one run: configs/experiments/paper_sac.yaml (the plain recipe) and
   configs/five_story.yaml (the new default) are each trained for at most --minutes of wall time;
   quality is reached when the validation J1 (generated motions, never the records) falls below
   that of LQG with the same cost on the same motions.
"""

from __future__ import annotations

import argparse
import platform
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from rlcontroller.config import AlgorithmConfig, Experiment, load_experiment
from rlcontroller.learning.algorithms import build_model, make_vec_env
from rlcontroller.learning.training import train
from rlcontroller.physics.plant import Plant

PAPER_STEPS = 1_500_000
CONFIGS = Path(__file__).resolve().parents[1] / "configs"


def steps_per_second(experiment: Experiment, steps: int, warmup: int, threads: int) -> float:
    torch.set_num_threads(threads)
    vec_env = make_vec_env(Plant(experiment), seed=0)
    model = build_model(experiment, vec_env, seed=0, device="cpu", tensorboard=None)
    model.learn(warmup)
    start = time.perf_counter()
    model.learn(steps, reset_num_timesteps=False)
    rate = (model.num_timesteps - warmup) / (time.perf_counter() - start)
    vec_env.close()
    return rate


def with_envs(experiment: Experiment, n_envs: int, vec_env: str) -> Experiment:
    algorithm = experiment.algorithm.model_copy(update={"n_envs": n_envs, "vec_env": vec_env})
    return experiment.model_copy(update={"algorithm": algorithm})


def collection_and_training(experiment: Experiment) -> tuple[float, float]:
    """(env steps/s of one rollout collection, env steps/s of learn() over two rollouts)."""
    vec_env = make_vec_env(Plant(experiment), seed=0)
    model = build_model(experiment, vec_env, seed=0, device="cpu", tensorboard=None)
    _, callback = model._setup_learn(10**9, None)  # what learn() does before collecting
    callback.on_training_start(locals(), globals())
    model.collect_rollouts(model.env, callback, model.rollout_buffer, model.n_steps)  # warm-up
    start = time.perf_counter()
    model.collect_rollouts(model.env, callback, model.rollout_buffer, model.n_steps)
    collection = model.n_steps * vec_env.num_envs / (time.perf_counter() - start)
    steps = 2 * model.n_steps * vec_env.num_envs
    start = time.perf_counter()
    model.learn(steps, reset_num_timesteps=False)
    training = steps / (time.perf_counter() - start)
    vec_env.close()
    return collection, training


def stepping(experiment: Experiment, steps: int = 400) -> float:
    """Env steps/s of the vector env alone, fed random actions."""
    vec_env = make_vec_env(Plant(experiment), seed=0)
    vec_env.reset()
    actions = np.random.default_rng(0).uniform(-1, 1, (steps, vec_env.num_envs, 3)).astype(np.float32)
    start = time.perf_counter()
    for action in actions:
        vec_env.step(action)
    return steps * vec_env.num_envs / (time.perf_counter() - start)


def vec_env_comparison(default: Experiment) -> None:
    torch.set_num_threads(1)
    for n_envs in (1, 8, 32, 128):
        dummy, batched = (stepping(with_envs(default, n_envs, kind)) for kind in ("dummy", "batched"))
        print(
            f"n_envs {n_envs:3d}: env stepping alone {dummy:,.0f} -> {batched:,.0f} env steps/s "
            f"({batched / dummy:.1f}x)"
        )
    for n_envs in (8, 32, 128):
        dummy = collection_and_training(with_envs(default, n_envs, "dummy"))
        batched = collection_and_training(with_envs(default, n_envs, "batched"))
        print(
            f"n_envs {n_envs:3d}: collection {dummy[0]:,.0f} -> {batched[0]:,.0f} env steps/s "
            f"({batched[0] / dummy[0]:.1f}x); PPO training {dummy[1]:,.0f} -> {batched[1]:,.0f} env steps/s "
            f"({batched[1] / dummy[1]:.1f}x)  [DummyVecEnv -> batched]"
        )


def throughput(default: Experiment) -> float:
    sac = Experiment(algorithm=AlgorithmConfig(name="SAC", kwargs={"gamma": 0.999, "learning_starts": 100}))
    ppo = Experiment(algorithm=AlgorithmConfig(name="PPO", n_envs=8, kwargs={"gamma": 0.999, "n_steps": 256}))
    sac_rate = 0.0
    for threads in (1, 2):
        sac_rate = steps_per_second(sac, 2000, warmup=100, threads=threads)
        ppo_rate = steps_per_second(ppo, 16384, warmup=2048, threads=threads)
        default_rate = steps_per_second(default, 32768, warmup=4096, threads=threads)
        hours = PAPER_STEPS / sac_rate / 3600
        print(
            f"torch threads {threads}: paper SAC {sac_rate:,.0f} steps/s (1.5 M steps = {hours:.1f} h); "
            f"PPO 8 envs {ppo_rate:,.0f} steps/s; "
            f"new default {default_rate:,.0f} steps/s ({default_rate / sac_rate:.0f}x paper SAC)"
        )
    return sac_rate


def time_to_quality(name: str, experiment: Experiment, minutes: float, folder: Path) -> float | None:
    summary = train(experiment=experiment, run_dir=folder / name, time_limit_s=60.0 * minutes)
    print(f"{name}: {summary.line()}")
    return None if summary.beat_lqg_at is None else summary.beat_lqg_at["wall_time_s"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=15.0, help="wall-time budget of each training run")
    parser.add_argument("--skip-quality", action="store_true", help="measure throughput only")
    parser.add_argument("--vec-env-only", action="store_true", help="only the vector env comparison")
    arguments = parser.parse_args()
    paper = load_experiment(CONFIGS / "experiments" / "paper_sac.yaml")
    default = load_experiment(CONFIGS / "five_story.yaml")
    print(
        f"machine: {platform.node()} ({platform.machine()}, {torch.get_num_threads()} torch threads "
        "available)"
    )
    vec_env_comparison(default)
    if arguments.vec_env_only:
        return
    throughput(default)
    if arguments.skip_quality:
        return
    with tempfile.TemporaryDirectory() as folder:
        paper_time = time_to_quality("paper SAC", paper, arguments.minutes, Path(folder))
        default_time = time_to_quality("new default", default, arguments.minutes, Path(folder))
    budget = 60.0 * arguments.minutes
    shown = {
        k: "not reached" if t is None else f"{t:.0f} s"
        for k, t in (("paper", paper_time), ("default", default_time))
    }
    print(f"time to beat LQG's validation J1: paper SAC {shown['paper']}, new default {shown['default']}")
    if default_time is not None:
        reference = paper_time if paper_time is not None else budget
        relation = "=" if paper_time is not None else ">="
        print(f"time-to-quality ratio (paper / new default) {relation} {reference / default_time:.1f}")


if __name__ == "__main__":
    main()
