"""Training with stable-baselines3: a new run or a resumed one, validation, checkpoints, stopping.

The run folder (`run_folder`) keeps everything; validation (`validation`) runs on held-out
generated motions. Ctrl-C or SIGTERM stops at the next step with a checkpoint; a time limit stops
the same way after that many seconds of this call.
"""

from __future__ import annotations

import importlib.util
import json
import shutil
import signal
import sys
import threading
import time
from collections.abc import Callable
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rlcontroller.config import ConfigError, Experiment
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.files import check_new_folder, folder_lock
from rlcontroller.learning.algorithms import algorithm_class, build_model, make_vec_env
from rlcontroller.learning.jax_learners import UnreadableFile, is_jax_model, jax_device, load_jax_learner
from rlcontroller.learning.run_folder import RunFolder, TrainingState, default_run_dir, plot_learning_curve
from rlcontroller.learning.sb3_models import policy_controller
from rlcontroller.learning.validation import Validator
from rlcontroller.physics.plant import Plant


class StopRequest:
    """First Ctrl-C (or SIGTERM) asks training to stop at the next step; a second one aborts."""

    def __init__(self) -> None:
        self.requested = False

    def __call__(self, signum, frame) -> None:
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True
        print("\nstopping: saving a checkpoint (Ctrl-C again to abort without saving)", file=sys.stderr)


def _callback(
    run: RunFolder,
    experiment: Experiment,
    validator: Validator,
    stop: StopRequest,
    state: TrainingState,
    time_limit_s: float | None,
    on_validation: Callable[[dict[str, float]], bool] | None,
):
    from stable_baselines3.common.callbacks import BaseCallback

    algorithm = experiment.algorithm

    class TrainingCallback(BaseCallback):
        def _on_training_start(self) -> None:
            self.started = self.session_start = time.perf_counter()
            self.keep_going = True
            self.previous_steps = self.model.num_timesteps
            # the starting policy is a candidate too: a residual's is its prior
            if self.model.num_timesteps == 0:
                self.validate()

        def wall_time(self) -> float:
            return state.wall_time_s + time.perf_counter() - self.session_start

        def _on_step(self) -> bool:
            steps, previous = self.num_timesteps, self.previous_steps  # RandomSearch: many steps per call
            self.previous_steps = steps
            if steps // algorithm.eval_every > previous // algorithm.eval_every:
                self.validate()
            if steps // algorithm.checkpoint_every > previous // algorithm.checkpoint_every:
                self.checkpoint()
            if time_limit_s is not None and time.perf_counter() - self.started >= time_limit_s:
                state.time_limit_reached = True
                return False
            return self.keep_going and not stop.requested

        def policy(self) -> PolicyController:
            return policy_controller(self.model, validator.prior, self.model.get_vec_normalize_env())

        def validate(self) -> None:
            policy = self.policy()
            result = validator(policy)
            episodes = [info["r"] for info in self.model.ep_info_buffer]
            row = {"steps": self.num_timesteps, "wall_time_s": round(self.wall_time(), 2)}
            row["episode_reward"] = float(np.mean(episodes)) if episodes else float("nan")
            row.update(result)
            run.append_curve(row)
            for key, value in row.items():  # TensorBoard's scalars when it is on; dropped otherwise
                if key not in ("steps", "wall_time_s"):
                    self.logger.record(f"validation/{key.removeprefix('eval_')}", value)
            self.logger.dump(self.num_timesteps)
            if on_validation is not None and not on_validation(row):
                state.stopped_by_validation = self.keep_going = False
            best = state.best
            if best is None or selection_score(result, algorithm.select_by) > selection_score(
                best, algorithm.select_by
            ):
                state.best_steps, state.best = self.num_timesteps, result
                run.save_model(self.model, "best", policy, validator.plant)

        def checkpoint(self) -> None:
            state.wall_time_s = self.wall_time()
            self.session_start = time.perf_counter()
            run.save_checkpoint(self.model, state)

    return TrainingCallback()


def selection_score(result: dict[str, float], select_by: str) -> float:
    """Higher is better: the validation reward, or minus the validation J1 or J1 + J2 (`algorithm.select_by`),
    or for `standard` a stable closed loop first, then minus the share of motions worse than the building
    failed safe, then J1 + J2."""
    if select_by == "standard":  # one motion in a hundred outweighs any J1 + J2 (each at most about 2)
        unstable = result.get("eval_spectral_radius", 0.0) >= 1.0  # the check's stability criterion fails
        return -1.0e6 * unstable - 1000.0 * result["eval_worse"] - result["eval_J1"] - result["eval_J2"]
    if select_by == "reward":
        return result["eval_reward"]
    return -result["eval_J1"] - (result["eval_J2"] if select_by == "J1+J2" else 0.0)


