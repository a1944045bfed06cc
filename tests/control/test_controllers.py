"""Controllers speak action units (force / force limit, in [-1, 1]) and read the observation the
agent reads."""

import numpy as np
import pytest

from rlcontroller.config import Experiment, PlantConfig
from rlcontroller.control.controllers import (
    LinearFeedback,
    LQGController,
    LQGPrior,
    Uncontrolled,
    residual_action,
)
from rlcontroller.control.lqg import design_lqg, design_lqg_ground_model
from rlcontroller.learning.env import BuildingEnv
from rlcontroller.physics.motions.records import synthetic_suite
from rlcontroller.physics.plant import Plant


def test_uncontrolled_is_zero_for_every_actuator():
    action = Uncontrolled(3).act(np.ones(33))
    assert action.shape == (3,) and not action.any()


def test_linear_feedback_is_clipped_w_o_for_one_building_or_a_batch():
    weights = np.array([[2.0, 0.0], [0.5, -1.0], [0.0, 0.1]])
    controller = LinearFeedback(weights)
    np.testing.assert_allclose(controller.act(np.array([1.0, 3.0])), [1.0, -1.0, 0.3])
    batch = np.array([[0.1, 0.2], [-0.1, -0.2]])
    np.testing.assert_allclose(controller.act(batch), [[0.2, -0.15, 0.02], [-0.2, 0.15, -0.02]])


def test_lqg_controller_acts_in_action_units_and_the_env_applies_newtons_once():
    plant = Plant(Experiment())
    design = design_lqg(plant, known_ground=True)
    controller = LQGController(design, plant)
    env = BuildingEnv(plant)
    observation, _ = env.reset(seed=3, options={"motion": synthetic_suite(count=1)[0]})
    for _ in range(200):
        action = controller.act(observation)
        ground = float(observation[plant.layout.ground]) * plant.layout.ground_scale
        expected = np.clip(-design.feedback @ controller.estimate - design.feedforward * ground, -1.0, 1.0)
        np.testing.assert_allclose(action, expected, rtol=1e-12, atol=1e-15)
        observation, *_ = env.step(action)
        np.testing.assert_allclose(env.held_force, action * plant.force_limits, rtol=1e-15)
    assert 0.05 < np.abs(action).max() <= 1.0  # a real command, not newtons and not zero


def test_a_huge_estimate_saturates_at_exactly_one():
    plant = Plant(Experiment())
    controller = LQGController(design_lqg(plant), plant)
    observation = np.zeros(plant.layout.size, dtype=np.float32)
    observation[plant.layout.readings] = 1.0e4
    action = controller.act(observation)
    assert np.all(np.abs(action) == 1.0)


