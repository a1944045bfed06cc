"""Saved policies as controllers: the numpy actor gives `predict`'s actions to float32 rounding."""

import numpy as np
import pytest
from conftest import REPOSITORY

from rlcontroller.learning.actor import actor_of
from rlcontroller.learning.env import BuildingEnv
from rlcontroller.learning.policy import PolicyController, algorithm_class, load_policy


def test_the_numpy_actor_equals_predict_to_float32_rounding():
    model, _, _ = load_policy(REPOSITORY / "models" / "five_story" / "best_model.zip")
    controller = PolicyController(model)
    assert controller.actor is not None
    observations = (np.random.default_rng(0).standard_normal((200, *model.observation_space.shape)) * 3.0).astype(
        np.float32
    )
    expected, _ = model.predict(observations, deterministic=True)
    batch = np.clip(controller._deterministic(observations), -1.0, 1.0)
    np.testing.assert_allclose(batch, expected, rtol=1e-5, atol=1e-6)
    for observation, row in zip(observations[:5], expected, strict=False):
        np.testing.assert_allclose(
            np.clip(controller._deterministic(observation), -1.0, 1.0), row, rtol=1e-5, atol=1e-6
        )


@pytest.mark.parametrize(("name", "activation"), [("SAC", "ReLU"), ("PPO", "Tanh"), ("PPO", "GELU"), ("A2C", "ELU")])
def test_the_numpy_actor_of_other_learners_and_activations(name, activation):
    import torch

    model = algorithm_class(name)(
        "MlpPolicy", BuildingEnv(), policy_kwargs={"net_arch": [32, 16], "activation_fn": getattr(torch.nn, activation)}
    )
    actor = actor_of(model)
    observations = np.random.default_rng(1).standard_normal((50, *model.observation_space.shape)).astype(np.float32)
    expected, _ = model.predict(observations, deterministic=True)
    np.testing.assert_allclose(np.clip(actor(observations), -1.0, 1.0), expected, rtol=1e-5, atol=1e-6)


def test_the_committed_policy_loads_with_its_normaliser_and_prior():
    controller = PolicyController.load(REPOSITORY / "models" / "five_story" / "best_model.zip")
    assert controller.prior is not None and controller.source.endswith("best_model.zip")
    action = controller.act(np.zeros(controller.model.observation_space.shape, dtype=np.float32))
    assert action.shape == (3,) and np.all(np.abs(action) <= 1.0)


def test_an_odd_policy_gives_no_force_without_readings_and_mirrors_its_action():
    from rlcontroller.config import Experiment
    from rlcontroller.learning.algorithms import build_model, make_vec_env
    from rlcontroller.physics.plant import Plant

    experiment = Experiment.model_validate(
        {"algorithm": {"name": "PPO", "policy": {"net_arch": [32, 32], "odd": True}}}
    )
    model = build_model(experiment, make_vec_env(Plant(experiment), seed=0), seed=0, device="cpu", tensorboard=None)
    observations = np.random.default_rng(2).standard_normal((20, *model.observation_space.shape)).astype(np.float32)
    zero = np.zeros((1, *model.observation_space.shape), dtype=np.float32)
    assert np.all(model.predict(zero, deterministic=True)[0] == 0.0)
    forward, _ = model.predict(observations, deterministic=True)
    mirrored, _ = model.predict(-observations, deterministic=True)
    np.testing.assert_allclose(mirrored, -forward, atol=1e-6)
    actor = actor_of(model)
    assert actor.odd
    np.testing.assert_allclose(np.clip(actor(observations), -1.0, 1.0), forward, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("name", ["PPO", "SAC"])
def test_an_empty_actor_arch_gives_a_linear_actor_and_keeps_the_critic(name):
    import torch

    from rlcontroller.config import Experiment
    from rlcontroller.learning.algorithms import build_model, make_vec_env
    from rlcontroller.physics.plant import Plant

    policy = {"net_arch": [32, 32], "actor_arch": [], "odd": name == "PPO", "log_std_init": -1.0}
    experiment = Experiment.model_validate({"algorithm": {"name": name, "policy": policy}})
    model = build_model(experiment, make_vec_env(Plant(experiment), seed=0), seed=0, device="cpu", tensorboard=None)
    actor = actor_of(model)
    assert len(actor.layers) == 1 and actor.layers[0].activation is None
    critic = model.policy.mlp_extractor.value_net if name == "PPO" else model.policy.critic.qf0
    assert sum(isinstance(layer, torch.nn.Linear) for layer in critic) == (2 if name == "PPO" else 3)
    first, second = np.random.default_rng(4).standard_normal((2, 7, *model.observation_space.shape)).astype(np.float32)
    if name == "PPO":  # odd and linear: the mean is W o, no bias
        np.testing.assert_allclose(actor(first + second), actor(first) + actor(second), rtol=1e-4, atol=1e-5)


def test_an_odd_policy_is_refused_for_sac():
    from rlcontroller.config import ConfigError, Experiment
    from rlcontroller.learning.algorithms import build_model, make_vec_env
    from rlcontroller.physics.plant import Plant

    experiment = Experiment.model_validate({"algorithm": {"name": "SAC", "policy": {"odd": True}}})
    with pytest.raises(ConfigError, match="policy.odd: only for PPO, A2C and RandomSearch"):
        build_model(experiment, make_vec_env(Plant(experiment), seed=0), seed=0, device="cpu", tensorboard=None)


def test_an_odd_policy_is_refused_with_centred_observations():
    from rlcontroller.config import ConfigError, Experiment
    from rlcontroller.learning.algorithms import check_algorithm

    experiment = Experiment.model_validate(
        {"algorithm": {"name": "PPO", "normalize_observations": True, "policy": {"odd": True}}}
    )
    with pytest.raises(ConfigError, match="policy.odd: needs normalize_observations: false"):
        check_algorithm(experiment)


ODD_ACTORS = [
    "five_story_odd",
    "five_story_robust_free",
    "five_story_model_free",
    "five_story_model_free_robust",
    "five_story_model_free_random_search",
    "five_story_model_free_random_search_robust",
]


@pytest.mark.parametrize("name", ["five_story", "five_story_robust", *ODD_ACTORS])
def test_every_committed_model_loads_and_acts_from_a_fresh_clone(name):
    controller = PolicyController.load(REPOSITORY / "models" / name / "best_model.zip")
    zero = np.zeros(controller.model.observation_space.shape, dtype=np.float32)
    action = controller.act(zero)
    assert action.shape == (3,) and np.all(np.abs(action) <= 1.0)
    assert (name in ODD_ACTORS) == controller.actor.odd
    if controller.actor.odd:
        assert np.all(controller.actor(zero) == 0.0)  # no readings, no residual
