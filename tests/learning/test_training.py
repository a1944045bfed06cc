import csv
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import REPOSITORY
from typer.testing import CliRunner

from rlcontroller.cli import app
from rlcontroller.config import PlantRandomization, load_experiment
from rlcontroller.control.policy_file import read_policy
from rlcontroller.learning.algorithms import build_model, make_vec_env
from rlcontroller.learning.run_folder import RunFolder
from rlcontroller.learning.training import train
from rlcontroller.physics.plant import Plant

SMOKE = REPOSITORY / "configs" / "testing" / "smoke.yaml"


def smoke(**algorithm):
    experiment = load_experiment(SMOKE)
    settings = experiment.algorithm.model_dump()
    settings.update(algorithm)
    return experiment.model_copy(update={"algorithm": type(experiment.algorithm).model_validate(settings)})


def curve(run_dir: Path) -> list[dict[str, str]]:
    with open(run_dir / "learning_curve.csv", newline="") as handle:
        return list(csv.DictReader(handle))


@pytest.mark.slow
def test_a_run_folder_has_every_file(tmp_path):
    summary = train(
        experiment=smoke(total_steps=600, checkpoint_every=300, eval_every=300), run_dir=tmp_path / "run"
    )
    run = tmp_path / "run"
    for name in (
        "config.yaml",
        "run.json",
        "learning_curve.csv",
        "learning_curve.png",
        "best_model.zip",
        "final_model.zip",
        "best_policy.yaml",
        "best_policy.npz",
        "final_policy.yaml",
        "final_policy.npz",
    ):
        assert (run / name).is_file(), name
    checkpoints = RunFolder(run).checkpoints()
    assert [c.name for c in checkpoints] == ["step_0000000300", "step_0000000600"]
    assert {p.name for p in checkpoints[-1].iterdir()} == {"model.zip", "replay_buffer.pkl", "state.json"}
    rows = curve(run)
    assert [int(r["steps"]) for r in rows] == [0, 300, 600]  # the starting policy is validated too
    assert all(
        np.isfinite(float(r[k]))
        for r in rows
        for k in ("eval_reward", "eval_J1", "eval_J2", "eval_peak_drift_m")
    )
    assert load_experiment(run / "config.yaml").algorithm.total_steps == 600
    assert json.loads((run / "run.json").read_text())["device"] == "cpu"  # the device used, not "auto"
    assert summary.steps == 600 and "run folder" in summary.line()
    policy = read_policy(run, "best", Plant(load_experiment(run / "config.yaml")))
    assert policy.normalizer is None and policy.prior is None and policy.steps == summary.best_steps


def test_runs_are_never_overwritten(tmp_path):
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "keep.txt").write_text("work")
    result = CliRunner().invoke(
        app, ["train", str(SMOKE), "--run-dir", str(tmp_path / "run"), "--total-steps", "10"]
    )
    assert result.exit_code == 2 and "never overwritten" in result.output
    assert (tmp_path / "run" / "keep.txt").read_text() == "work"


@pytest.mark.slow
def test_same_seed_gives_identical_parameters(tmp_path):
    settings = {"total_steps": 300, "checkpoint_every": 300, "eval_every": 300}
    train(experiment=smoke(**settings), run_dir=tmp_path / "a")
    train(experiment=smoke(**settings), run_dir=tmp_path / "b")
    first, second = (np.load(tmp_path / run / "final_policy.npz") for run in ("a", "b"))
    assert first.files == second.files
    for name in first.files:
        assert np.array_equal(first[name], second[name]), name


