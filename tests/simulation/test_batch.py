"""The batch steps many buildings as the env steps one: the same responses as `rollout`, record by
record, for records of different lengths and sampling, on plants with actuator dynamics, sensor
faults and yielding stories."""

from dataclasses import replace

import numpy as np
import pytest
from conftest import NETWORK_POLICY, SAME_PHYSICS

from rlcontroller.config import Experiment, load_experiment
from rlcontroller.control.controllers import LQGController, Uncontrolled
from rlcontroller.control.lqg import design_lqg, design_lqg_ground_model
from rlcontroller.control.policy_file import read_policy
from rlcontroller.learning.env import BuildingEnv, rollout
from rlcontroller.physics.motions.records import synthetic_suite
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation import rollout as rollout_module
from rlcontroller.simulation.rollout import batch_rollout

PLANTS = {
    "nominal": {},
    "lag, delay and sensor faults": {
        "plant": {
            "stiffness": 0.8,
            "actuators": {"time_constant": 0.03, "delay_steps": 2},
            "sensors": {"noise_factor": 2.0, "dead_floors": [2], "bias": [{"floor": 4, "value": 0.05}]},
        }
    },
    "yielding": {"plant": {"hysteresis": {"yield_drift": 0.012}}},
    "a 4th-power, a force-change term, per motion": {
        "reward": {
            "terms": [
                {"quantity": "drift", "weight": 1.0, "scale": 0.05},
                {"quantity": "drift", "weight": 1.0, "scale": 0.03, "power": 4},
                {"quantity": "force_change", "weight": 0.2, "scale": 5.0e4},
            ],
            "per_motion": True,
        }
    },
}


def mixed_motions():
    """Three motions of different lengths sampled at 0.005, 0.01 and 0.02 s."""
    motions = synthetic_suite(count=3)
    shortened = replace(motions[1], acceleration=motions[1].acceleration[:601])
    time = np.arange(motions[2].acceleration.size) * motions[2].dt
    fine_time = np.arange(0.0, 0.3 * motions[2].duration, motions[2].dt / 4)
    finer = replace(
        motions[2], dt=motions[2].dt / 4, acceleration=np.interp(fine_time, time, motions[2].acceleration)
    )
    coarser = replace(motions[0], dt=motions[0].dt * 2, acceleration=motions[0].acceleration[::2])
    return [shortened, finer, coarser]


@pytest.mark.slow
@pytest.mark.parametrize("case", list(PLANTS))
def test_a_batch_of_records_gives_each_record_s_rollout(case):
    plant = Plant(Experiment.model_validate(PLANTS[case]))
    motions = mixed_motions()
    assert len({motion.dt for motion in motions}) == 3 and len({m.acceleration.size for m in motions}) == 3
    design = plant.design
    controllers = [
        Uncontrolled(3),
        LQGController(design_lqg(design, known_ground=True), design),
        LQGController(design_lqg_ground_model(design), design, "LQG + ground model"),
    ]
    assert_batch_is_env(
        plant, motions, controllers, ("drift", "absolute_acceleration", "base_shear", "force")
    )


def assert_batch_is_env(plant, motions, controllers, quantities, seeds=(5, 6, 7)):
    """Every controller on every motion, batched, as the Gymnasium env gives it alone (to SAME_PHYSICS)."""
    batched = batch_rollout(plant, motions, controllers, seeds=list(seeds))
    env = BuildingEnv(plant)
    for controller, runs in zip(controllers, batched, strict=True):
        for motion, seed, (result, reward) in zip(motions, seeds, runs, strict=True):
            alone, alone_reward = rollout(env, motion, controller, seed=seed)
            assert reward == pytest.approx(alone_reward, rel=SAME_PHYSICS)
            assert result.drift.shape == alone.drift.shape
            for quantity in quantities:
                expected = alone.quantity(quantity)
                np.testing.assert_allclose(
                    result.quantity(quantity),
                    expected,
                    rtol=SAME_PHYSICS,
                    atol=SAME_PHYSICS * np.abs(expected).max(),
                )


