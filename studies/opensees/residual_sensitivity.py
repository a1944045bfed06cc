"""How far the FE frame's own residual drift moves under changes too small to matter elsewhere.

Usage: python studies/opensees/residual_sensitivity.py [--motions 8]

`rlc reduce` judges the reduced model's residual drift by the median relative error per story over the motions
not fitted (`identification.hysteretic.accuracy`, the same motions: seed TEST_SEED). This study applies that
very measure to the FE model against itself, changed in ways a modeller would call the same frame:
- the analysis step halved (5 ms against the experiment's 10 ms): the numerics alone;
- the beams' yield strength 2 % higher (253 against 248 MPa; A36 steel's expected yield is 1.5 times its
  nominal one, FEMA 356 Table 5-3): a material far inside its own scatter.
If the FE frame's residual moves by 25 % or more in a story under these, no reduced model can be held to 25 %
there against one run of it. Peak drift errors are printed beside, by the same measure. The FE runs are kept
(`simulation.kept`): a second run of the study computes nothing again. About 15 min on 2 cores the first time.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from rlcontroller.api.common import load
from rlcontroller.identification.hysteretic import TEST_SEED, calibration_motions, fe_responses, residual
from rlcontroller.physics.metrics import peak
from rlcontroller.physics.plant import Plant

REPOSITORY = Path(__file__).resolve().parents[2]
CONFIG = REPOSITORY / "configs/experiments/nine_story_frame.yaml"
YIELD_LINE = "FY_COLUMN, FY_BEAM = 345.0e6, 248.0e6"


def frame(analysis_dt: float | None = None, model: Path | None = None) -> Plant:
    """The nine-story frame's plant, with another analysis step (s) or model file."""
    experiment = load(CONFIG)
    fe = experiment.plant.opensees
    fe = fe.model_copy(update={"analysis_dt": analysis_dt or fe.analysis_dt, "model": str(model or fe.model)})
    return Plant(
        experiment.model_copy(update={"plant": experiment.plant.model_copy(update={"opensees": fe})})
    )


def stronger_beams(folder: Path, factor: float) -> Path:
    """A copy of the frame's model file in `folder` with the beams' yield strength times `factor`."""
    source = (REPOSITORY / "configs/opensees/nine_story_frame.py").read_text()
    if YIELD_LINE not in source:
        raise SystemExit(f"configs/opensees/nine_story_frame.py: expected the line {YIELD_LINE!r}")
    path = folder / "nine_story_frame.py"
    path.write_text(source.replace(YIELD_LINE, f"FY_COLUMN, FY_BEAM = 345.0e6, {248.0e6 * factor!r}"))
    return path


def errors(variant: list[np.ndarray], base: list[np.ndarray], dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Per story, the median relative errors of peak and residual drift of `variant` against `base` (the
    measure `accuracy` applies to the reduced model)."""
    peaks, residuals = [], []
    for drift, target in zip(variant, base, strict=True):
        fe_peak, fe_residual = peak(target), np.abs(residual(target, dt))
        peaks.append(np.abs(peak(drift) - fe_peak) / fe_peak)
        residuals.append(
            np.abs(np.abs(residual(drift, dt)) - fe_residual) / np.maximum(fe_residual, 0.01 * fe_peak)
        )
    return np.median(peaks, axis=0), np.median(residuals, axis=0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--motions", type=int, default=8)
    args = parser.parse_args()
    motions = calibration_motions(args.motions, TEST_SEED)
    base_plant = frame()
    dt = base_plant.control_dt
    base = [response.drift for response in fe_responses(base_plant, motions)]
    with tempfile.TemporaryDirectory() as scratch:
        variants = {
            "analysis step 5 ms": frame(analysis_dt=0.005),
            "beams' yield strength x 1.02": frame(model=stronger_beams(Path(scratch), 1.02)),
        }
        print(
            f"The FE frame against itself on {args.motions} motions of seed {TEST_SEED} (rlc reduce's test "
            "motions)"
        )
        print("median relative error per story, stories 1 -> 9")
        for name, plant in variants.items():
            drifts = [response.drift for response in fe_responses(plant, motions)]
            peak_error, residual_error = errors(drifts, base, dt)
            print(f"{name}: peak drift {np.round(100 * peak_error, 1).tolist()} %")
            print(
                f"{name}: residual drift {np.round(100 * residual_error, 1).tolist()} %, "
                f"{int(np.sum(residual_error < 0.25))} of 9 within 25 %"
            )


if __name__ == "__main__":
    main()
