"""Benchmark: what an engine costs per run of `rlc sweep`, local processes against a local Dask cluster.

Usage: python scripts/bench_sweep.py [--runs 8] [--workers 2]

The same sweep of tiny runs (configs/testing/tiny.yaml: PPO, 256 steps; evaluated on the
synthetic suite) on each engine, in a new folder each time. The overhead per run is the worker time
not spent inside runs, (wall time x workers - sum of the runs' own times) / runs: engine start-up,
fresh worker processes importing torch and stable-baselines3, scheduling, and the final aggregate.
"""

from __future__ import annotations

import argparse
import platform
import tempfile
import time
from pathlib import Path

from rlcontroller.config import load_experiment
from rlcontroller.multirun.sweep import sweep

TINY = Path(__file__).resolve().parents[1] / "configs" / "testing" / "tiny.yaml"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=8)
    parser.add_argument("--workers", type=int, default=2)
    arguments = parser.parse_args()
    print(f"machine: {platform.node()} ({platform.machine()})")
    experiment = load_experiment(TINY)
    for engine in ("local", "dask"):
        with tempfile.TemporaryDirectory() as folder:
            start = time.perf_counter()
            results, _ = sweep(
                experiment,
                list(range(arguments.runs)),
                [],
                Path(folder),
                engine=engine,
                workers=arguments.workers,
                echo=lambda _: None,
            )
            wall = time.perf_counter() - start
        inside = sum(result.seconds for result in results)
        overhead = (wall * arguments.workers - inside) / len(results)
        print(
            f"{engine:5s}: {len(results)} runs on {arguments.workers} workers in {wall:.1f} s, "
            f"runs themselves {inside / len(results):.1f} s each, engine overhead {overhead:.1f} s per run"
        )


if __name__ == "__main__":
    main()
