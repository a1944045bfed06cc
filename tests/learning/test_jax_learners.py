"""The sbx backend (`algorithm.backend: sbx`): its actor saved as data acts as sbx's own deterministic policy,
its checkpoints restore every part of the learner without a pickle, and damaged ones stop in one line."""

import shutil
import zipfile

import numpy as np
import pytest
from conftest import REPOSITORY
from typer.testing import CliRunner

from rlcontroller.cli import app
from rlcontroller.config import ConfigError, build_experiment, load_experiment
from rlcontroller.control.policy_file import read_policy, write_policy
from rlcontroller.learning.algorithms import build_model, make_vec_env
from rlcontroller.learning.run_folder import RunFolder
from rlcontroller.learning.sb3_models import policy_controller
from rlcontroller.learning.training import train
from rlcontroller.physics.plant import Plant

pytest.importorskip("sbx")
import jax  # noqa: E402

from rlcontroller.learning.jax_learners import load_jax_learner, save_jax_learner  # noqa: E402

SMOKE = REPOSITORY / "configs" / "testing" / "smoke.yaml"


def smoke(name: str = "SAC", **settings):
    experiment = load_experiment(SMOKE)
    algorithm = experiment.algorithm.model_dump() | {"name": name, "backend": "sbx"} | settings
    if name == "TD3":
        algorithm["kwargs"] = {key: value for key, value in algorithm["kwargs"].items() if key != "ent_coef"}
    return experiment.model_copy(update={"algorithm": type(experiment.algorithm).model_validate(algorithm)})


def learned(experiment, steps: int = 400):
    """An sbx learner trained `steps` steps on the experiment's env (its updates started at 200)."""
    vec_env = make_vec_env(Plant(experiment), experiment.seed)
    model = build_model(experiment, vec_env, experiment.seed, "cpu", tensorboard=None)
    model.learn(steps)
    return model, vec_env


@pytest.mark.parametrize(
    ("name", "activation", "actor_arch"),
    [("SAC", "relu", None), ("TQC", "gelu", [16]), ("TD3", "tanh", None)],
)
def test_the_saved_actor_acts_as_sbx_s_deterministic_policy(tmp_path, name, activation, actor_arch):
    policy = {"net_arch": [32, 32], "activation": activation, "actor_arch": actor_arch}
    experiment = smoke(name, policy=policy, normalize_observations=True, kwargs={"learning_starts": 50})
    model, vec_env = learned(experiment, steps=100)
    normalize = model.get_vec_normalize_env()
    write_policy(policy_controller(model, None, normalize), Plant(experiment), tmp_path, "final")
    controller = read_policy(tmp_path, "final", Plant(experiment))  # the data a run folder keeps
    raw = 5.0 * np.random.default_rng(0).normal(size=(64, vec_env.observation_space.shape[0])).astype(
        np.float32
    )
    expected = np.asarray(model.policy.predict(normalize.normalize_obs(raw), deterministic=True)[0])
    got = np.clip(controller.actor(controller.normalizer(raw)), -1.0, 1.0)
    assert np.abs(expected).max() > 0.05  # a policy that acts, not the zero map
    assert np.allclose(got, expected, atol=2e-5), np.abs(got - expected).max()


@pytest.mark.parametrize(("name", "actor_arch"), [("SAC", []), ("TQC", [16])])
def test_an_odd_sbx_actor_gives_no_force_without_readings_mirrors_its_action_and_saves_as_data(
    tmp_path, name, actor_arch
):
    policy = {"net_arch": [32, 32], "actor_arch": actor_arch, "odd": True}
    experiment = smoke(name, policy=policy, normalize_observations=False, kwargs={"learning_starts": 50})
    model, vec_env = learned(experiment, steps=100)
    write_policy(policy_controller(model, None, None), Plant(experiment), tmp_path, "final")
    controller = read_policy(tmp_path, "final", Plant(experiment))
    size = vec_env.observation_space.shape[0]
    readings = np.random.default_rng(1).normal(size=(64, size)).astype(np.float32)
    forward = np.asarray(model.policy.predict(readings, deterministic=True)[0])
    mirrored = np.asarray(model.policy.predict(-readings, deterministic=True)[0])
    assert np.abs(forward).max() > 0.05  # a policy that acts
    np.testing.assert_allclose(mirrored, -forward, atol=1e-6)
    assert np.all(model.policy.predict(np.zeros((1, size), np.float32), deterministic=True)[0] == 0.0)
    assert controller.actor.odd  # the data a run folder keeps acts as sbx's policy
    np.testing.assert_allclose(np.clip(controller.actor(readings), -1.0, 1.0), forward, atol=2e-5)
    if not actor_arch:  # odd and linear: tanh(W o), no bias
        first, second = readings[:32], readings[32:]
        pre = np.arctanh(np.clip(controller.actor(first + second), -0.999999, 0.999999))
        parts = np.arctanh(controller.actor(first)) + np.arctanh(controller.actor(second))
        np.testing.assert_allclose(pre, parts, rtol=1e-3, atol=1e-4)


