"""Saved policies as controllers: the deterministic fast path gives exactly `predict`'s actions."""

import numpy as np
from conftest import REPOSITORY

from rlcontroller.learning.policy import PolicyController, load_policy


def test_the_fast_deterministic_path_equals_predict_bit_for_bit():
    model, _, _ = load_policy(REPOSITORY / "models" / "five_story" / "best_model.zip")
    controller = PolicyController(model)
    observations = np.random.default_rng(0).standard_normal((200, *model.observation_space.shape)) * 3.0
    for observation in observations.astype(np.float32):
        expected, _ = model.predict(observation, deterministic=True)
        np.testing.assert_array_equal(np.clip(controller._deterministic(observation), -1.0, 1.0), expected)


def test_the_committed_policy_loads_with_its_normaliser_and_prior():
    controller = PolicyController.load(REPOSITORY / "models" / "five_story" / "best_model.zip")
    assert controller.prior is not None and controller.source.endswith("best_model.zip")
    action = controller.act(np.zeros(controller.model.observation_space.shape, dtype=np.float32))
    assert action.shape == (3,) and np.all(np.abs(action) <= 1.0)