@pytest.mark.slow
def test_killed_run_resumes_to_the_same_total_with_a_continuous_curve(tmp_path):
    config = yaml.safe_load(SMOKE.read_text())
    config.update(
        {
            key: f"{REPOSITORY}/configs/testing/{value}"
            for key, value in config.items()
            if isinstance(value, str) and value.endswith(".yaml")
        }
    )
    config["algorithm"].update(total_steps=2000, checkpoint_every=250, eval_every=250)
    path = tmp_path / "long.yaml"
    path.write_text(yaml.safe_dump(config))
    run = tmp_path / "run"
    command = [
        sys.executable,
        "-m",
        "rlcontroller",
        "train",
        str(path),
        "--run-dir",
        str(run),
        "--no-progress",
    ]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    deadline = time.time() + 120
    while not (run / "checkpoints" / "step_0000000500").is_dir():
        assert process.poll() is None and time.time() < deadline, process.communicate()[0]
        time.sleep(0.1)
    busy = CliRunner().invoke(app, ["train", "--resume", str(run), "--no-progress"])  # while it trains
    assert busy.exit_code != 0
    assert (
        f"in use by rlc train on {socket.gethostname()} (pid {process.pid}, since"
        in busy.output.splitlines()[-1]
    )
    os.kill(process.pid, signal.SIGKILL)  # its lock stays behind, stale: the resume below takes it over
    process.wait()
    assert (run / ".lock").is_file()
    steps_at_kill = int(RunFolder(run).checkpoints()[-1].name.removeprefix("step_"))
    assert steps_at_kill < 2000
    result = CliRunner().invoke(app, ["train", "--resume", str(run), "--no-progress"])
    assert result.exit_code == 0, result.output
    assert result.output.startswith(f"resuming {run} at step {steps_at_kill:,} of 2,000\n")
    assert "trained: 2000 steps" in result.output
    steps = [int(r["steps"]) for r in curve(run)]
    assert steps == [0, *range(250, 2001, 250)]  # continuous: no gap, no duplicate
    wall = [float(r["wall_time_s"]) for r in curve(run)]
    assert wall == sorted(wall)
    assert RunFolder(run).checkpoints()[-1].name == "step_0000002000"
    assert not (run / ".lock").exists()


@pytest.mark.slow
def test_ctrl_c_saves_a_checkpoint_and_resume_finishes(tmp_path):
    run = tmp_path / "run"
    command = [
        sys.executable,
        "-m",
        "rlcontroller",
        "train",
        str(SMOKE),
        "--run-dir",
        str(run),
        "--total-steps",
        "3000",
        "--no-progress",
    ]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    deadline = time.time() + 120
    while not (run / "checkpoints" / "step_0000000500").is_dir():
        assert process.poll() is None and time.time() < deadline, process.communicate()[0]
        time.sleep(0.1)
    process.send_signal(signal.SIGINT)
    output, _ = process.communicate(timeout=120)
    assert process.returncode == 130, output
    assert "resume with: rlc train --resume" in output and "Traceback" not in output
    interrupted_at = int(RunFolder(run).checkpoints()[-1].name.removeprefix("step_"))
    assert 500 <= interrupted_at < 3000
    assert not any(p.name.startswith(".incomplete") for p in (run / "checkpoints").iterdir())
    summary = train(resume=run)
    assert summary.steps == 3000


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "kwargs"),
    [
        ("PPO", {"n_steps": 64, "batch_size": 32, "n_epochs": 2}),
        ("TD3", {"learning_starts": 50}),
        ("DDPG", {"learning_starts": 50}),
        ("A2C", {"n_steps": 8}),
    ],
)
def test_other_learners_train(tmp_path, name, kwargs):
    summary = train(
        experiment=smoke(
            name=name, kwargs=kwargs, n_envs=2, total_steps=256, checkpoint_every=128, eval_every=128
        ),
        run_dir=tmp_path / name,
    )
    assert summary.steps >= 256 and (tmp_path / name / "final_model.zip").is_file()


@pytest.mark.parametrize(("name", "kwargs"), [("PPO", {"learning_rate": 0.002}), ("SAC", {})])
def test_a_linear_schedule_lowers_the_learning_rate_to_zero_at_total_steps(name, kwargs):
    experiment = smoke(name=name, kwargs=kwargs, learning_rate_schedule="linear")
    plant = Plant(experiment)
    model = build_model(experiment, make_vec_env(plant, 0), 0, "cpu", tensorboard=None)
    start = kwargs.get("learning_rate", 3e-4)  # SAC's own default where the experiment names none
    progress_remaining = np.array([1.0, 0.75, 0.1, 0.0])
    rates = [model.lr_schedule(float(progress)) for progress in progress_remaining]
    np.testing.assert_allclose(rates, start * progress_remaining, rtol=1e-12, atol=0.0)


