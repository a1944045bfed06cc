"""Benchmark: environment steps per second while training, SAC (paper settings) and PPO (8 envs).

Usage: python scripts/bench_train.py [--sac-steps N] [--ppo-steps N]
Measures model.learn() wall time after the replay buffer's warm-up (SAC) on the paper's
five-story env, with torch threads 1 and 2, and projects the paper's 1.5 M SAC steps.
"""

from __future__ import annotations

import argparse
import platform
import time

import torch

from rlcontroller.config import AlgorithmConfig, Experiment
from rlcontroller.training import build_model, make_vec_env

PAPER_STEPS = 1_500_000


def steps_per_second(algorithm: AlgorithmConfig, steps: int, warmup: int, threads: int) -> float:
    torch.set_num_threads(threads)
    experiment = Experiment(algorithm=algorithm)
    vec_env = make_vec_env(experiment, seed=0)
    model = build_model(experiment, vec_env, seed=0, device="cpu", tensorboard=None)
    model.learn(warmup)
    start = time.perf_counter()
    model.learn(steps, reset_num_timesteps=False)
    rate = (model.num_timesteps - warmup) / (time.perf_counter() - start)
    vec_env.close()
    return rate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sac-steps", type=int, default=2000)
    parser.add_argument("--ppo-steps", type=int, default=16384)
    arguments = parser.parse_args()
    sac = AlgorithmConfig(name="SAC", kwargs={"gamma": 0.999, "learning_starts": 100})
    ppo = AlgorithmConfig(name="PPO", n_envs=8, kwargs={"gamma": 0.999, "n_steps": 256})
    print(f"machine: {platform.node()} ({platform.machine()}, {torch.get_num_threads()} torch threads available)")
    for threads in (1, 2):
        sac_rate = steps_per_second(sac, arguments.sac_steps, warmup=100, threads=threads)
        ppo_rate = steps_per_second(ppo, arguments.ppo_steps, warmup=2048, threads=threads)
        hours = PAPER_STEPS / sac_rate / 3600
        print(
            f"torch threads {threads}: SAC 3x128 batch 256 {sac_rate:,.0f} steps/s "
            f"(1.5 M steps = {hours:.1f} h); PPO 8 envs {ppo_rate:,.0f} steps/s ({ppo_rate / sac_rate:.0f}x SAC)"
        )


if __name__ == "__main__":
    main()
