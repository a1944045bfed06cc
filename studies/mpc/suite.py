"""What the MPC studies measure on a suite of motions: mean J1, mean J2 and the strokes against their
limits."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rlcontroller.control.controllers import Uncontrolled
from rlcontroller.physics.metrics import j_metrics
from rlcontroller.physics.motions.excitation import Load
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.rollout import batch_rollout


@dataclass
class Suite:
    """Motions on a plant with the uncontrolled building's responses to them (motion i on plant draw i, noise
    seeded i, as `learning.validation.Validator`)."""

    plant: Plant
    motions: list[Load]

    def __post_init__(self) -> None:
        bare = self.plant.bare
        runs = batch_rollout(bare, self.motions, [Uncontrolled(bare.building.n_actuators)], randomize=True)
        self.uncontrolled = [response for response, _ in runs[0]]

    def judge(self, controller) -> dict[str, float]:
        """Mean J1 and J2; with stroke-limited mass devices the largest and the mean (over motions) peak
        stroke / limit, and the motions whose peak stroke exceeds its limit by more than 1 %."""
        runs = batch_rollout(self.plant, self.motions, [controller], randomize=True)[0]
        metrics = [j_metrics(result, bare) for (result, _), bare in zip(runs, self.uncontrolled, strict=True)]
        row = {
            "J1": float(np.mean([np.mean(m["J1"]) for m in metrics])),
            "J2": float(np.mean([np.mean(m["J2"]) for m in metrics])),
        }
        limits = [device.stroke_limit for device in getattr(self.plant.building, "devices", ())]
        if limits and all(limit is not None for limit in limits):
            peaks = np.array([np.max(np.abs(result.stroke) / np.array(limits)) for result, _ in runs])
            row |= {"stroke_max": float(peaks.max()), "stroke_mean": float(peaks.mean())}
            row["over_limit"] = int(np.sum(peaks > 1.01))
        return row