@pytest.mark.parametrize("backend", ["sb3", "sbx"])
def test_td3_explores_with_the_gaussian_noise_it_is_given(backend):
    if backend == "sbx":
        pytest.importorskip("sbx")
    experiment = smoke(name="TD3", backend=backend, exploration_noise=0.2, kwargs={})
    model = build_model(experiment, make_vec_env(Plant(experiment), 0), 0, "cpu", tensorboard=None)
    noise = model.action_noise
    m = Plant(experiment).building.n_actuators
    np.testing.assert_array_equal(noise._sigma, np.full(m, 0.2))
    np.testing.assert_array_equal(noise._mu, np.zeros(m))
    assert smoke(name="TD3", kwargs={}).algorithm.exploration_noise == 0.0  # none unless asked, as before


@pytest.mark.slow
def test_a_run_normalising_rewards_alone_resumes(tmp_path):
    # without normalize_observations VecNormalize keeps no observation statistics; resume must not need them
    run = tmp_path / "run"
    experiment = smoke(normalize_rewards=True, total_steps=600, checkpoint_every=300, eval_every=300)
    assert train(experiment=experiment, run_dir=run, time_limit_s=0.0).time_limit_reached
    assert (RunFolder(run).checkpoints()[-1] / "vecnormalize.pkl").is_file()
    assert train(resume=run).steps == 600
    assert read_policy(run, "final", Plant(experiment)).normalizer is None


@pytest.mark.slow
def test_observation_normalisation_is_checkpointed_and_used(tmp_path):
    train(
        experiment=smoke(normalize_observations=True, total_steps=300, checkpoint_every=300, eval_every=300),
        run_dir=tmp_path / "run",
    )
    assert (RunFolder(tmp_path / "run").checkpoints()[-1] / "vecnormalize.pkl").is_file()
    policy = read_policy(tmp_path / "run", "final", Plant(load_experiment(tmp_path / "run" / "config.yaml")))
    assert policy.normalizer is not None and np.any(policy.normalizer.mean != 0.0)


@pytest.mark.parametrize(
    ("algorithm", "expected"),
    [
        ("{name: DQN}", "algorithm.name: Input should be 'SAC'"),
        ("{kwargs: {bogus: 1}}", "algorithm.kwargs.bogus: not a keyword argument of SAC"),
        ("{kwargs: {policy_kwargs: {}}}", "algorithm.kwargs.policy_kwargs: set by rlc"),
        ("{kwargs: {batch_size: -1}}", "algorithm.kwargs.batch_size: expected an integer in [1, "),
        ("{kwargs: {gamma: 1.5}}", "algorithm.kwargs.gamma: expected a number in [0.0, 1.0]"),
        (
            "{kwargs: {learning_rate: -0.001}}",
            "algorithm.kwargs.learning_rate: expected a number in [0.0, 1.0]",
        ),
        ("{learning_rate_schedule: cosine}", "algorithm.learning_rate_schedule: Input should be"),
        ("{exploration_noise: 0.1}", "algorithm.exploration_noise: only for TD3 and DDPG"),
        (
            "{name: TD3, exploration_noise: 2}",
            "algorithm.exploration_noise: Input should be less than or equal to 1",
        ),
        ("{name: TD3, kwargs: {action_noise: 0.1}}", "algorithm.kwargs.action_noise: an object, not a value"),
        ("{kwargs: {train_freq: often}}", "algorithm.kwargs: SAC refused them"),
        ("{policy: {activation: swish}}", "algorithm.policy.activation: Input should be"),
    ],
)
def test_bad_algorithm_settings_exit_2_naming_the_key(tmp_path, algorithm, expected):
    path = tmp_path / "bad.yaml"
    path.write_text(f"algorithm: {algorithm}\n")
    result = CliRunner().invoke(app, ["train", str(path), "--run-dir", str(tmp_path / "run")])
    assert result.exit_code == 2, result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and expected in lines[0] and "bad.yaml" in lines[0]
    assert not (tmp_path / "run").exists()


@pytest.mark.slow
def test_time_limit_stops_cleanly_and_the_run_resumes(tmp_path):
    summary = train(
        experiment=smoke(total_steps=600, checkpoint_every=300, eval_every=300),
        run_dir=tmp_path / "run",
        time_limit_s=0.0,
    )
    assert summary.time_limit_reached and summary.steps < 600 and "time limit" in summary.line()
    assert (tmp_path / "run" / "final_model.zip").is_file()
    assert train(resume=tmp_path / "run").steps == 600


