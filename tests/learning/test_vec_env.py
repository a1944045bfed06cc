"""The batched vector env is N copies of the Gymnasium env, stepped as one: the same observations,
rewards, episode ends and plant draws as a DummyVecEnv, step by step."""

import numpy as np
import pytest
from stable_baselines3.common.vec_env import DummyVecEnv

from rlcontroller.config import Experiment
from rlcontroller.control.controllers import LQGPrior
from rlcontroller.learning.algorithms import make_env, make_vec_env
from rlcontroller.learning.vec_env import BatchedVecEnv
from rlcontroller.physics.plant import Plant

SHORT_MOTIONS = {"generator": {"kind": "noise_impulses", "duration": [1.0, 3.0]}}
CASES = {
    "nominal, residual on LQG": {
        "sensors": {"state_estimate": True},
        "excitation": SHORT_MOTIONS,
        "algorithm": {"name": "PPO", "residual_lqg": True},
    },
    "randomised plants, delays of 0-2 steps": {
        "excitation": SHORT_MOTIONS,
        "sensors": {"action_history": 3},
        "plant_randomization": {
            "stiffness": {"low": 0.7, "high": 1.3},
            "time_constant": {"low": 0.0, "high": 0.03},
            "delay_steps": [0, 2],
            "noise_factor": {"low": 0.5, "high": 2.0},
        },
    },
    "delays of 0-2 steps only: each drawn plant built once": {
        "excitation": SHORT_MOTIONS,
        "sensors": {"action_history": 3},
        "plant_randomization": {"delay_steps": [0, 2]},
    },
    "integrated readings, model-free, reward per motion": {
        "excitation": SHORT_MOTIONS,
        "sensors": {"integration_cutoff": 0.1, "action_history": 2},
        "reward": {
            "per_motion": True,
            "terms": [
                {"quantity": "drift", "weight": 1.0, "scale": 0.01},
                {"quantity": "drift", "weight": 1.0, "scale": 0.02, "power": 4},
                {"quantity": "force_change", "weight": 0.2, "scale": 1.0e5},
            ],
        },
    },
    "yielding stories": {"excitation": SHORT_MOTIONS, "plant": {"hysteresis": {"yield_drift": 0.01}}},
}


@pytest.mark.parametrize("case", list(CASES))
def test_the_batched_vec_env_steps_as_a_dummy_vec_env(case):
    plant = Plant(Experiment.model_validate(CASES[case]))
    prior = LQGPrior.design(plant) if plant.experiment.algorithm.residual_lqg else None
    dummy = DummyVecEnv([lambda: make_env(plant, prior) for _ in range(4)])
    batched = BatchedVecEnv(plant, 4, prior)
    dummy.seed(11)
    batched.seed(11)
    expected, actual = dummy.reset(), batched.reset()
    np.testing.assert_allclose(actual, expected, rtol=1e-6, atol=1e-6)
    rng = np.random.default_rng(0)
    episodes, delays = 0, set()
    for _ in range(400):
        actions = rng.uniform(-1.2, 1.2, (4, 3)).astype(np.float32)
        expected, expected_rewards, expected_dones, expected_infos = dummy.step(actions)
        actual, rewards, dones, infos = batched.step(actions)
        np.testing.assert_array_equal(dones, expected_dones)
        np.testing.assert_allclose(actual, expected, rtol=1e-5, atol=1e-5)
        np.testing.assert_allclose(rewards, expected_rewards, rtol=1e-5, atol=1e-7)
        for env in np.flatnonzero(dones):
            np.testing.assert_allclose(
                infos[env]["terminal_observation"],
                expected_infos[env]["terminal_observation"],
                rtol=1e-5,
                atol=1e-5,
            )
            assert infos[env]["TimeLimit.truncated"] == expected_infos[env]["TimeLimit.truncated"]
        episodes += int(dones.sum())
        delays |= {member.delay_steps for member in batched.batch.plants}
    assert episodes >= 8  # several restarts were compared
    if plant.experiment.plant_randomization is not None:
        assert delays == {0, 1, 2}  # plant states of three sizes, padded to the largest
    if case.startswith("delays"):  # a repeated draw reuses its plant, rows and transitions: the same steps
        assert len(batched.batch._drawn) == 3 and episodes > 3


def test_the_algorithm_chooses_the_vec_env():
    experiment = Experiment.model_validate({"algorithm": {"name": "PPO", "n_envs": 3}})
    assert isinstance(make_vec_env(Plant(experiment), seed=0).unwrapped, BatchedVecEnv)
    dummy = experiment.model_copy(
        update={"algorithm": experiment.algorithm.model_copy(update={"vec_env": "dummy"})}
    )
    assert isinstance(make_vec_env(Plant(dummy), seed=0).unwrapped, DummyVecEnv)