def test_small_batches_give_the_same_responses_as_one(monkeypatch):
    plant = Plant(Experiment())
    motions = mixed_motions()
    controller = LQGController(design_lqg(plant), plant)
    whole = batch_rollout(plant, motions, [controller])[0]
    monkeypatch.setattr(rollout_module, "ROWS_PER_BATCH", 1)  # one motion per batch
    for (one, _), (many, _) in zip(batch_rollout(plant, motions, [controller])[0], whole, strict=True):
        np.testing.assert_allclose(
            one.drift, many.drift, rtol=SAME_PHYSICS, atol=SAME_PHYSICS * np.abs(many.drift).max()
        )


def test_the_policy_acts_on_the_batch_as_on_each_record():
    plant = Plant(load_experiment(NETWORK_POLICY / "config.yaml"))
    controller = read_policy(NETWORK_POLICY, "best", plant)
    motions = mixed_motions()
    batched = batch_rollout(plant, motions, [controller])[0]
    env = BuildingEnv(plant)
    for index, (motion, (result, _)) in enumerate(zip(motions, batched, strict=True)):
        alone, _ = rollout(env, motion, controller, seed=index)
        scale = np.abs(alone.force).max()
        np.testing.assert_allclose(result.force, alone.force, rtol=1e-4, atol=1e-4 * scale)


@pytest.mark.slow
def test_a_batch_of_mr_damper_buildings_gives_each_record_s_rollout():
    """Members of one damper plant step in one compiled call per sampling; each as the env alone."""
    from conftest import REPOSITORY

    from rlcontroller.control.controllers import ClippedOptimal, ConstantCommand

    plant = Plant(load_experiment(REPOSITORY / "configs" / "experiments" / "five_story_mr.yaml"))
    controllers = [ConstantCommand(0.3, 3, "constant"), ClippedOptimal(plant)]
    assert_batch_is_env(plant, mixed_motions(), controllers, ("drift", "absolute_acceleration", "force"))


def test_an_episode_generator_is_gymnasiums_for_the_same_seed():
    """The batch seeds its members as `BuildingEnv.reset(seed=...)` does, without importing gymnasium."""
    from gymnasium.utils import seeding

    from rlcontroller.simulation.batch import episode_generator

    for seed in (0, 7, 2**32 - 1):
        np.testing.assert_array_equal(episode_generator(seed).random(5), seeding.np_random(seed)[0].random(5))


def test_a_reward_with_the_uncontrolled_baseline_adds_back_the_cost_of_the_step_left_alone():
    """`reward.baseline: uncontrolled`: with no force every step's reward is zero (to rounding); with any
    actions it is the plain reward less the plain reward of the same motion and noise with no force, step by
    step (the same ground, the same linear map); a plant that is not linear is refused in one line."""
    from rlcontroller.config import ConfigError
    from rlcontroller.simulation.batch import BuildingBatch, episode_generator

    terms = PLANTS["a 4th-power, a force-change term, per motion"]["reward"]["terms"]
    motions = synthetic_suite(count=3)

    def rewards(baseline: str, actions) -> np.ndarray:
        plant = Plant(Experiment.model_validate({"reward": {"terms": terms, "baseline": baseline}}))
        batch = BuildingBatch(plant, 3)
        for member, motion in enumerate(motions):
            batch.start(member, episode_generator(member), motion)
        steps = int(batch.steps.min())
        return np.array([batch.step(actions(k))[1] for k in range(steps)])

    rng = np.random.default_rng(0)
    pushes = rng.uniform(-1.0, 1.0, (4000, 3, 3))
    alone = rewards("none", lambda k: np.zeros((3, 3)))
    assert np.max(np.abs(rewards("uncontrolled", lambda k: np.zeros((3, 3))))) < 1e-9 * np.max(np.abs(alone))
    relative, plain = rewards("uncontrolled", lambda k: pushes[k]), rewards("none", lambda k: pushes[k])
    np.testing.assert_allclose(relative, plain - alone, rtol=1e-9, atol=1e-12 * np.max(np.abs(alone)))
    yielding = Experiment.model_validate(
        PLANTS["yielding"] | {"reward": {"terms": terms, "baseline": "uncontrolled"}}
    )
    with pytest.raises(ConfigError, match="reward.baseline: uncontrolled needs a linear plant"):
        BuildingBatch(Plant(yielding), 1).start(0, episode_generator(0), motions[0])