@pytest.mark.slow
def test_a_residual_policy_trains_and_starts_at_lqg(tmp_path):
    experiment = smoke(
        name="PPO", kwargs={"n_steps": 64, "batch_size": 64}, n_envs=2, total_steps=128, residual_lqg=True
    )
    experiment = experiment.model_copy(
        update={"sensors": experiment.sensors.model_copy(update={"state_estimate": True})}
    )
    summary = train(experiment=experiment, run_dir=tmp_path / "run")
    policy = read_policy(tmp_path / "run", "final", Plant(experiment))
    assert policy.prior is not None
    # Barely trained, the residual is close to zero: validation J1 is near LQG + ground's.
    assert abs(summary.best["eval_J1"] - summary.best["lqg_ground_J1"]) < 0.1


def test_resuming_a_curve_written_before_new_columns_fills_them_with_nan(tmp_path):
    run = RunFolder(tmp_path)
    old_columns = ["steps", "wall_time_s", "eval_J1"]
    run.curve_path.write_text(",".join(old_columns) + "\n1000,10,0.7\n2000,20,0.6\n3000,30,0.5\n")
    run.truncate_curve(2000)
    rows = run.read_curve()
    assert [row["steps"] for row in rows] == [1000.0, 2000.0] and rows[1]["eval_J1"] == 0.6
    assert np.isnan(rows[0]["lqg_ground_model_J1"])


def test_a_run_that_fails_to_start_leaves_no_run_folder(tmp_path, monkeypatch):
    """As when the progress bar's packages were missing: the error must not leave a half-made run."""
    from stable_baselines3.common import callbacks

    def missing(self):
        raise ImportError("You must install tqdm and rich in order to use the progress bar callback.")

    monkeypatch.setattr(callbacks.ProgressBarCallback, "__init__", missing)
    with pytest.raises(ImportError):
        train(experiment=smoke(total_steps=300), run_dir=tmp_path / "run", progress_bar=True)
    assert not (tmp_path / "run").exists()


@pytest.mark.slow
def test_the_time_limit_counts_this_invocation_not_the_whole_run(tmp_path):
    run = tmp_path / "run"
    train(
        experiment=smoke(total_steps=600, checkpoint_every=300, eval_every=300), run_dir=run, time_limit_s=0.0
    )
    state = RunFolder(run).checkpoints()[-1] / "state.json"
    # a long first session
    state.write_text(json.dumps({**json.loads(state.read_text()), "wall_time_s": 1.0e6}))
    summary = train(resume=run, time_limit_s=1.0e5)
    assert summary.steps == 600 and not summary.time_limit_reached


@pytest.mark.slow
def test_a_stop_at_the_time_limit_prints_the_resume_command(tmp_path):
    run = tmp_path / "run"
    arguments = [
        "train",
        str(SMOKE),
        "--run-dir",
        str(run),
        "--total-steps",
        "3000",
        "--time-limit",
        "0.0001",
    ]
    result = CliRunner().invoke(app, arguments)
    assert result.exit_code == 0, result.output
    assert (
        "stopped at the time limit" in result.output
        and f"resume with: rlc train --resume {run}" in result.output
    )


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory):
    run = tmp_path_factory.mktemp("finished") / "run"
    train(experiment=smoke(total_steps=600, checkpoint_every=300, eval_every=300), run_dir=run)
    return run


@pytest.mark.slow
@pytest.mark.parametrize(
    ("damaged", "expected"),
    [
        ("model.zip", "model.zip: unreadable checkpoint file (ValueError: Error: the file"),
        ("state.json", "state.json: unreadable checkpoint file (JSONDecodeError"),
    ],
)
def test_a_damaged_checkpoint_stops_resume_with_one_line_and_the_way_out(
    finished_run, tmp_path, damaged, expected
):
    run = tmp_path / "run"
    shutil.copytree(finished_run, run)
    config = run / "config.yaml"
    config.write_text(config.read_text().replace("total_steps: 600", "total_steps: 900"))
    previous, newest = RunFolder(run).checkpoints()[-2:]
    (newest / damaged).write_bytes(b"\x00garbage")
    result = CliRunner().invoke(app, ["train", "--resume", str(run), "--no-progress"])
    assert result.exit_code == 2 and "Traceback" not in result.output
    line = result.output.strip().splitlines()[-1]
    assert expected in line and line.endswith(f"delete {newest} to resume from {previous.name}")
    shutil.rmtree(newest)
    assert train(resume=run).steps == 900


