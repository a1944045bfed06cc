"""The nine-story frame (docs/opensees.md, example b): how far its FE model departs from the reduced model the
controllers are designed on. Prints, on the seven records, the LQG variants' J1 and J2 with the reduced
model as the plant (to set beside `rlc compare lqg --config configs/experiments/nine_story_frame.yaml`, the
FE model as the plant) and, per record, the uncontrolled peak drift ratio (% of the story height) of the FE
model and of the reduced model, and the residual drift ratio of the FE model (uncontrolled and under LQG +
ground model) after a settling tail of zero ground motion (`excitation.with_settling_tail`).

Usage: python studies/opensees/frame_study.py RECORDS    (≈ 15 min on 2 cores: the FE runs)
"""

import sys
from pathlib import Path

import numpy as np

from rlcontroller import api
from rlcontroller.assets import CONFIGS
from rlcontroller.control.controllers import LQGController, Uncontrolled
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.evaluation.evaluation import compare
from rlcontroller.physics.motions.excitation import SETTLING_TAIL_S, with_settling_tail
from rlcontroller.physics.motions.records import load_records
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.rollout import batch_rollout, uncontrolled_responses

experiment = api.load(CONFIGS / "experiments" / "nine_story_frame.yaml")
fe = Plant(experiment)
records = load_records(Path(sys.argv[1]))[0]
summary = compare(fe.design, records, "seven records", policy=None).summary()
print("reduced model as the plant:")
print(summary[["J1", "J2"]].round(3).to_string())
heights = np.asarray(experiment.building.story_heights)
linear_runs = uncontrolled_responses(fe.design, records)
tailed = [with_settling_tail(motion) for motion in records]
lqg = LQGController(design_lqg_ground_model(fe.design), fe.design, "LQG + ground model")
uncontrolled, controlled = batch_rollout(fe, tailed, [Uncontrolled(fe.building.n_actuators), lqg])
print("peak drift ratio FE / reduced model, uncontrolled; residual drift ratio of the FE model after")
print(f"{SETTLING_TAIL_S:g} s at rest, uncontrolled / LQG + ground model (all % of the story height):")
for motion, (fe_run, _), (lqg_run, _), linear_run in zip(
    records, uncontrolled, controlled, linear_runs, strict=True
):
    peak_fe = np.max(np.abs(fe_run.drift) / heights) * 100
    peak_linear = np.max(np.abs(linear_run.drift) / heights) * 100
    residual = [np.max(np.abs(run.drift[-1]) / heights) * 100 for run in (fe_run, lqg_run)]
    pga = np.max(np.abs(motion.acceleration)) / 9.80665
    peaks = f"{peak_fe:.2f} / {peak_linear:.2f}"
    print(f"  {motion.name} ({pga:.2f} g): {peaks}; residual {residual[0]:.3f} / {residual[1]:.3f}")
