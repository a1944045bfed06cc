"""How predictable is a record's ground acceleration a few control steps ahead?

For each record (at the 0.02 s control step) a linear AR predictor on the last 20 samples is fitted
by least squares *on that same record* and scored by R^2 = 1 - var(error) / var(signal) for horizons
of 1, 2, 5 and 10 steps. Fitting on the record being predicted is optimistic: it bounds what any
linear predictor learnt from other motions can do.

Usage: python studies/benchmark/ground_predictability.py [RECORDS_DIR]   (default ../shared/records)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from rlcontroller.config import SimulationConfig
from rlcontroller.physics.motions.excitation import on_control_grid
from rlcontroller.physics.motions.records import load_records

HISTORY = 20
HORIZONS = (1, 2, 5, 10)


def prediction_r2(ground: np.ndarray, horizon: int, history: int = HISTORY) -> float:
    """R^2 of the least-squares AR(history) prediction of ground[k + horizon - 1] from ground[k -
    history:k]."""
    count = ground.size - history - horizon + 1
    past = np.stack([ground[lag : lag + count] for lag in range(history)], axis=1)
    future = ground[history + horizon - 1 :]
    coefficients, *_ = np.linalg.lstsq(past, future, rcond=None)
    return float(1.0 - np.var(future - past @ coefficients) / np.var(future))


def main(folder: Path) -> None:
    control_dt = SimulationConfig().control_dt
    print(f"AR({HISTORY}) prediction R^2 at control step {control_dt} s, fitted on each record itself\n")
    print("| record | " + " | ".join(f"{h * control_dt:.2f} s ahead" for h in HORIZONS) + " |")
    print("|---|" + "---|" * len(HORIZONS))
    scores = []
    for motion in load_records(folder)[0]:
        grid = on_control_grid(motion, control_dt)
        samples, substeps = grid.ground, grid.substeps
        scores.append([prediction_r2(samples[::substeps], horizon) for horizon in HORIZONS])
        print(f"| {motion.name} | " + " | ".join(f"{s:.2f}" for s in scores[-1]) + " |")
    print("| mean | " + " | ".join(f"{s:.2f}" for s in np.mean(scores, axis=0)) + " |")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "../shared/records"))