@pytest.mark.slow
def test_a_run_stopped_after_its_last_step_before_the_final_save_resumes_to_the_end(finished_run, tmp_path):
    """A stop (a sweep's pool sending SIGTERM, say) between the last checkpoint and the final save leaves a
    checkpoint at the last step and no final model; resuming has no step left to train and must still
    save the final model (it failed on a callback that training had never set up)."""
    run = tmp_path / "run"
    shutil.copytree(finished_run, run)
    for name in ("final_model.zip", "final_policy.yaml", "final_policy.npz"):
        (run / name).unlink()
    assert RunFolder(run).checkpoints()[-1].name == "step_0000000600"
    result = CliRunner().invoke(app, ["train", "--resume", str(run), "--no-progress"])
    assert result.exit_code == 0, result.output
    assert (run / "final_model.zip").is_file() and (run / "final_policy.yaml").is_file()
    assert [int(row["steps"]) for row in curve(run)] == [0, 300, 600]  # nothing trained or validated twice


@pytest.mark.slow
def test_a_damaged_saved_model_stops_evaluate_with_one_line(finished_run, tmp_path):
    run = tmp_path / "run"
    shutil.copytree(finished_run, run)
    (run / "best_policy.npz").write_bytes(b"PK\x03\x04 truncated")
    result = CliRunner().invoke(app, ["evaluate", str(run), "--out", str(tmp_path / "out")])
    lines = result.output.strip().splitlines()
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert lines[-1].startswith(f"error: {run / 'best_policy.npz'}: not readable weights")
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_training_on_randomised_plants_validates_on_fixed_draws(tmp_path):
    experiment = smoke(total_steps=600, checkpoint_every=600, eval_every=300)
    randomization = PlantRandomization(stiffness={"low": 0.7, "high": 1.3}, delay_steps=(0, 1))
    experiment = experiment.model_copy(update={"plant_randomization": randomization})
    experiment = load_experiment_from(experiment, tmp_path)
    train(experiment=experiment, run_dir=tmp_path / "run")
    rows = curve(tmp_path / "run")
    assert len(rows) == 3 and len({row["lqg_J1"] for row in rows}) == 1  # the same plants at every validation
    nominal = curve_of(smoke(total_steps=300, checkpoint_every=300, eval_every=300), tmp_path / "nominal")
    assert rows[0]["lqg_J1"] != nominal[0]["lqg_J1"]  # and not the nominal plant
    assert load_experiment(tmp_path / "run" / "config.yaml").plant_randomization is not None


def load_experiment_from(experiment, folder: Path):
    """Round-trip through YAML, so the randomisation is validated as a user's file would be."""
    path = folder / "randomized.yaml"
    path.write_text(experiment.to_yaml())
    return load_experiment(path)


def curve_of(experiment, run_dir: Path) -> list[dict[str, str]]:
    train(experiment=experiment, run_dir=run_dir)
    return curve(run_dir)


class ScriptedValidator:
    """Validation results in a set order: the reward keeps rising, J1 is best at the third one (the
    first is the starting policy's, at step 0), which makes 10 % of its motions worse than failing safe:
    among those that make none, J1 is best at the sixth."""

    J1 = [0.97, 0.9, 0.5, 0.7, 0.8, 0.6, 0.9, 0.95, 0.99]
    WORSE = [0.0, 0.0, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]

    def __init__(self, plant) -> None:
        self.calls, self.plant, self.prior = 0, plant, None

    def __call__(self, model) -> dict[str, float]:
        self.calls += 1
        j1 = self.J1[self.calls - 1]
        reference = {
            f"{name}_J{i}": 1.0 for name in ("lqg", "lqg_ground", "lqg_ground_model") for i in (1, 2)
        }
        worse = self.WORSE[self.calls - 1]
        results = {"eval_reward": float(self.calls), "eval_peak_drift_m": 0.01, "eval_J1": j1, "eval_J2": j1}
        return results | {"eval_worse": worse} | reference


