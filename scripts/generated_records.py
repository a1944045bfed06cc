"""Write a suite of generated motions as record files, for `rlc evaluate --records DIR`.

Usage: python scripts/generated_records.py OUT [--count 200] [--seed 20000] [--config
configs/excitations/broad.yaml]

The motions are draws of the excitation part's validation generator (default: the broad suite, PGA
0.005-1 g log-uniform on soft, medium and firm soil and noise + impulses) with a seed of their own,
so they are neither the training nor the validation motions: a test suite for generalisation across
shaking levels, as the real records cannot be (the project's seven are strong motions). Each motion
is a two-column CSV (time in s, acceleration in m/s^2); a manifest.csv lists them in order.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rlcontroller.config import ExcitationConfig, read_yaml
from rlcontroller.files import atomic_write, new_folder
from rlcontroller.physics.motions.excitation import STANDARD_GRAVITY
from rlcontroller.physics.motions.generators import generate_suite

REPOSITORY = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="a new folder")
    parser.add_argument("--count", type=int, default=200)
    parser.add_argument("--seed", type=int, default=20_000)
    parser.add_argument("--config", type=Path, default=REPOSITORY / "configs" / "excitations" / "broad.yaml")
    arguments = parser.parse_args()
    excitation = ExcitationConfig.model_validate(read_yaml(arguments.config))
    motions = generate_suite(excitation.validation, arguments.count, arguments.seed)
    with new_folder(arguments.out) as folder:
        manifest = ["file,event,pga_g"]
        for index, motion in enumerate(motions):
            name = f"generated_{index:04d}.csv"
            rows = ["time_s,acceleration [m/s2]"]
            rows += [f"{i * motion.dt:.4f},{value:.8g}" for i, value in enumerate(motion.acceleration)]
            atomic_write(folder / name, "\n".join(rows) + "\n")
            manifest.append(f"{name},{motion.name},{motion.pga / STANDARD_GRAVITY:.4f}")
        atomic_write(folder / "manifest.csv", "\n".join(manifest) + "\n")
    print(f"{len(motions)} motions in {arguments.out}")


if __name__ == "__main__":
    main()