@pytest.mark.slow
def test_a_checkpoint_restores_the_whole_learner_without_pickle(tmp_path):
    experiment = smoke(normalize_observations=True)
    model, vec_env = learned(experiment)
    save_jax_learner(model, tmp_path)
    for path in tmp_path.iterdir():  # arrays and JSON only: every npz loads without pickle
        assert path.suffix in (".npz", ".json"), path
        if path.suffix == ".npz":
            with np.load(path, allow_pickle=False) as saved:
                [saved[name] for name in saved.files]
    fresh = build_model(
        experiment, make_vec_env(Plant(experiment), experiment.seed), experiment.seed, "cpu", tensorboard=None
    )
    load_jax_learner(fresh, tmp_path)
    fresh.set_logger(model.logger)
    assert fresh.num_timesteps == model.num_timesteps == 400 and fresh._n_updates == model._n_updates > 0
    buffers = model.replay_buffer, fresh.replay_buffer
    assert buffers[1].pos == buffers[0].pos
    assert np.array_equal(
        buffers[1].observations[: buffers[0].pos], buffers[0].observations[: buffers[0].pos]
    )
    saved_rms, loaded_rms = model.get_vec_normalize_env().obs_rms, fresh.get_vec_normalize_env().obs_rms
    assert np.array_equal(saved_rms.mean, loaded_rms.mean) and saved_rms.count == loaded_rms.count
    # the same updates from the same batches: parameters, targets, optimiser moments, temperature and keys all
    # came back
    for learner in (model, fresh):
        np.random.seed(5)  # stable-baselines3's replay buffer samples with numpy's global generator
        learner.train(gradient_steps=3, batch_size=64)
    for before, after in zip(
        jax.tree_util.tree_leaves((model.policy.actor_state, model.policy.qf_state, model.ent_coef_state)),
        jax.tree_util.tree_leaves((fresh.policy.actor_state, fresh.policy.qf_state, fresh.ent_coef_state)),
        strict=True,
    ):
        assert np.array_equal(np.asarray(before), np.asarray(after))


def test_return_statistics_alone_are_checkpointed_and_restored(tmp_path):
    # normalize_rewards without normalize_observations (an odd actor's setting): VecNormalize keeps no
    # observation statistics then, and the checkpoint holds the returns' alone
    experiment = smoke(normalize_observations=False, normalize_rewards=True, kwargs={"learning_starts": 50})
    model, _ = learned(experiment, steps=100)
    save_jax_learner(model, tmp_path)
    with np.load(tmp_path / "vecnormalize.npz") as saved:
        assert sorted(saved.files) == ["ret_count", "ret_mean", "ret_var"]
    fresh = build_model(experiment, make_vec_env(Plant(experiment), 1), 1, "cpu", tensorboard=None)
    load_jax_learner(fresh, tmp_path)
    kept, restored = model.get_vec_normalize_env().ret_rms, fresh.get_vec_normalize_env().ret_rms
    assert kept.count > 100 and restored.count == kept.count and restored.var == kept.var