@pytest.mark.slow
@pytest.mark.parametrize(("select_by", "best_steps"), [("reward", 1024), ("J1", 256), ("standard", 640)])
def test_the_best_model_is_the_validation_chosen_by_select_by(tmp_path, monkeypatch, select_by, best_steps):
    """best_model.zip is the model of the best validation by reward, by mean J1, or by the standard (no motion
    worse than failing safe first; a checkpoint is saved and kept at every validation here, so the two can be
    compared)."""
    from stable_baselines3 import PPO

    from rlcontroller.learning import run_folder, training

    monkeypatch.setattr(run_folder, "KEPT_CHECKPOINTS", 100)
    monkeypatch.setattr(training, "Validator", ScriptedValidator)
    experiment = load_experiment(REPOSITORY / "configs" / "testing" / "tiny.yaml")
    settings = experiment.algorithm.model_dump() | {"total_steps": 1024, "select_by": select_by}
    experiment = experiment.model_copy(
        update={"algorithm": type(experiment.algorithm).model_validate(settings)}
    )
    summary = train(experiment=experiment, run_dir=tmp_path / "run", device="cpu")
    assert summary.best_steps == best_steps
    best = PPO.load(tmp_path / "run" / "best_model.zip", device="cpu")
    saved = PPO.load(tmp_path / "run" / "checkpoints" / f"step_{best_steps:010d}" / "model.zip", device="cpu")
    for ours, theirs in zip(best.policy.parameters(), saved.policy.parameters(), strict=True):
        assert ours.detach().equal(theirs.detach())


class WorseningValidator(ScriptedValidator):
    """The starting policy validates best: every later validation is worse."""

    J1 = [0.4, 0.9, 0.5, 0.7, 0.8, 0.6, 0.9, 0.95, 0.99]


@pytest.mark.slow
def test_a_run_that_only_gets_worse_keeps_its_starting_policy_as_best(tmp_path, monkeypatch):
    """The policy training starts from (for a residual: its prior) is validated at step 0 and is the
    best model while nothing validates better, instead of the least bad of the later ones."""
    from stable_baselines3 import PPO

    from rlcontroller.learning import training

    monkeypatch.setattr(training, "Validator", WorseningValidator)
    experiment = load_experiment(REPOSITORY / "configs" / "testing" / "tiny.yaml")
    settings = experiment.algorithm.model_dump() | {"total_steps": 1024, "select_by": "J1"}
    experiment = experiment.model_copy(
        update={"algorithm": type(experiment.algorithm).model_validate(settings)}
    )
    summary = train(experiment=experiment, run_dir=tmp_path / "run", device="cpu")
    assert summary.best_steps == 0 and summary.best["eval_J1"] == 0.4
    best = PPO.load(tmp_path / "run" / "best_model.zip", device="cpu")
    final = PPO.load(tmp_path / "run" / "final_model.zip", device="cpu")
    assert best.num_timesteps == 0 and final.num_timesteps == 1024
    pairs = zip(best.policy.parameters(), final.policy.parameters(), strict=True)
    assert any(not ours.detach().equal(theirs.detach()) for ours, theirs in pairs)


def tensorboard_scalars(run: Path) -> dict[str, list[tuple[int, float]]]:
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    scalars: dict[str, list[tuple[int, float]]] = {}
    for folder in sorted((run / "tensorboard").iterdir()):
        events = EventAccumulator(str(folder))
        events.Reload()
        for tag in events.Tags()["scalars"]:
            scalars.setdefault(tag, []).extend((e.step, e.value) for e in events.Scalars(tag))
    return scalars


@pytest.mark.slow
def test_tensorboard_gets_the_validation_row_and_a_resume_continues_it(tmp_path):
    pytest.importorskip("tensorboard")
    run = tmp_path / "run"
    train(
        experiment=smoke(total_steps=600, checkpoint_every=300, eval_every=300),
        run_dir=run,
        time_limit_s=0.0,
        tensorboard=True,
    )
    train(resume=run, tensorboard=True)
    scalars = tensorboard_scalars(run)
    rows = curve(run)
    for tag, column in (
        ("validation/J1", "eval_J1"),
        ("validation/J2", "eval_J2"),
        ("validation/lqg_J1", "lqg_J1"),
    ):
        assert [step for step, _ in scalars[tag]] == [int(row["steps"]) for row in rows]
        assert [value for _, value in scalars[tag]] == pytest.approx(
            [float(row[column]) for row in rows], rel=1e-6
        )
    result = CliRunner().invoke(
        app, ["train", str(SMOKE), "--run-dir", str(tmp_path / "off"), "--total-steps", "300"]
    )
    assert result.exit_code == 0, result.output
    assert not (tmp_path / "off" / "tensorboard").exists()  # off unless asked for


