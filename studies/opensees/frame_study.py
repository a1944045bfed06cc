"""The nine-story frame (docs/opensees.md, example b): how far its FE model departs from the reduced model the
controllers are designed on. Prints, on the seven records, the LQG variants' J1 and J2 with the reduced
model as the plant (to set beside `rlc compare lqg --config configs/experiments/nine_story_frame.yaml`, the
FE model as the plant) and, per record, the uncontrolled peak drift ratio (% of the story height) of the FE
model and of the reduced model.

Usage: python studies/opensees/frame_study.py RECORDS    (≈ 5 min on 2 cores: the FE runs)
"""

import sys
from pathlib import Path

import numpy as np

from rlcontroller.assets import CONFIGS
from rlcontroller.config import load_experiment
from rlcontroller.evaluation.evaluation import compare, uncontrolled_responses
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.records import load_records

experiment = load_experiment(CONFIGS / "experiments" / "nine_story_frame.yaml")
fe = Plant(experiment)
records = load_records(Path(sys.argv[1]))[0]
summary = compare(fe.design, records, "seven records", None).summary()
print("reduced model as the plant:")
print(summary[["J1", "J2"]].round(3).to_string())
heights = np.asarray(experiment.building.story_heights)
fe_runs, linear_runs = uncontrolled_responses(fe, records), uncontrolled_responses(fe.design, records)
print("uncontrolled peak drift ratio, % of the story height (FE model / reduced model):")
for motion, fe_run, linear_run in zip(records, fe_runs, linear_runs, strict=True):
    peak_fe = np.max(np.abs(fe_run.drift) / heights) * 100
    peak_linear = np.max(np.abs(linear_run.drift) / heights) * 100
    pga = np.max(np.abs(motion.acceleration)) / 9.80665
    print(f"  {motion.name} ({pga:.2f} g): {peak_fe:.2f} / {peak_linear:.2f}")
