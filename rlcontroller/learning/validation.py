"""Validation: a policy on held-out generated motions, never the real records.

The deterministic policy runs on `excitation.validation_motions` motions of the validation generator
(`excitation.validation_generator`, else the training generator) drawn with
`excitation.validation_seed`; J1/J2 are taken against the uncontrolled building on the same motions,
and the three LQGs, designed on the design model as deployed, are run once on them as references.
`eval_worse` is the share of the motions on which the policy is worse than the building failed safe (the
safety check's measure, `metrics.ratio_to_reference`, above 1 + the standard's default tolerance): what
`select_by: standard` minimises first, among the policies whose closed loop linearised at rest is stable on
the design model and on the scenarios the standard judges (`eval_spectral_radius`, the largest, below 1: the
check's stability criterion; measured only then). With `plant_randomization`, motion i runs on the plant drawn
with seed i, the same draw for every controller and every validation.
"""

from __future__ import annotations

import numpy as np

from rlcontroller.config import SafetyCheckConfig
from rlcontroller.control.controllers import LQGController, LQGPrior, Uncontrolled, fail_safe_controller
from rlcontroller.control.lqg import design_lqg, design_lqg_ground_model
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.physics.metrics import j_metrics, peak, ratio_to_reference
from rlcontroller.physics.motions.loads import generate_suite
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.linearised import judged_plants, robust_spectral_radius
from rlcontroller.simulation.rollout import batch_rollout


class Validator:
    """Runs a policy on the held-out generated validation motions."""

    def __init__(self, plant: Plant) -> None:
        self.plant = plant
        self.judged: list[Plant] | None = None  # the standard's stability scenarios (select_by: standard)
        excitation = plant.experiment.excitation
        self.motions = generate_suite(
            excitation.validation, excitation.validation_motions, excitation.validation_seed, plant.building
        )
        self.prior = LQGPrior.design(plant) if plant.experiment.algorithm.residual_lqg else None
        bare = plant.bare  # without its mass devices
        uncontrolled = batch_rollout(
            bare, self.motions, [Uncontrolled(bare.building.n_actuators)], randomize=True
        )
        self.uncontrolled = [response for response, _ in uncontrolled[0]]
        failed_safe = batch_rollout(
            plant.failed_safe, self.motions, [fail_safe_controller(plant)], randomize=True
        )
        self.fail_safe = [response for response, _ in failed_safe[0]]
        self.reference = {}
        model = plant.design
        designs = {
            "lqg": lambda: design_lqg(model),
            "lqg_ground": lambda: design_lqg(model, known_ground=True),
            "lqg_ground_model": lambda: design_lqg_ground_model(model),
        }
        for prefix, design in designs.items():
            try:
                lqg = self.run(LQGController(design(), model))
            except ValueError:  # a reward LQG cannot be designed for
                lqg = {"eval_J1": float("nan"), "eval_J2": float("nan")}
            self.reference |= {f"{prefix}_J1": lqg["eval_J1"], f"{prefix}_J2": lqg["eval_J2"]}

    def __call__(self, policy: PolicyController) -> dict[str, float]:
        """The validation row of `policy` (a model's `policy_controller`), with the references."""
        row = self.run(policy) | self.reference
        if self.plant.experiment.algorithm.select_by == "standard":
            if self.judged is None:  # built at the first checkpoint that asks
                self.judged = judged_plants(self.plant)
            row["eval_spectral_radius"] = robust_spectral_radius(self.plant, policy, self.judged)
        return row

    def _rollouts(self, controller) -> list:
        """Motion i on the plant drawn with seed i (with randomisation), noise seeded i: in one batch."""
        return batch_rollout(self.plant, self.motions, [controller], randomize=True)[0]

    def run(self, controller) -> dict[str, float]:
        rewards, peaks, j1, j2, worse = [], [], [], [], []
        for index, (result, reward) in enumerate(self._rollouts(controller)):
            metrics = j_metrics(result, self.uncontrolled[index])
            worse.append(ratio_to_reference(result, self.fail_safe[index]) > 1.0 + WORSE_TOLERANCE)
            rewards.append(reward)
            peaks.append(float(np.max(peak(result.drift))))
            j1.append(float(np.mean(metrics["J1"])))
            j2.append(float(np.mean(metrics["J2"])))
        return {
            "eval_reward": float(np.mean(rewards)),
            "eval_peak_drift_m": float(np.mean(peaks)),
            "eval_J1": float(np.mean(j1)),
            "eval_J2": float(np.mean(j2)),
            "eval_worse": float(np.mean(worse)),
        }


WORSE_TOLERANCE = SafetyCheckConfig.model_fields[
    "tolerance"
].default  # the standard's, configs/checks/standard.yaml