@pytest.mark.parametrize("ground_model", [False, True])
def test_the_residual_prior_reads_the_scaled_estimate_of_the_observation(ground_model):
    experiment = Experiment(sensors={"state_estimate": True, "ground_model": ground_model})
    plant = Plant(experiment)
    env = BuildingEnv(plant)
    observation, _ = env.reset(seed=1, options={"motion": synthetic_suite(count=1)[0]})
    for _ in range(60):
        observation, *_ = env.step(np.zeros(3))
    layout = plant.layout
    design = design_lqg_ground_model(plant) if ground_model else design_lqg(plant, known_ground=True)
    estimate = observation[layout.estimate].astype(float) * layout.estimate_scale
    ground = float(observation[layout.ground]) * layout.ground_scale
    expected = -design.feedback @ estimate - design.feedforward * ground
    np.testing.assert_allclose(LQGPrior.design(plant)(observation), expected, rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize("ground_model", [False, True])
def test_the_prior_is_designed_on_the_design_model_not_on_the_plant(ground_model):
    experiment = Experiment(sensors={"state_estimate": True, "ground_model": ground_model})
    nominal = LQGPrior.design(Plant(experiment))
    softer = LQGPrior.design(Plant(experiment.model_copy(update={"plant": PlantConfig(stiffness=0.7)})))
    np.testing.assert_array_equal(softer.feedback, nominal.feedback)
    np.testing.assert_array_equal(softer.feedforward, nominal.feedforward)
    delayed = Plant(experiment.model_copy(update={"plant": PlantConfig(actuators={"delay_steps": 2})}))
    observation = np.ones(delayed.layout.size, dtype=np.float32)
    np.testing.assert_array_equal(LQGPrior.design(delayed)(observation), nominal(observation))


def test_a_prior_needs_the_state_estimate():
    with pytest.raises(ValueError, match="state_estimate"):
        LQGPrior.design(Plant(Experiment()))


def test_the_residual_rule_clips_the_policy_then_the_sum():
    policy = np.array([5.0, -0.5, 0.2])
    prior = np.array([0.1, -0.8, 3.0])
    np.testing.assert_allclose(residual_action(policy, prior), [1.0, -1.0, 1.0])
    np.testing.assert_allclose(residual_action(np.zeros(3), np.array([0.3, -0.2, 0.0])), [0.3, -0.2, 0.0])


def mr_plant(**sensors) -> Plant:
    from conftest import REPOSITORY

    from rlcontroller.config import load_experiment

    experiment = load_experiment(REPOSITORY / "configs" / "experiments" / "five_story_mr.yaml")
    if sensors:
        experiment = experiment.model_copy(update={"sensors": experiment.sensors.model_copy(update=sensors)})
    return Plant(experiment)


def test_clipped_optimal_switches_a_damper_on_only_to_push_toward_the_desired_force():
    """Dyke et al.'s law: on when (f_desired - f_measured) f_measured > 0, else off."""
    from types import SimpleNamespace

    from rlcontroller.control.controllers import ClippedOptimal

    plant = mr_plant()
    controller = ClippedOptimal(plant)
    measured = np.array([1.0e3, 1.0e3, -1.0e3])
    desired = np.array([2.0e3, 0.5e3, -3.0e3])  # larger, smaller, larger (negative) than measured
    size = controller.design.filter.size
    estimate = np.zeros(size)
    estimate[0] = 1.0
    feedback = np.zeros((3, size))
    feedback[:, 0] = -desired / controller.capacity
    controller.design = SimpleNamespace(
        filter=SimpleNamespace(size=size, update=lambda *args, **named: estimate), feedback=feedback
    )
    observation = np.zeros(plant.layout.size)
    observation[controller.force_rows] = measured / plant.layout.reading_scale[controller.force_rows]
    np.testing.assert_array_equal(controller.act(observation), [1.0, -1.0, 1.0])


def test_clipped_optimal_needs_every_damper_force_measured():
    from rlcontroller.config import MeasurementConfig
    from rlcontroller.control.controllers import ClippedOptimal

    plant = mr_plant(measurements=[MeasurementConfig(quantity="absolute_acceleration", scale=5.0)])
    with pytest.raises(ValueError, match=r"needs the force of every damper measured; not of \[1, 2, 3\]"):
        ClippedOptimal(plant)


def test_an_lqg_bank_acts_as_each_lqg_alone():
    """The batch steps consecutive LQG lanes as one padded linear system: over 50 steps of random
    observations, each lane's actions are its controller's own (states of sizes 11 and 13)."""
    from rlcontroller.control.controllers import LQGBank

    plant = Plant(Experiment())
    alone = [
        LQGController(design_lqg(plant, known_ground=True), plant),
        LQGController(design_lqg_ground_model(plant), plant),
    ]
    bank = LQGBank(alone, rows=3)
    rng = np.random.default_rng(7)
    for _ in range(50):
        observations = rng.standard_normal((6, plant.layout.size)).astype(np.float32)
        together = bank.act(observations)
        for lane, controller in enumerate(alone):
            rows = slice(3 * lane, 3 * lane + 3)
            np.testing.assert_allclose(
                together[rows], controller.act(observations[rows]), rtol=1e-12, atol=1e-14
            )
