"""What a check suite's ground motions are made of at a building's periods: Sa / PGA (2 % damped) over its
motions, median and 16-84 %, for each standard named (and, for comparison only, a folder of records).

Usage (from the repository's root):
    python studies/safety_check/suite_family.py configs/checks/standard.yaml [OTHER_STANDARD.yaml ...] \\
        --periods 6.25 2 1.44 0.55 0.35 [--records ../shared/records]

Round 6's standard is in git: `git show 0259b7f:configs/checks/standard.yaml > /tmp/round6.yaml`. The records
are the test set: they are shown, never fitted (docs/safety_check.md, "Round 7: the check suite's family").
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from rlcontroller.config.scenarios import load_safety_check
from rlcontroller.physics.motions.excitation import Load
from rlcontroller.physics.motions.generators import generate_suite
from rlcontroller.physics.motions.records import load_records
from rlcontroller.physics.motions.spectra import spectral_shape

DAMPING = 0.02


def spread(motions: list[Load], periods: np.ndarray) -> np.ndarray:
    """Rows 16 %, median, 84 % of Sa / PGA over `motions`, one column per period."""
    shapes = np.array([spectral_shape(motion, periods, DAMPING) for motion in motions])
    return np.percentile(shapes, [16.0, 50.0, 84.0], axis=0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("standards", type=Path, nargs="+", help="safety-check standards (YAML)")
    parser.add_argument("--periods", type=float, nargs="+", required=True, help="s")
    parser.add_argument("--records", type=Path, default=None, help="a folder of records, shown beside them")
    arguments = parser.parse_args()
    periods = np.array(arguments.periods)
    print(f"Sa/PGA ({DAMPING:.0%} damped): median (16-84 %) at " + ", ".join(f"{p:g} s" for p in periods))
    suites = {
        str(path): generate_suite(load_safety_check(path).generator, 320, 31337)
        for path in arguments.standards
    }
    if arguments.records is not None:
        suites[f"{arguments.records} (the test set)"] = load_records(arguments.records)[0]
    for name, motions in suites.items():
        low, median, high = spread(motions, periods)
        cells = ", ".join(f"{m:.2f} ({lo:.2f}-{hi:.2f})" for lo, m, hi in zip(low, median, high, strict=True))
        print(f"{name}, {len(motions)} motions: {cells}")


if __name__ == "__main__":
    main()
