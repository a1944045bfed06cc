"""Benchmark: the wall time of whole `rlc` processes, as a user waits for them.

Usage: python scripts/bench_startup.py [--records ../shared/records] [--repeats 5] [--demo]

Times, each as a fresh process (the median and the range over --repeats runs): `rlc --help`, and
`rlc evaluate` of the records with the default controller into a new temporary folder; with --demo,
`rlc demo` once (it trains). Prints the machine's CPU count beside the figures: they depend on it.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPOSITORY = Path(__file__).resolve().parents[1]
RLC = [sys.executable, "-m", "rlcontroller"]


def wall_times(arguments: list[str], repeats: int, folder: Path) -> list[float]:
    """Seconds per run of `rlc ARGUMENTS` ({out} in an argument: a new folder each run)."""
    times = []
    for run in range(repeats):
        out = folder / f"out{run}"
        command = RLC + [argument.replace("{out}", str(out)) for argument in arguments]
        start = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True, cwd=folder)
        times.append(time.perf_counter() - start)
        shutil.rmtree(out, ignore_errors=True)
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=Path, default=REPOSITORY.parent / "shared" / "records")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--demo", action="store_true", help="also time rlc demo once (≈ 30 s)")
    arguments = parser.parse_args()
    cases = {
        "rlc --help": ["--help"],
        f"rlc evaluate --records {arguments.records}": [
            "evaluate",
            "--records",
            str(arguments.records.resolve()),
            "--out",
            "{out}",
        ],
    }
    print(f"{os.cpu_count()} CPUs; median (min-max) wall time over {arguments.repeats} fresh processes")
    with tempfile.TemporaryDirectory() as folder:
        for name, case in cases.items():
            times = wall_times(case, arguments.repeats, Path(folder))
            print(f"{name}: {statistics.median(times):.2f} s ({min(times):.2f}-{max(times):.2f})")
        if arguments.demo:
            times = wall_times(["demo", "--no-progress"], 1, Path(folder))
            print(f"rlc demo: {times[0]:.1f} s")


if __name__ == "__main__":
    main()
