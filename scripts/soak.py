"""Soak test: a sweep whose workers are killed at random, against the same sweep left alone.

Usage: python scripts/soak.py OUT [--runs 12] [--steps 40000] [--checkpoint-every 8192] [--workers 2]
                              [--engine local|dask] [--kill-every 60 180] [--seed 0]
                              [--learner ppo|random_search]

1. A quiet sweep of `--runs` seeds of a small run (configs/testing/tiny.yaml with `--steps`
   training steps and a checkpoint every `--checkpoint-every`; its PPO, or with `--learner
   random_search` the model-free random search, whose resume is exact) into OUT/quiet.
2. The same sweep into OUT/soak while, every `--kill-every` LOW HIGH seconds (uniform; the first after
   training is first seen running), a kill falls due: the next moment a run is training, the process training
   a random one (the pid in its run folder's lock) gets SIGKILL — one run at most WORKER_LOSSES // 2 times, so
   that the soak tests resuming, not the sweep's limit of losses per run.
3. The verdict: every run of the soak finished and evaluated, how many kills and resumes, the wall
   times, and whether each run's evaluation metrics and the aggregate equal the quiet sweep's.
Written to OUT/soak.md and printed.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import signal
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import yaml

from rlcontroller.multirun.sweep import WORKER_LOSSES

REPOSITORY = Path(__file__).resolve().parents[1]


def sweep_command(config: Path, runs: int, workers: int, engine: str, out: Path) -> list[str]:
    return [
        *(sys.executable, "-m", "rlcontroller", "sweep", str(config)),
        *("--seeds", f"0-{runs - 1}", "--workers", str(workers), "--engine", engine, "--out", str(out)),
    ]


def training_pids(out: Path) -> dict[str, int]:
    """The process holding each run folder's lock under `out` (the ones training now), by run."""
    pids = {}
    for lock in out.glob("seed*/.lock"):
        try:
            pids[lock.parent.name] = int(json.loads(lock.read_text())["pid"])
        except (OSError, ValueError, KeyError):
            continue
    return pids


def same_file(first: Path, second: Path) -> bool:
    return first.is_file() and second.is_file() and first.read_bytes() == second.read_bytes()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="a new folder")
    parser.add_argument("--runs", type=int, default=12)
    parser.add_argument("--steps", type=int, default=40_000)
    parser.add_argument("--checkpoint-every", type=int, default=8192)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--engine", choices=("local", "dask"), default="local")
    parser.add_argument("--kill-every", type=float, nargs=2, default=(60.0, 180.0), metavar=("LOW", "HIGH"))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--learner", choices=("ppo", "random_search"), default="ppo")
    arguments = parser.parse_args()
    out: Path = arguments.out
    out.mkdir(parents=True)
    config = yaml.safe_load((REPOSITORY / "configs" / "testing" / "tiny.yaml").read_text())
    if arguments.learner == "random_search":
        config["algorithm"] = yaml.safe_load(
            (REPOSITORY / "configs" / "algorithms" / "random_search.yaml").read_text()
        )
    every = arguments.checkpoint_every
    config["algorithm"].update(
        total_steps=arguments.steps, checkpoint_every=every, eval_every=max(every, 4096)
    )
    (out / "soak.yaml").write_text(yaml.safe_dump(config))
    chooser = random.Random(arguments.seed)

    start = time.perf_counter()
    quiet = subprocess.run(
        sweep_command(out / "soak.yaml", arguments.runs, arguments.workers, arguments.engine, out / "quiet"),
        capture_output=True,
        text=True,
    )
    quiet_seconds = time.perf_counter() - start
    if quiet.returncode != 0:
        sys.exit(f"the quiet sweep failed: {quiet.stderr.strip().splitlines()[-1:]}")

    start = time.perf_counter()
    command = sweep_command(
        out / "soak.yaml", arguments.runs, arguments.workers, arguments.engine, out / "soak"
    )
    soak = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    kills = []
    # the first kill falls LOW-HIGH s after training is first seen running (not after start-up)
    next_kill = None
    killed_runs: Counter[str] = Counter()
    while soak.poll() is None:
        time.sleep(0.2)
        pids = {
            run: pid
            for run, pid in training_pids(out / "soak").items()
            if killed_runs[run] < WORKER_LOSSES // 2
        }
        if next_kill is None and pids:
            next_kill = time.perf_counter() + chooser.uniform(*arguments.kill_every)
        if next_kill is None or time.perf_counter() < next_kill or not pids:
            continue
        run = chooser.choice(sorted(pids))
        try:
            os.kill(pids[run], signal.SIGKILL)
            kills.append((round(time.perf_counter() - start, 1), pids[run]))
            killed_runs[run] += 1
        except ProcessLookupError:
            pass
        next_kill = time.perf_counter() + chooser.uniform(*arguments.kill_every)
    output = soak.communicate()[0]
    soak_seconds = time.perf_counter() - start

    rows = (
        (out / "soak" / "sweep.csv").read_text().splitlines()[1:]
        if (out / "soak" / "sweep.csv").is_file()
        else []
    )
    statuses = [row.split(",")[3] for row in rows]
    finished = all(
        (out / "soak" / f"seed{s}" / "evaluation" / "metrics.csv").is_file() for s in range(arguments.runs)
    )
    same_runs = [
        same_file(
            out / "quiet" / f"seed{s}" / "evaluation" / "metrics.csv",
            out / "soak" / f"seed{s}" / "evaluation" / "metrics.csv",
        )
        for s in range(arguments.runs)
    ]
    same_aggregate = same_file(out / "quiet" / "aggregate.csv", out / "soak" / "aggregate.csv")
    lines = [
        f"# Soak: {arguments.runs} runs of {arguments.steps:,} {config['algorithm']['name']} steps, "
        f"{arguments.workers} {arguments.engine} workers",
        "",
        f"- quiet sweep: {quiet_seconds:.0f} s",
        f"- soak: {soak_seconds:.0f} s, exit code {soak.returncode}, {len(kills)} workers killed "
        f"(at s: {', '.join(f'{t:g}' for t, _ in kills)})",
        f"- run statuses: {', '.join(f'{statuses.count(s)} {s}' for s in sorted(set(statuses)))}",
        f"- every run finished and evaluated: {'yes' if finished and len(rows) == arguments.runs else 'NO'}",
        f"- evaluation metrics equal to the quiet sweep's: {sum(same_runs)} of {arguments.runs} runs",
        f"- aggregate equal to the quiet sweep's: {'yes' if same_aggregate else 'NO'}",
        "",
        "```",
        *output.strip().splitlines()[-5:],
        "```",
    ]
    (out / "soak.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