def test_tensorboard_without_the_package_is_one_line(tmp_path, monkeypatch):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "tensorboard" else real(name, *a)
    )
    result = CliRunner().invoke(
        app, ["train", str(SMOKE), "--run-dir", str(tmp_path / "run"), "--tensorboard"]
    )
    assert result.exit_code == 2
    assert result.output.strip() == (
        "error: --tensorboard: the tensorboard package is not installed (pip install "
        "'rlcontroller[tensorboard]')"
    )
    assert not (tmp_path / "run").exists()


@pytest.mark.slow
def test_training_under_generated_wind_validates_on_wind(tmp_path):
    """A wind generator in the excitation: the env and validation load the floors, not the ground."""
    from rlcontroller.config import ExcitationConfig, WindGeneratorConfig

    wind = WindGeneratorConfig(duration=(20.0, 30.0), speed=(15.0, 25.0))
    experiment = smoke(total_steps=400, eval_every=200, checkpoint_every=200)
    experiment = experiment.model_copy(
        update={"excitation": ExcitationConfig(generator=wind, validation_motions=2, validation_seed=3)}
    )
    summary = train(experiment=experiment, run_dir=tmp_path / "run")
    assert summary.steps >= 400 and np.isfinite(summary.best["eval_J1"])
    from rlcontroller.learning.validation import Validator

    validator = Validator(Plant(experiment))
    assert all(
        motion.floor_forces is not None and not motion.acceleration.any() for motion in validator.motions
    )


def test_select_by_j1_plus_j2_weighs_floor_accelerations_alike():
    """A validation that cuts drift a little more by raising floor accelerations wins on J1, loses on
    J1+J2."""
    from rlcontroller.learning.training import selection_score

    drift_only = {"eval_reward": -1.0, "eval_J1": 0.30, "eval_J2": 0.90}
    balanced = {"eval_reward": -2.0, "eval_J1": 0.32, "eval_J2": 0.60}
    assert selection_score(drift_only, "J1") > selection_score(balanced, "J1")
    assert selection_score(balanced, "J1+J2") > selection_score(drift_only, "J1+J2")
    assert selection_score(drift_only, "reward") > selection_score(balanced, "reward")


def test_auto_takes_the_cpu_for_rlc_s_mlp_policies_even_where_cuda_is_visible(tmp_path, monkeypatch):
    """A GPU steps rlc's small MLPs slower than the CPU (docs/training.md): with CUDA reported visible, a run
    on `auto` still trains on the CPU (stable-baselines3's own `auto` would take the GPU: here, one that is
    not there)."""
    import torch

    from rlcontroller.learning.training import training_device

    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    train(
        experiment=smoke(total_steps=200, checkpoint_every=200, eval_every=200),
        run_dir=tmp_path / "run",
        device="auto",
    )
    assert json.loads((tmp_path / "run" / "run.json").read_text())["device"] == "cpu"
    assert training_device("cuda") == "cuda" and training_device("cpu") == "cpu"


def test_selection_by_the_standard_takes_a_stable_closed_loop_first():
    """`select_by: standard`: an unstable checkpoint (the check's stability criterion fails) is never
    preferred, however few motions it makes worse; among stable ones, fewer motions worse, then lower J1 +
    J2."""
    from rlcontroller.learning.training import selection_score

    def row(radius, worse, j):
        return {"eval_spectral_radius": radius, "eval_worse": worse, "eval_J1": j, "eval_J2": j}

    unstable, stable_worse, stable_good = row(1.01, 0.0, 0.1), row(0.99, 0.5, 1.0), row(0.99, 0.0, 0.6)
    assert selection_score(unstable, "standard") < selection_score(stable_worse, "standard")
    assert selection_score(stable_worse, "standard") < selection_score(stable_good, "standard")
    assert selection_score(unstable, "J1") > selection_score(stable_good, "J1")  # other modes read no radius
