"""Benchmark: an FE plant's control steps/s and peak story drifts under other solver settings, each in its own
process.

Usage: python scripts/bench_fe_solvers.py EXPERIMENT [--records DIR] [--record KOBE] [--seconds 12]

EXPERIMENT names an FE plant (plant.opensees) whose model is a Tcl file with its description beside it (e.g.
studies/opensees/benchmark_9st/benchmark_9st.yaml, once its files are fetched: its README). Each option set
below copies the model's folder to a scratch folder, changes the description (algorithm, system, test) or the
experiment's analysis step, and runs the first --seconds of the record uncontrolled, in a fresh process (one
OpenSees domain per process): control steps/s of the FE model alone, and the largest difference of a story's
peak drift from the first set's. docs/opensees.md, "Speed", has a run.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import yaml

OPTION_SETS = {  # name: (changes to the model's description, analysis step in s or None for the experiment's)
    "as described": ({}, None),
    "BandGeneral": ({"system": ["BandGeneral"]}, None),
    "test 1e-8 m": ({"test": ["NormDispIncr", 1e-8, 30]}, None),
    "ModifiedNewton -initial": ({"algorithm": ["ModifiedNewton", "-initial"]}, None),
    "KrylovNewton": ({"algorithm": ["KrylovNewton"]}, None),
    "steps of 10 ms": ({}, 0.01),
    "KrylovNewton, 10 ms": ({"algorithm": ["KrylovNewton"]}, 0.01),
    "KrylovNewton, 20 ms": ({"algorithm": ["KrylovNewton"]}, 0.02),
}


def one_set(experiment: Path, records: Path, record: str, seconds: float) -> dict:
    """In this process: the FE model stepped uncontrolled on the record's first `seconds`."""
    from numpy.lib.stride_tricks import sliding_window_view

    from rlcontroller import api
    from rlcontroller.physics.motions.excitation import on_control_grid
    from rlcontroller.physics.motions.loads import load_suite
    from rlcontroller.physics.plant import Plant

    plant = Plant(api.load(experiment))
    motions, _ = load_suite(records, None, plant, lambda *_: None)
    motion = next(m for m in motions if record.lower() in m.name.lower())
    motion = replace(motion, acceleration=motion.acceleration[: int(seconds / motion.dt)])
    grid = on_control_grid(motion, plant.control_dt)
    windows = sliding_window_view(grid.ground, grid.substeps + 1)[:: grid.substeps]
    state, action = np.zeros(plant.n_state), np.zeros(plant.building.n_actuators)
    floors, start = [], time.perf_counter()
    for window in windows:
        state = plant.integrator.step(state, action, window, plant.control_dt)
        floors.append(state[: plant.building.n_floors].copy())
    rate = len(windows) / (time.perf_counter() - start)
    floors = np.array(floors)
    drift = np.diff(np.hstack([np.zeros((len(floors), 1)), floors]), axis=1)
    return {"rate": rate, "peaks": np.abs(drift).max(axis=0).tolist()}


def scratch_experiment(experiment: Path, folder: Path, changes: dict, analysis_dt: float | None) -> Path:
    """A copy of the experiment and its model's folder in `folder`, the description and step changed."""
    raw = yaml.safe_load(experiment.read_text())
    model = (experiment.parent / raw["plant"]["opensees"]["model"]).resolve()
    shutil.copytree(model.parent, folder / "model")
    sidecar = folder / "model" / model.with_suffix(".yaml").name
    sidecar.write_text(yaml.safe_dump(yaml.safe_load(sidecar.read_text()) | changes))
    raw["plant"]["opensees"]["model"] = str(folder / "model" / model.name)
    if analysis_dt is not None:
        raw["plant"]["opensees"]["analysis_dt"] = analysis_dt
    for key, value in raw.items():  # the experiment's parts by absolute path
        if isinstance(value, str) and value.endswith(".yaml"):
            raw[key] = str((experiment.parent / value).resolve())
    path = folder / experiment.name
    path.write_text(yaml.safe_dump(raw))
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("experiment", type=Path)
    parser.add_argument("--records", type=Path, default=Path("../shared/records"))
    parser.add_argument("--record", default="KOBE", help="part of the record's name")
    parser.add_argument("--seconds", type=float, default=12.0)
    parser.add_argument("--one", help=argparse.SUPPRESS)  # internal: run one scratch experiment here
    arguments = parser.parse_args()
    if arguments.one:
        print(
            json.dumps(one_set(Path(arguments.one), arguments.records, arguments.record, arguments.seconds))
        )
        return
    reference = None
    for name, (changes, analysis_dt) in OPTION_SETS.items():
        with tempfile.TemporaryDirectory() as folder:
            path = scratch_experiment(arguments.experiment.resolve(), Path(folder), changes, analysis_dt)
            command = [
                sys.executable,
                __file__,
                str(arguments.experiment),
                "--one",
                str(path),
                "--records",
                str(arguments.records.resolve()),
                "--record",
                arguments.record,
                "--seconds",
                str(arguments.seconds),
            ]
            done = subprocess.run(command, capture_output=True, text=True)
        if done.returncode != 0:
            print(f"{name}: failed ({(done.stderr.strip().splitlines() or ['?'])[-1]})")
            continue
        result = json.loads(done.stdout.strip().splitlines()[-1])
        reference = reference or result["peaks"]
        difference = max(abs(a - b) / b for a, b in zip(result["peaks"], reference, strict=True))
        print(
            f"{name}: {result['rate']:.0f} control steps/s, largest peak-drift difference "
            f"{100 * difference:.2f} %"
        )


if __name__ == "__main__":
    main()