@dataclass
class TrainingSummary:
    run_dir: Path
    steps: int
    wall_time_s: float
    best: dict[str, float] | None
    best_steps: int | None
    interrupted: bool
    time_limit_reached: bool = False
    beat_lqg_at: dict[str, float] | None = None
    stopped_by_validation: bool = False  # `on_validation` asked to stop (a pruned trial)

    def line(self) -> str:
        rate = self.steps / self.wall_time_s if self.wall_time_s > 0 else float("nan")
        verb = (
            "interrupted"
            if self.interrupted
            else "stopped at the time limit"
            if self.time_limit_reached
            else "stopped early by its validation (pruned)"
            if self.stopped_by_validation
            else "trained"
        )
        text = f"{verb}: {self.steps} steps in {self.wall_time_s:.0f} s ({rate:.0f} steps/s)"
        if self.beat_lqg_at:
            first = self.beat_lqg_at
            at = f"step {first['steps']:.0f} ({first['wall_time_s']:.0f} s)"
            text += f"; validation J1 first below LQG's at {at}"
        if self.best:
            best = self.best
            references = [
                f"{name} {best[key]:.3f}"
                for name, key in (
                    ("LQG J1", "lqg_J1"),
                    ("J2", "lqg_J2"),
                    ("LQG + ground J1", "lqg_ground_J1"),
                    ("LQG + ground model J1", "lqg_ground_model_J1"),
                )
                if np.isfinite(best[key])  # none for dampers, which LQG cannot command
            ]
            scores = ", ".join([f"J1 {best['eval_J1']:.3f}", f"J2 {best['eval_J2']:.3f}", *references])
            reward = f"validation reward {best['eval_reward']:.2f} ({scores})"
            text += f"; best model at step {self.best_steps}: {reward}"
        return text + f"; run folder: {self.run_dir}"


def train(
    *,
    experiment: Experiment | None = None,
    run_dir: Path | None = None,
    resume: Path | None = None,
    device: str = "auto",
    progress_bar: bool = False,
    time_limit_s: float | None = None,
    on_validation: Callable[[dict[str, float]], bool] | None = None,
    tensorboard: bool = False,
) -> TrainingSummary:
    """Train a new run (from `experiment`) or resume one (`resume` = its run folder) on `device` (`auto`: the
    CPU, `training_device`).

    With `time_limit_s`, training stops (as finished, and resumable) once this call has trained
    that long; a new run that fails before its first checkpoint leaves no run folder.
    `on_validation(row)` sees each learning-curve row as it is logged; returning False stops
    training the same way (a tuner's pruner). With `tensorboard`, stable-baselines3's logger also
    writes TensorBoard event files to RUN/tensorboard, the validation row included.
    """
    if tensorboard and importlib.util.find_spec("tensorboard") is None:
        raise ConfigError(
            "--tensorboard: the tensorboard package is not installed (pip install "
            "'rlcontroller[tensorboard]')"
        )
    with ExitStack() as held:  # the run folder's lock, from the start (resume) or its creation (new)
        if resume is not None and (resume / "config.yaml").is_file():
            held.enter_context(folder_lock(resume, "rlc train"))
        device = training_device(device)
        return _train(
            experiment, run_dir, resume, device, progress_bar, time_limit_s, on_validation, tensorboard, held
        )


def training_device(device: str) -> str:
    """`auto` is the CPU: every rlc policy is a small MLP, which a GPU steps slower (one H100: `rlc train
    configs/five_story.yaml --total-steps 100000` 47 s with cuda, 37 s with cpu; stable-baselines3 warns the
    same for PPO's MLP policies; docs/training.md). `cuda` is honoured as asked."""
    return "cpu" if device == "auto" else device


