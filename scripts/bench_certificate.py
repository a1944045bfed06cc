"""Benchmark: the certificate's solve time (`rlc certify`) for every shipped controller, per plant.

Usage: python scripts/bench_certificate.py [NAME ...]
Certifies a copy of each shipped model (models/NAME) in a temporary folder, on its design model and on each
linear scenario plant of the standard, and prints per model: the closed loop's size (states, units), the
design model's X and its solve time, the plants certified, and the whole command's wall time (including the
boundary simulations). Reports seconds on this machine; compare runs on one machine only.
"""

from __future__ import annotations

import argparse
import platform
import shutil
import tempfile
import time
from pathlib import Path

import yaml

from rlcontroller.api.certify import certify
from rlcontroller.api.common import shipped_folders


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", help="only these models (default: every shipped one)")
    names = parser.parse_args().names
    folders = [folder for folder in shipped_folders() if not names or folder.name in names]
    print(f"{platform.node()} ({platform.processor() or platform.machine()}), {time.strftime('%Y-%m-%d')}")
    print("| model | design X (mm) | design solve (s) | plants certified | wall (s) |")
    print("|---|---|---|---|---|")
    for folder in folders:
        with tempfile.TemporaryDirectory() as scratch:
            copy = Path(scratch) / folder.name
            shutil.copytree(folder, copy)
            started = time.perf_counter()
            data = yaml.safe_load(certify(copy).read_text(encoding="utf-8"))
            wall = time.perf_counter() - started
        plants = data["plants"]
        if not plants:
            print(f"| {folder.name} | none ({data['reason']}) | - | 0 of 0 | {wall:.1f} |")
            continue
        nominal = plants[0]
        x = f"{nominal['drift_mm']:.3g}" if nominal.get("certified") else "none"
        certified = sum(bool(plant.get("certified")) for plant in plants)
        print(
            f"| {folder.name} | {x} | {nominal.get('solve_seconds', 0.0):.1f} | {certified} of {len(plants)} "
            f"| {wall:.1f} |"
        )


if __name__ == "__main__":
    main()