@pytest.mark.slow
def test_an_sbx_run_resumes_to_its_total_and_holds_no_pickle(tmp_path):
    run = tmp_path / "run"
    experiment = smoke(total_steps=600, checkpoint_every=300, eval_every=300)
    # stops at the first step, with a checkpoint
    summary = train(experiment=experiment, run_dir=run, time_limit_s=0.0)
    assert summary.time_limit_reached and RunFolder(run).checkpoints()
    assert train(resume=run).steps == 600
    files = [path.name for path in run.rglob("*") if path.is_file()]
    assert not [name for name in files if name.endswith((".pkl", ".zip"))], files
    assert {p.name for p in RunFolder(run).checkpoints()[-1].iterdir()} == {
        "learner.npz",
        "learner.json",
        "replay_buffer.npz",
        "state.json",
    }
    assert read_policy(run, "best", Plant(experiment)).algorithm == "SAC"


@pytest.mark.slow
@pytest.mark.parametrize(
    ("damaged", "expected"),
    [
        ("learner.npz", "learner.npz: unreadable checkpoint file (ValueError: not a numpy .npz archive)"),
        (
            "replay_buffer.npz",
            "replay_buffer.npz: unreadable checkpoint file (ValueError: not a numpy .npz archive)",
        ),
        ("learner.json", "learner.json: unreadable checkpoint file (JSONDecodeError"),
    ],
)
def test_a_damaged_sbx_checkpoint_stops_resume_with_one_line(tmp_path, damaged, expected):
    run = tmp_path / "run"
    train(experiment=smoke(total_steps=600, checkpoint_every=300, eval_every=300), run_dir=run)
    config = run / "config.yaml"
    config.write_text(config.read_text().replace("total_steps: 600", "total_steps: 900"))
    previous, newest = RunFolder(run).checkpoints()[-2:]
    (newest / damaged).write_bytes(b"\x00garbage")
    result = CliRunner().invoke(app, ["train", "--resume", str(run), "--no-progress"])
    assert result.exit_code == 2 and "Traceback" not in result.output
    line = result.output.strip().splitlines()[-1]
    assert expected in line and line.endswith(f"delete {newest} to resume from {previous.name}")


def test_a_checkpoint_of_another_network_is_refused_naming_the_array(tmp_path):
    model, _ = learned(smoke(policy={"net_arch": [8]}), steps=1)
    save_jax_learner(model, tmp_path)
    other = smoke(policy={"net_arch": [16]})
    fresh = build_model(other, make_vec_env(Plant(other), 0), 0, "cpu", tensorboard=None)
    with pytest.raises(Exception, match=r"learner.npz: array \d+ is float32\[.*\], expected float32"):
        load_jax_learner(fresh, tmp_path)
    assert zipfile.is_zipfile(tmp_path / "learner.npz")


@pytest.mark.parametrize(
    ("algorithm", "message"),
    [
        ({"name": "PPO", "backend": "sbx"}, "algorithm.backend: sbx learns SAC, TQC, TD3, not PPO"),
        ({"name": "TQC"}, "algorithm.name: TQC is an sbx learner; add backend: sbx"),
        (
            {"name": "SAC", "backend": "sbx", "kwargs": {"optimize_memory_usage": True}},
            "not a keyword argument of SAC",
        ),
        (
            {"name": "SAC", "backend": "sbx", "policy": {"log_std_init": -1}},
            "policy.log_std_init: not with backend",
        ),
        ({"name": "TD3", "backend": "sbx", "policy": {"odd": True}}, "policy.odd: only for .* not TD3 with"),
        (
            {"name": "SAC", "backend": "sbx", "normalize_observations": True, "policy": {"odd": True}},
            "policy.odd: needs normalize_observations: false",
        ),
    ],
)
def test_what_the_sbx_backend_refuses_is_refused_at_loading(algorithm, message):
    config = {"algorithm": algorithm}
    with pytest.raises(ConfigError, match=message):
        build_experiment(config, {}, "x.yaml")


def test_without_sbx_installed_the_backend_is_one_line(monkeypatch, tmp_path):
    import sys

    monkeypatch.setitem(sys.modules, "sbx", None)
    shutil.copy(SMOKE, tmp_path / "smoke.yaml")
    experiment = smoke()
    needs = r"backend: sbx needs the sbx-rl package \(pip install 'rlcontroller\[fast\]'\)"
    with pytest.raises(ConfigError, match=needs):
        build_model(experiment, make_vec_env(Plant(experiment), 0), 0, "cpu", tensorboard=None)
