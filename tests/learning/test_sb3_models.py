"""Saved policies: the numpy actor gives `predict`'s actions to float32 rounding; a policy is data
(saved and read back exactly, never unpickled)."""

import base64
import json
import pickle
import shutil
import zipfile
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import NETWORK_POLICY, REPOSITORY
from typer.testing import CliRunner

from rlcontroller.cli import app
from rlcontroller.config import Experiment, load_experiment
from rlcontroller.control.controllers import LQGPrior
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.control.policy_file import read_policy, write_policy
from rlcontroller.learning.actor import actor_of
from rlcontroller.learning.env import BuildingEnv
from rlcontroller.learning.sb3_models import algorithm_class, policy_controller
from rlcontroller.physics.plant import Plant


def test_the_numpy_actor_equals_predict_to_float32_rounding():
    model = algorithm_class("PPO")("MlpPolicy", BuildingEnv(), policy_kwargs={"net_arch": [64, 64]}, seed=0)
    controller = policy_controller(model, None)
    observations = (
        np.random.default_rng(0).standard_normal((200, *model.observation_space.shape)) * 3.0
    ).astype(np.float32)
    expected, _ = model.predict(observations, deterministic=True)
    np.testing.assert_allclose(controller.act(observations), expected, rtol=1e-5, atol=1e-6)
    for observation, row in zip(observations[:5], expected, strict=False):
        np.testing.assert_allclose(controller.act(observation), row, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize(
    ("name", "activation"),
    [("SAC", "ReLU"), ("PPO", "Tanh"), ("PPO", "GELU"), ("A2C", "ELU"), ("TD3", "ReLU")],
)
def test_the_numpy_actor_of_other_learners_and_activations(name, activation):
    import torch

    model = algorithm_class(name)(
        "MlpPolicy",
        BuildingEnv(),
        policy_kwargs={"net_arch": [32, 16], "activation_fn": getattr(torch.nn, activation)},
    )
    actor = actor_of(model)
    observations = (
        np.random.default_rng(1).standard_normal((50, *model.observation_space.shape)).astype(np.float32)
    )
    expected, _ = model.predict(observations, deterministic=True)
    np.testing.assert_allclose(np.clip(actor(observations), -1.0, 1.0), expected, rtol=1e-5, atol=1e-6)


def test_the_committed_policy_loads_with_its_prior_from_data():
    plant = Plant(load_experiment(NETWORK_POLICY / "config.yaml"))
    controller = read_policy(NETWORK_POLICY, "best", plant)
    assert controller.prior is not None and controller.source.endswith("best_policy.yaml")
    np.testing.assert_allclose(controller.prior.feedback, LQGPrior.design(plant).feedback, rtol=1e-12)
    action = controller.act(np.zeros(plant.layout.size, dtype=np.float32))
    assert action.shape == (3,) and np.all(np.abs(action) <= 1.0)


@pytest.mark.parametrize(
    ("name", "experiment"),
    [
        ("PPO", {"algorithm": {"name": "PPO", "normalize_observations": True}}),
        ("SAC", {"algorithm": {"name": "SAC"}, "sensors": {"history": 3}}),
        ("PPO", {"algorithm": {"name": "PPO", "residual_lqg": True}, "sensors": {"state_estimate": True}}),
    ],
)
def test_a_policy_saved_as_data_reads_back_to_the_same_actions(tmp_path, name, experiment):
    from rlcontroller.learning.algorithms import build_model, make_vec_env

    experiment = Experiment.model_validate(experiment)
    plant = Plant(experiment)
    vec_env = make_vec_env(plant, seed=0)
    model = build_model(experiment, vec_env, seed=0, device="cpu", tensorboard=None)
    normalize = model.get_vec_normalize_env()
    if normalize is not None:  # statistics away from their initial values
        normalize.obs_rms.mean = np.linspace(-1.0, 1.0, plant.layout.size)
        normalize.obs_rms.var = np.linspace(0.5, 2.0, plant.layout.size)
    prior = LQGPrior.design(plant) if experiment.algorithm.residual_lqg else None
    saved = policy_controller(model, prior, normalize)
    write_policy(saved, plant, tmp_path, "best")
    read = read_policy(tmp_path, "best", plant)
    observations = np.random.default_rng(3).standard_normal((50, plant.layout.size)).astype(np.float32)
    np.testing.assert_array_equal(read.act(observations), saved.act(observations))
    assert (read.normalizer is None) == (normalize is None) and (read.prior is None) == (prior is None)
    if normalize is not None:  # the statistics matter: without them the actions differ
        bare = PolicyController(read.actor)
        assert not np.allclose(bare.act(observations), read.act(observations))


class Payload:
    """Unpickling this creates the file `marker`: proof that opening a file ran its author's code."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (open, (str(self.marker), "w"))


def plant_payloads(folder: Path, marker: Path) -> None:
    """A copy of a model folder with a pickle payload in every file a loader might open."""
    payload = pickle.dumps(Payload(marker))
    serialized = {"policy_class": {":type:": "x", ":serialized:": base64.b64encode(payload).decode()}}
    with zipfile.ZipFile(folder / "best_model.zip", "w") as archive:  # stable-baselines3's layout
        archive.writestr("data", json.dumps(serialized))
        archive.writestr("policy.pth", payload)
    (folder / "best_model.vecnormalize.pkl").write_bytes(payload)
    (folder / "replay_buffer.pkl").write_bytes(payload)


@pytest.mark.slow
@pytest.mark.parametrize("where", ["beside", "weights", "yaml"])
def test_a_payload_planted_in_a_model_folder_never_runs(tmp_path, records, where):
    folder = tmp_path / "shared_model"
    shutil.copytree(NETWORK_POLICY, folder)
    marker = tmp_path / "payload_ran"
    plant_payloads(folder, marker)
    if where == "weights":  # an object array in the .npz is a pickle
        np.savez(folder / "best_policy.npz", layer0_weight=np.array([Payload(marker)], dtype=object))
    if where == "yaml":
        text = (folder / "best_policy.yaml").read_text()
        tag = f"extra: !!python/object/apply:builtins.open ['{marker}', 'w']\n"
        (folder / "best_policy.yaml").write_text(text + tag)
    kobe = str(records / "RSN1106_KOBE_KJM000.AT2")
    quick = tmp_path / "quick_standard.yaml"  # the safety check on a few motions: the same reading path
    standard = yaml.safe_load((REPOSITORY / "configs" / "checks" / "standard.yaml").read_text())
    quick.write_text(yaml.safe_dump(standard | {"motions": 3, "rest_runs": 1, "rest_duration": 5.0}))
    commands = [
        ["check", str(folder), "--standard", str(quick)],
        ["evaluate", str(folder), "--records", kobe, "--out", str(tmp_path / "evaluation")],
        ["compare", "lqg", str(folder), "--records", kobe, "--out", str(tmp_path / "compare")],
        ["robustness", str(folder), "--records", kobe, "--out", str(tmp_path / "robustness")],
        ["export", str(folder), "--out", str(tmp_path / "controller.onnx")],
    ]
    for arguments in commands:
        result = CliRunner().invoke(app, arguments)
        assert not marker.exists(), f"rlc {arguments[0]} ran the payload"
        if where == "beside":
            assert result.exit_code in (0, 1) if arguments[0] == "check" else result.exit_code == 0, (
                result.output
            )
        else:
            assert result.exit_code == 2 and "error: " in result.output, result.output
            assert "Traceback" not in result.output


@pytest.mark.slow
def test_a_folder_with_only_a_stable_baselines3_zip_is_refused_with_the_way_to_convert(tmp_path):
    folder = tmp_path / "old_run"
    folder.mkdir()
    shutil.copy(NETWORK_POLICY / "config.yaml", folder)
    plant_payloads(folder, tmp_path / "payload_ran")
    result = CliRunner().invoke(app, ["evaluate", str(folder), "--out", str(tmp_path / "out")])
    assert (
        result.exit_code == 2
        and "--trust-pickle" in result.output
        and not (tmp_path / "payload_ran").exists()
    )
    refused = CliRunner().invoke(app, ["convert", str(folder)])
    assert refused.exit_code == 2 and "can run their author's code" in refused.output
    assert not (tmp_path / "payload_ran").exists()


def test_an_odd_policy_gives_no_force_without_readings_and_mirrors_its_action():
    from rlcontroller.config import Experiment
    from rlcontroller.learning.algorithms import build_model, make_vec_env
    from rlcontroller.physics.plant import Plant

    experiment = Experiment.model_validate(
        {"algorithm": {"name": "PPO", "policy": {"net_arch": [32, 32], "odd": True}}}
    )
    model = build_model(
        experiment, make_vec_env(Plant(experiment), seed=0), seed=0, device="cpu", tensorboard=None
    )
    observations = (
        np.random.default_rng(2).standard_normal((20, *model.observation_space.shape)).astype(np.float32)
    )
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
    model = build_model(
        experiment, make_vec_env(Plant(experiment), seed=0), seed=0, device="cpu", tensorboard=None
    )
    actor = actor_of(model)
    assert len(actor.layers) == 1 and actor.layers[0].activation is None
    critic = model.policy.mlp_extractor.value_net if name == "PPO" else model.policy.critic.qf0
    assert sum(isinstance(layer, torch.nn.Linear) for layer in critic) == (2 if name == "PPO" else 3)
    first, second = (
        np.random.default_rng(4).standard_normal((2, 7, *model.observation_space.shape)).astype(np.float32)
    )
    if name == "PPO":  # odd and linear: the mean is W o, no bias
        np.testing.assert_allclose(actor(first + second), actor(first) + actor(second), rtol=1e-4, atol=1e-5)


def test_an_odd_policy_is_refused_at_loading_for_sac_and_with_centred_observations():
    from rlcontroller.config import ConfigError, build_experiment

    with pytest.raises(
        ConfigError,
        match="policy.odd: only for PPO, A2C, RandomSearch, and SAC or TQC with backend: sbx, not SAC$",
    ):
        build_experiment({"algorithm": {"name": "SAC", "policy": {"odd": True}}})
    with pytest.raises(ConfigError, match="policy.odd: needs normalize_observations: false"):
        build_experiment(
            {"algorithm": {"name": "PPO", "normalize_observations": True, "policy": {"odd": True}}}
        )


SHIPPED = sorted(path.name for path in (REPOSITORY / "models").iterdir() if path.is_dir())


@pytest.mark.parametrize("name", SHIPPED)
def test_every_shipped_model_loads_and_acts_from_a_fresh_clone(name):
    folder = REPOSITORY / "models" / name
    plant = Plant(load_experiment(folder / "config.yaml"))
    controller = read_policy(folder, "best", plant)
    zero = np.zeros(plant.layout.size, dtype=np.float32)
    action = controller.act(zero)
    assert action.shape == (plant.building.n_actuators,) and np.all(np.abs(action) <= 1.0)
    if controller.actor.odd:
        assert np.all(controller.actor(zero) == 0.0)  # no readings, no residual
    assert not list(folder.glob("*.zip")) and not list(folder.glob("*.pkl"))  # nothing that unpickles


@pytest.mark.parametrize(
    ("damage", "expected"),
    [
        (
            lambda f: edit(f / "best_policy.yaml", "format_version: 1", "format_version: 7"),
            "format_version 7",
        ),
        (lambda f: edit(f / "best_policy.yaml", "size: 43", "size: 44"), "observation size 44"),
        (lambda f: edit(f / "best_policy.yaml", "network:", "network: 5\nx:"), "unknown key x"),
        (lambda f: (f / "best_policy.yaml").write_text("[1, 2"), "not readable YAML"),
        (
            lambda f: arrays(f, layer0_weight=lambda a: a[:, :5]),
            "layer0_weight is (128, 5) of float32, the policy declares (128, 43)",
        ),
        (lambda f: arrays(f, layer1_bias=lambda a: a * np.nan), "expected finite floating-point numbers"),
        (lambda f: arrays(f, prior_feedback=None), "no array prior_feedback (the policy declares it)"),
        (lambda f: (f / "best_policy.npz").unlink(), "missing (the policy's weights)"),
    ],
)
@pytest.mark.slow
def test_a_damaged_policy_file_is_one_line_naming_it(tmp_path, damage, expected):
    folder = tmp_path / "model"
    shutil.copytree(NETWORK_POLICY, folder)
    damage(folder)
    result = CliRunner().invoke(app, ["evaluate", str(folder), "--out", str(tmp_path / "out")])
    lines = result.output.strip().splitlines()
    assert result.exit_code == 2 and lines[-1].startswith(f"error: {folder}") and expected in lines[-1], (
        result.output
    )
    assert "Traceback" not in result.output and not (tmp_path / "out").exists()


def edit(path: Path, old: str, new: str) -> None:
    path.write_text(path.read_text().replace(old, new))


def arrays(folder: Path, **changes) -> None:
    """Rewrite best_policy.npz with each named array changed (None: removed)."""
    weights = dict(np.load(folder / "best_policy.npz"))
    for key, change in changes.items():
        if change is None:
            del weights[key]
        else:
            weights[key] = change(weights[key])
    np.savez(folder / "best_policy.npz", **weights)