def _train(
    experiment: Experiment | None,
    run_dir: Path | None,
    resume: Path | None,
    device: str,
    progress_bar: bool,
    time_limit_s: float | None,
    on_validation: Callable[[dict[str, float]], bool] | None,
    tensorboard: bool,
    held: ExitStack,
) -> TrainingSummary:
    import torch

    if resume is not None:
        run = RunFolder(resume)
        if not (resume / "config.yaml").is_file():
            raise ConfigError(f"{resume}: not a run folder (no config.yaml)")
        experiment = experiment or run.experiment()
    else:
        assert experiment is not None
        run = RunFolder(run_dir or default_run_dir(experiment))
        check_new_folder(run.path, "run", " (use --resume)")
    if not experiment.command_labels():
        where = experiment.origin("actuators")[0]
        raise ConfigError(
            f"{where}: nothing to command (no actuators, no active devices): a passive building is not "
            "trained"
        )
    if experiment.algorithm.backend == "sbx" and device != "cpu":
        raise ConfigError(
            f"--device {device}: backend: sbx runs where JAX runs (its CPU build, rlcontroller[fast]); "
            "leave --device out or use backend: sb3"
        )
    torch.set_num_threads(experiment.algorithm.torch_threads)
    plant = Plant(experiment)
    if plant.fe_model is not None and experiment.plant.opensees.train_on == "reduced":
        # learned on the FE model's reduced one, judged on the FE model (evaluate --config)
        plant = plant.design
    vec_env = make_vec_env(plant, experiment.seed)
    created = False
    try:
        model, state = _start(run, experiment, vec_env, device, resume is not None, tensorboard)
        created = resume is None
        if created:
            held.enter_context(folder_lock(run.path, "rlc train"))
        policy_controller(model, None)  # a policy that cannot be saved as data stops before training
        stop = StopRequest()
        signals = (
            (signal.SIGINT, signal.SIGTERM) if threading.current_thread() is threading.main_thread() else ()
        )
        previous_handlers = {s: signal.signal(s, stop) for s in signals}  # none in a worker thread (Dask)
        callback = _callback(run, experiment, Validator(plant), stop, state, time_limit_s, on_validation)
        remaining = max(experiment.algorithm.total_steps - model.num_timesteps, 0)
        # also with nothing left (stopped after its last step, before the final save): sets the callback up
        try:
            model.learn(remaining, callback=callback, reset_num_timesteps=False, progress_bar=progress_bar)
        finally:
            for number, handler in previous_handlers.items():
                signal.signal(number, handler)
    except BaseException:
        if created and not run.checkpoints() and not (run.path / "best_policy.yaml").exists():
            shutil.rmtree(run.path, ignore_errors=True)  # nothing trained: leave no half-made run folder
        raise
    if remaining > 0:
        callback.checkpoint()
    if not stop.requested:
        run.save_model(model, "final", callback.policy(), plant)
        if state.best is None:
            callback.validate()
        plot_learning_curve(run)
    vec_env.close()
    beat = [row for row in run.read_curve() if row["eval_J1"] < row["lqg_J1"]]
    return TrainingSummary(
        run_dir=run.path,
        steps=int(model.num_timesteps),
        wall_time_s=state.wall_time_s,
        best=state.best,
        best_steps=state.best_steps,
        interrupted=stop.requested,
        time_limit_reached=state.time_limit_reached,
        beat_lqg_at=beat[0] if beat else None,
        stopped_by_validation=state.stopped_by_validation,
    )


def _start(
    run: RunFolder, experiment: Experiment, vec_env, device: str, resume: bool, tensorboard: bool
) -> tuple[Any, TrainingState]:
    """The model and training state: from the newest checkpoint when resuming, else new (and the
    run folder is created, recording the device the model is on)."""
    log = run.path / "tensorboard" if tensorboard else None
    checkpoints = run.checkpoints()
    if resume and checkpoints:
        model = _load_checkpoint(experiment, checkpoints, vec_env, device)
        model.tensorboard_log = str(log) if log else None  # this invocation's choice, not the saved one
        state = _read_state(checkpoints)
        run.truncate_curve(model.num_timesteps)
        return model, state
    state = TrainingState()
    model = build_model(experiment, vec_env, experiment.seed, device, tensorboard=log)
    if resume:
        run.truncate_curve(0)
    else:
        RunFolder.create(run.path, experiment, jax_device() if is_jax_model(model) else str(model.device))
    return model, state


def _unreadable(checkpoints: list[Path], path: Path, error: Exception) -> ConfigError:
    detail = (str(error).splitlines() or [""])[0][:120] or type(error).__name__
    hint = f"; delete {checkpoints[-1]} to resume from {checkpoints[-2].name}" if len(checkpoints) > 1 else ""
    return ConfigError(f"{path}: unreadable checkpoint file ({type(error).__name__}: {detail}){hint}")


def _read_state(checkpoints: list[Path]) -> TrainingState:
    path = checkpoints[-1] / "state.json"
    try:
        return TrainingState.from_json(json.loads(path.read_text()))
    except (OSError, UnicodeDecodeError, ValueError) as error:
        raise _unreadable(checkpoints, path, error) from None


def _load_checkpoint(experiment: Experiment, checkpoints: list[Path], vec_env, device: str):
    from stable_baselines3.common.vec_env import VecNormalize

    checkpoint = checkpoints[-1]
    if experiment.algorithm.backend == "sbx":  # arrays into a fresh model of the same config: no pickle
        model = build_model(experiment, vec_env, experiment.seed, device, tensorboard=None)
        try:
            load_jax_learner(model, checkpoint)
        except UnreadableFile as unreadable:
            raise _unreadable(checkpoints, unreadable.path, unreadable.error) from None
        return model
    path = checkpoint / "vecnormalize.pkl"
    try:
        if path.is_file():
            statistics = VecNormalize.load(str(path), vec_env.venv)
            vec_env.ret_rms = statistics.ret_rms
            if vec_env.norm_obs:  # VecNormalize keeps no observation statistics without it
                vec_env.obs_rms = statistics.obs_rms
        path = checkpoint / "model.zip"
        model = algorithm_class(experiment.algorithm.name).load(path, env=vec_env, device=device)
        path = checkpoint / "replay_buffer.pkl"
        if path.is_file():
            model.load_replay_buffer(path)
    except Exception as error:  # a damaged file: zip, pickle or torch errors of any kind
        raise _unreadable(checkpoints, path, error) from None
    return model
