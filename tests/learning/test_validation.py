"""Validation references are the controllers as deployed: designed on the design model."""

import numpy as np
from conftest import REPOSITORY

from rlcontroller.config import PlantConfig, load_experiment
from rlcontroller.control.controllers import LQGController, fail_safe_controller
from rlcontroller.control.lqg import design_lqg
from rlcontroller.learning.training import selection_score
from rlcontroller.learning.validation import Validator
from rlcontroller.physics.plant import Plant


def test_the_lqg_references_are_designed_on_the_design_model_and_run_on_the_plant():
    experiment = load_experiment(REPOSITORY / "configs" / "testing" / "smoke.yaml")
    softer = Plant(experiment.model_copy(update={"plant": PlantConfig(stiffness=0.7)}))
    validator = Validator(softer)
    nominal = validator.run(LQGController(design_lqg(softer.design), softer.design))
    oracle = validator.run(LQGController(design_lqg(softer), softer))
    assert validator.reference["lqg_J1"] == nominal["eval_J1"]
    assert abs(oracle["eval_J1"] - nominal["eval_J1"]) > 1e-3  # the two designs differ on this plant


def test_the_ground_model_reference_exists_with_actuator_delays_on_the_plant():
    experiment = load_experiment(REPOSITORY / "configs" / "testing" / "smoke.yaml")
    delayed = Plant(experiment.model_copy(update={"plant": PlantConfig(actuators={"delay_steps": 1})}))
    reference, nominal = Validator(delayed).reference, Validator(Plant(experiment)).reference
    assert set(reference) == set(nominal) and all(np.isfinite(value) for value in reference.values())
    # every design exists, acts (J1 < 1) and is simulated with the delay: a delayed plant is harder to control
    for design in ("lqg", "lqg_ground", "lqg_ground_model"):
        assert nominal[f"{design}_J1"] < reference[f"{design}_J1"] < 1.0


def test_eval_worse_counts_the_motions_made_worse_than_failing_safe_and_standard_selection_puts_it_first():
    plant = Plant(load_experiment(REPOSITORY / "configs" / "testing" / "smoke.yaml"))
    validator = Validator(plant)
    lqg = LQGController(design_lqg(plant.design), plant.design)

    class Reversed:
        name = "reversed LQG"

        def reset(self):
            lqg.reset()

        def act(self, observation):
            return -lqg.act(observation)

    failed_safe, helping, harming = (validator.run(c) for c in (fail_safe_controller(plant), lqg, Reversed()))
    assert failed_safe["eval_worse"] == 0.0 and helping["eval_worse"] == 0.0 < helping["eval_J1"] < 1.0
    assert harming["eval_worse"] > 0.5
    assert selection_score(failed_safe, "standard") > selection_score(harming, "standard")
    assert selection_score(helping, "standard") > selection_score(failed_safe, "standard")
