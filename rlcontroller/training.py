"""Training with stable-baselines3: run folders, validation, checkpoints that resume.

A run folder is never overwritten. It holds:
    config.yaml            the resolved experiment (with command-line overrides applied)
    run.json               command line, package versions, seed, device, host, start time
    checkpoints/step_N/    model.zip, replay_buffer.pkl (off-policy), vecnormalize.pkl (if used),
                           state.json (steps, wall time, best validation reward); written to a
                           temporary folder and renamed, so the newest complete one is always valid
    learning_curve.csv     steps, wall_time_s, episode_reward, eval_reward, eval_peak_drift_m,
                           eval_J1, eval_J2 (validation on held-out generated motions), and the
                           references lqg_J1, lqg_J2, lqg_ground_J1, lqg_ground_J2,
                           lqg_ground_model_J1, lqg_ground_model_J2 on the same motions
    best_model.zip         the best validation reward so far; final_model.zip at the end
    learning_curve.png     written at the end; tensorboard/ when tensorboard is installed

Validation runs the deterministic policy on `excitation.validation_motions` motions drawn with
`excitation.validation_seed` (never the real records) and reports J1/J2 against the
uncontrolled building on the same motions.
"""

from __future__ import annotations

import csv
import datetime as dt
import functools
import importlib.metadata
import importlib.util
import inspect
import json
import os
import platform
import shutil
import signal
import socket
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from rlcontroller.config import ConfigError, Experiment, load_experiment
from rlcontroller.controllers import PolicyController, Uncontrolled, rollout
from rlcontroller.env import BuildingEnv
from rlcontroller.excitation import generate_suite
from rlcontroller.files import atomic_savefig, atomic_write, check_new_folder
from rlcontroller.lqg import LQGController, LQGPrior, design_lqg, design_lqg_ground_model
from rlcontroller.metrics import j_metrics, peak

CURVE_COLUMNS = (
    "steps",
    "wall_time_s",
    "episode_reward",
    "eval_reward",
    "eval_peak_drift_m",
    "eval_J1",
    "eval_J2",
    "lqg_J1",
    "lqg_J2",
    "lqg_ground_J1",
    "lqg_ground_J2",
    "lqg_ground_model_J1",
    "lqg_ground_model_J2",
)
ACTIVATIONS = {"relu": "ReLU", "tanh": "Tanh", "elu": "ELU", "leaky_relu": "LeakyReLU", "gelu": "GELU"}
RESERVED_KWARGS = {
    "policy",
    "env",
    "policy_kwargs",
    "seed",
    "device",
    "tensorboard_log",
    "verbose",
    "_init_setup_model",
}
KEPT_CHECKPOINTS = 2
# (low, high, integer) for the learners' common numeric keyword arguments.
NUMERIC_KWARGS = {
    "gamma": (0.0, 1.0, False),
    "tau": (0.0, 1.0, False),
    "gae_lambda": (0.0, 1.0, False),
    "batch_size": (1, 2**31, True),
    "buffer_size": (1, 2**40, True),
    "n_steps": (1, 2**31, True),
    "n_epochs": (1, 2**31, True),
    "learning_starts": (0, 2**40, True),
}


def algorithm_class(name: str) -> type:
    import stable_baselines3

    return getattr(stable_baselines3, name)


def check_algorithm(experiment: Experiment) -> None:
    """Refuse keyword arguments the learner does not take, naming the file and key."""
    algorithm = experiment.algorithm
    file, prefix = experiment.origin("algorithm")
    accepted = set(inspect.signature(algorithm_class(algorithm.name).__init__).parameters) - {"self"}
    for key, value in algorithm.kwargs.items():
        where = f"{file}: {prefix + '.' if prefix else ''}kwargs.{key}"
        if key in RESERVED_KWARGS:
            raise ConfigError(f"{where}: set by rlc (use 'policy:', 'seed' or --device instead)")
        if key not in accepted:
            options = ", ".join(sorted(accepted - RESERVED_KWARGS))
            raise ConfigError(f"{where}: not a keyword argument of {algorithm.name}; expected one of: {options}")
        if key in NUMERIC_KWARGS and not _in_range(value, *NUMERIC_KWARGS[key]):
            low, high, integer = NUMERIC_KWARGS[key]
            kind = "an integer" if integer else "a number"
            raise ConfigError(f"{where}: expected {kind} in [{low}, {high}], got {value!r}")


def _in_range(value: Any, low: float, high: float, integer: bool) -> bool:
    if isinstance(value, bool) or not isinstance(value, int | float) or (integer and not isinstance(value, int)):
        return False
    return low <= value <= high


class ResidualAction(gym.ActionWrapper):
    """The agent's action is added to a prior controller's action computed from the observation."""

    def __init__(self, env: gym.Env, prior) -> None:
        super().__init__(env)
        self.prior = prior
        self._observation = None

    def reset(self, **kwargs):
        observation, info = self.env.reset(**kwargs)
        self._observation = observation
        return observation, info

    def step(self, action):
        observation, reward, terminated, truncated, info = self.env.step(self.action(action))
        self._observation = observation
        return observation, reward, terminated, truncated, info

    def action(self, action):
        return np.clip(np.clip(action, -1.0, 1.0) + self.prior(self._observation), -1.0, 1.0)


def make_env(experiment: Experiment) -> gym.Env:
    """One training env: a BuildingEnv, wrapped as a residual on LQG if configured."""
    env = BuildingEnv(experiment)
    return ResidualAction(env, LQGPrior(experiment)) if experiment.algorithm.residual_lqg else env


def make_vec_env(experiment: Experiment, seed: int):
    """The training vector env: `n_envs` BuildingEnvs (dummy or subprocess) with episode statistics."""
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecMonitor, VecNormalize

    factories = [functools.partial(make_env, experiment) for _ in range(experiment.algorithm.n_envs)]
    if experiment.algorithm.vec_env == "subproc" and len(factories) > 1:
        vec_env = SubprocVecEnv(factories)
    else:
        vec_env = DummyVecEnv(factories)
    vec_env.seed(seed)
    vec_env = VecMonitor(vec_env)
    if experiment.algorithm.normalize_observations:
        vec_env = VecNormalize(vec_env, norm_obs=True, norm_reward=False)
    return vec_env


def build_model(experiment: Experiment, vec_env, seed: int, device: str, tensorboard: Path | None):
    import torch

    algorithm = experiment.algorithm
    check_algorithm(experiment)
    policy_kwargs = {
        "net_arch": list(algorithm.policy.net_arch),
        "activation_fn": getattr(torch.nn, ACTIVATIONS[algorithm.policy.activation]),
    }
    if algorithm.policy.log_std_init is not None:
        policy_kwargs["log_std_init"] = algorithm.policy.log_std_init
    try:
        return algorithm_class(algorithm.name)(
            "MlpPolicy",
            vec_env,
            policy_kwargs=policy_kwargs,
            seed=seed,
            device=device,
            tensorboard_log=str(tensorboard) if tensorboard else None,
            verbose=0,
            **algorithm.kwargs,
        )
    except (TypeError, ValueError, AssertionError) as error:
        file, prefix = experiment.origin("algorithm")
        message = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise ConfigError(
            f"{file}: {prefix + '.' if prefix else ''}kwargs: {algorithm.name} refused them: {message}"
        ) from None


def package_versions() -> dict[str, str]:
    names = ("rlcontroller", "stable-baselines3", "gymnasium", "torch", "numpy", "scipy", "control", "pydantic")
    versions = {"python": platform.python_version()}
    for name in names:
        try:
            versions[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return versions


class RunFolder:
    """The files of one run; see the module docstring."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.checkpoint_root = path / "checkpoints"
        self.curve_path = path / "learning_curve.csv"

    @classmethod
    def create(cls, path: Path, experiment: Experiment, device: str) -> RunFolder:
        """A new run folder with the resolved config and run.json (`device`: the one the model is on)."""
        check_new_folder(path, "run")
        path.mkdir(parents=True, exist_ok=True)
        run = cls(path)
        atomic_write(path / "config.yaml", experiment.to_yaml())
        details = {
            "command": sys.argv,
            "seed": experiment.seed,
            "device": device,
            "host": socket.gethostname(),
            "started": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
            "versions": package_versions(),
        }
        atomic_write(path / "run.json", json.dumps(details, indent=2) + "\n")
        with open(run.curve_path, "w", newline="") as handle:
            csv.writer(handle).writerow(CURVE_COLUMNS)
        return run

    def experiment(self) -> Experiment:
        return load_experiment(self.path / "config.yaml")

    def checkpoints(self) -> list[Path]:
        """Complete checkpoints, oldest first."""
        if not self.checkpoint_root.is_dir():
            return []
        found = [
            p
            for p in self.checkpoint_root.iterdir()
            if p.is_dir() and p.name.startswith("step_") and (p / "state.json").is_file()
        ]
        return sorted(found, key=lambda p: int(p.name.removeprefix("step_")))

    def save_checkpoint(self, model, state: dict[str, Any]) -> Path:
        """Write model, replay buffer, normalisation statistics and state; rename when complete."""
        steps = int(model.num_timesteps)
        final = self.checkpoint_root / f"step_{steps:010d}"
        if final.exists():
            return final
        temporary = self.checkpoint_root / f".incomplete_step_{steps:010d}"
        shutil.rmtree(temporary, ignore_errors=True)
        temporary.mkdir(parents=True)
        try:
            model.save(temporary / "model.zip")
            if hasattr(model, "replay_buffer") and model.replay_buffer is not None:
                model.save_replay_buffer(temporary / "replay_buffer.pkl")
            normalize = model.get_vec_normalize_env()
            if normalize is not None:
                normalize.save(str(temporary / "vecnormalize.pkl"))
            (temporary / "state.json").write_text(json.dumps({**state, "steps": steps}) + "\n")
            os.rename(temporary, final)
        except BaseException:
            shutil.rmtree(temporary, ignore_errors=True)  # the newest complete checkpoint stays the newest
            raise
        for old in self.checkpoints()[:-KEPT_CHECKPOINTS]:
            shutil.rmtree(old, ignore_errors=True)
        return final

    def append_curve(self, row: dict[str, float]) -> None:
        with open(self.curve_path, "a", newline="") as handle:
            csv.writer(handle).writerow([row[c] for c in CURVE_COLUMNS])

    def truncate_curve(self, steps: int) -> None:
        """Drop rows logged after the checkpoint being resumed (they will be logged again); columns
        added since the run started are filled with nan."""
        with open(self.curve_path, newline="") as handle:
            rows = list(csv.DictReader(handle))
        kept = [list(CURVE_COLUMNS)] + [
            [row.get(column, "nan") for column in CURVE_COLUMNS] for row in rows if int(float(row["steps"])) <= steps
        ]
        temporary = self.curve_path.with_name(self.curve_path.name + ".tmp")
        with open(temporary, "w", newline="") as handle:
            csv.writer(handle).writerows(kept)
        os.replace(temporary, self.curve_path)

    def read_curve(self) -> list[dict[str, float]]:
        with open(self.curve_path, newline="") as handle:
            return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(handle)]

    def save_model(self, model, name: str) -> Path:
        """Save `name`.zip (and `name`.vecnormalize.pkl if used) atomically."""
        temporary = self.path / f".{name}.tmp.zip"
        model.save(temporary)
        os.replace(temporary, self.path / f"{name}.zip")
        normalize = model.get_vec_normalize_env()
        if normalize is not None:
            statistics = self.path / f".{name}.vecnormalize.tmp"
            normalize.save(str(statistics))
            os.replace(statistics, self.path / f"{name}.vecnormalize.pkl")
        return self.path / f"{name}.zip"


class Validator:
    """Runs a policy on the held-out generated validation motions."""

    def __init__(self, experiment: Experiment) -> None:
        self.env = BuildingEnv(experiment)
        excitation = experiment.excitation
        self.motions = generate_suite(excitation.generator, excitation.validation_motions, excitation.validation_seed)
        self.prior = LQGPrior(experiment) if experiment.algorithm.residual_lqg else None
        bare = Uncontrolled(self.env.building.n_actuators)
        self.uncontrolled = [rollout(self.env, motion, bare)[0] for motion in self.motions]
        self.reference = {}
        designs = {
            "lqg": lambda: design_lqg(experiment),
            "lqg_ground": lambda: design_lqg(experiment, known_ground=True),
            "lqg_ground_model": lambda: design_lqg_ground_model(experiment),
        }
        for prefix, design in designs.items():
            try:
                lqg = self.run(LQGController(design(), self.env))
            except ValueError:  # a reward LQG cannot be designed for
                lqg = {"eval_J1": float("nan"), "eval_J2": float("nan")}
            self.reference |= {f"{prefix}_J1": lqg["eval_J1"], f"{prefix}_J2": lqg["eval_J2"]}

    def __call__(self, model) -> dict[str, float]:
        policy = PolicyController(model, self.env.force_limits, model.get_vec_normalize_env(), prior=self.prior)
        return self.run(policy) | self.reference

    def run(self, controller) -> dict[str, float]:
        rewards, peaks, j1, j2 = [], [], [], []
        for index, motion in enumerate(self.motions):
            result, reward = rollout(self.env, motion, controller, seed=index)
            metrics = j_metrics(result, self.uncontrolled[index])
            rewards.append(reward)
            peaks.append(float(np.max(peak(result.drift))))
            j1.append(float(np.mean(metrics["J1"])))
            j2.append(float(np.mean(metrics["J2"])))
        return {
            "eval_reward": float(np.mean(rewards)),
            "eval_peak_drift_m": float(np.mean(peaks)),
            "eval_J1": float(np.mean(j1)),
            "eval_J2": float(np.mean(j2)),
        }


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
    state: dict[str, Any],
    time_limit_s: float | None,
):
    from stable_baselines3.common.callbacks import BaseCallback

    algorithm = experiment.algorithm

    class TrainingCallback(BaseCallback):
        def _on_training_start(self) -> None:
            self.started = self.session_start = time.perf_counter()

        def wall_time(self) -> float:
            return state["wall_time_s"] + time.perf_counter() - self.session_start

        def _on_step(self) -> bool:
            steps, previous = self.num_timesteps, self.num_timesteps - self.training_env.num_envs
            if steps // algorithm.eval_every > previous // algorithm.eval_every:
                self.validate()
            if steps // algorithm.checkpoint_every > previous // algorithm.checkpoint_every:
                self.checkpoint()
            if time_limit_s is not None and time.perf_counter() - self.started >= time_limit_s:
                state["time_limit_reached"] = True
                return False
            return not stop.requested

        def validate(self) -> None:
            result = validator(self.model)
            episodes = [info["r"] for info in self.model.ep_info_buffer]
            row = {"steps": self.num_timesteps, "wall_time_s": round(self.wall_time(), 2)}
            row["episode_reward"] = float(np.mean(episodes)) if episodes else float("nan")
            row.update(result)
            run.append_curve(row)
            if result["eval_reward"] > state["best_eval_reward"]:
                state.update(best_eval_reward=result["eval_reward"], best_steps=self.num_timesteps, best=result)
                run.save_model(self.model, "best_model")

        def checkpoint(self) -> None:
            state["wall_time_s"] = self.wall_time()
            self.session_start = time.perf_counter()
            run.save_checkpoint(self.model, state)

    return TrainingCallback()


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

    def line(self) -> str:
        rate = self.steps / self.wall_time_s if self.wall_time_s > 0 else float("nan")
        verb = (
            "interrupted" if self.interrupted else "stopped at the time limit" if self.time_limit_reached else "trained"
        )
        text = f"{verb}: {self.steps} steps in {self.wall_time_s:.0f} s ({rate:.0f} steps/s)"
        if self.beat_lqg_at:
            first = self.beat_lqg_at
            text += f"; validation J1 first below LQG's at step {first['steps']:.0f} ({first['wall_time_s']:.0f} s)"
        if self.best:
            text += (
                f"; best validation reward {self.best['eval_reward']:.2f} at step {self.best_steps} "
                f"(J1 {self.best['eval_J1']:.3f}, J2 {self.best['eval_J2']:.3f}; LQG J1 {self.best['lqg_J1']:.3f}, "
                f"J2 {self.best['lqg_J2']:.3f}; LQG + ground J1 {self.best['lqg_ground_J1']:.3f}; "
                f"LQG + ground model J1 {self.best['lqg_ground_model_J1']:.3f})"
            )
        return text + f"; run folder: {self.run_dir}"


def default_run_dir(experiment: Experiment) -> Path:
    stamp = dt.datetime.now().strftime("%Y%m%d-%H%M%S")
    return Path("runs") / f"{experiment.name}-seed{experiment.seed}-{stamp}"


def train(
    experiment: Experiment | None = None,
    run_dir: Path | None = None,
    resume: Path | None = None,
    device: str = "auto",
    progress_bar: bool = False,
    time_limit_s: float | None = None,
) -> TrainingSummary:
    """Train a new run (from `experiment`) or resume one (`resume` = its run folder).

    With `time_limit_s`, training stops (as finished, and resumable) once this call has trained
    that long; a new run that fails before its first checkpoint leaves no run folder.
    """
    import torch

    if resume is not None:
        run = RunFolder(resume)
        if not (resume / "config.yaml").is_file():
            raise ConfigError(f"{resume}: not a run folder (no config.yaml)")
        experiment = run.experiment()
    else:
        assert experiment is not None
        check_algorithm(experiment)
        run = RunFolder(run_dir or default_run_dir(experiment))
        check_new_folder(run.path, "run", " (use --resume)")
    torch.set_num_threads(experiment.algorithm.torch_threads)
    vec_env = make_vec_env(experiment, experiment.seed)
    created = False
    try:
        model, state = _start(run, experiment, vec_env, device, resume is not None)
        created = resume is None
        stop = StopRequest()
        previous_handlers = {s: signal.signal(s, stop) for s in (signal.SIGINT, signal.SIGTERM)}
        callback = _callback(run, experiment, Validator(experiment), stop, state, time_limit_s)
        remaining = experiment.algorithm.total_steps - model.num_timesteps
        try:
            if remaining > 0:
                model.learn(remaining, callback=callback, reset_num_timesteps=False, progress_bar=progress_bar)
        finally:
            for number, handler in previous_handlers.items():
                signal.signal(number, handler)
    except BaseException:
        if created and not run.checkpoints() and not (run.path / "best_model.zip").exists():
            shutil.rmtree(run.path, ignore_errors=True)  # nothing trained: leave no half-made run folder
        raise
    if remaining > 0:
        callback.checkpoint()
    if not stop.requested:
        run.save_model(model, "final_model")
        if state["best"] is None:
            callback.validate()
        plot_learning_curve(run)
    vec_env.close()
    beat = [row for row in run.read_curve() if row["eval_J1"] < row["lqg_J1"]]
    return TrainingSummary(
        run.path,
        int(model.num_timesteps),
        state["wall_time_s"],
        state["best"],
        state["best_steps"],
        stop.requested,
        bool(state.get("time_limit_reached")),
        beat[0] if beat else None,
    )


def _start(run: RunFolder, experiment: Experiment, vec_env, device: str, resume: bool) -> tuple[Any, dict[str, Any]]:
    """The model and training state: from the newest checkpoint when resuming, else new (and the
    run folder is created, recording the device the model is on)."""
    state: dict[str, Any] = {"wall_time_s": 0.0, "best_eval_reward": -float("inf"), "best_steps": None, "best": None}
    checkpoints = run.checkpoints()
    if resume and checkpoints:
        model = _load_checkpoint(experiment, checkpoints, vec_env, device)
        state.update(_read_state(checkpoints))
        state.pop("steps", None)
        state.pop("time_limit_reached", None)
        run.truncate_curve(model.num_timesteps)
        return model, state
    tensorboard = run.path / "tensorboard" if importlib.util.find_spec("tensorboard") else None
    model = build_model(experiment, vec_env, experiment.seed, device, tensorboard)
    if resume:
        run.truncate_curve(0)
    else:
        RunFolder.create(run.path, experiment, str(model.device))
    return model, state


def _unreadable(checkpoints: list[Path], path: Path, error: Exception) -> ConfigError:
    detail = (str(error).splitlines() or [""])[0][:120] or type(error).__name__
    hint = f"; delete {checkpoints[-1]} to resume from {checkpoints[-2].name}" if len(checkpoints) > 1 else ""
    return ConfigError(f"{path}: unreadable checkpoint file ({type(error).__name__}: {detail}){hint}")


def _read_state(checkpoints: list[Path]) -> dict[str, Any]:
    path = checkpoints[-1] / "state.json"
    try:
        state = json.loads(path.read_text())
        if not isinstance(state, dict) or not isinstance(state.get("wall_time_s"), int | float):
            raise ValueError("expected a mapping with wall_time_s")
        return state
    except (OSError, UnicodeDecodeError, ValueError) as error:
        raise _unreadable(checkpoints, path, error) from None


def _load_checkpoint(experiment: Experiment, checkpoints: list[Path], vec_env, device: str):
    from stable_baselines3.common.vec_env import VecNormalize

    checkpoint = checkpoints[-1]
    path = checkpoint / "vecnormalize.pkl"
    try:
        if path.is_file():
            statistics = VecNormalize.load(str(path), vec_env.venv)
            vec_env.obs_rms, vec_env.ret_rms = statistics.obs_rms, statistics.ret_rms
        path = checkpoint / "model.zip"
        model = algorithm_class(experiment.algorithm.name).load(path, env=vec_env, device=device)
        path = checkpoint / "replay_buffer.pkl"
        if path.is_file():
            model.load_replay_buffer(path)
    except Exception as error:  # a damaged file: zip, pickle or torch errors of any kind
        raise _unreadable(checkpoints, path, error) from None
    return model


def load_policy(model_path: Path):
    """A saved model of a run folder, its observation normaliser and its prior (or None), on the CPU."""
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    model_path = Path(model_path)
    experiment = load_experiment(model_path.parent / "config.yaml")
    statistics = model_path.with_name(model_path.stem + ".vecnormalize.pkl")
    normalize = None
    path = model_path
    try:
        model = algorithm_class(experiment.algorithm.name).load(model_path, device="cpu")
        if statistics.is_file():
            path = statistics
            normalize = VecNormalize.load(str(statistics), DummyVecEnv([functools.partial(BuildingEnv, experiment)]))
            normalize.training = False
    except Exception as error:  # a damaged file: zip, pickle or torch errors of any kind
        detail = (str(error).splitlines() or [""])[0][:120] or type(error).__name__
        raise ConfigError(f"{path}: cannot load the saved model ({type(error).__name__}: {detail})") from None
    prior = LQGPrior(experiment) if experiment.algorithm.residual_lqg else None
    return model, normalize, prior


def plot_learning_curve(run: RunFolder) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = run.read_curve()
    steps = [r["steps"] for r in rows]
    figure, (reward_axis, metric_axis) = plt.subplots(1, 2, figsize=(13, 4))
    reward_axis.plot(steps, [r["episode_reward"] for r in rows], label="training episodes (mean of last 100)")
    reward_axis.plot(steps, [r["eval_reward"] for r in rows], "o-", label="validation motions")
    reward_axis.set(xlabel="environment steps", ylabel="episode reward", title="Reward")
    reward_axis.legend(fontsize=8)
    j1, j2 = [r["eval_J1"] for r in rows], [r["eval_J2"] for r in rows]
    metric_axis.plot(steps, j1, "o-", label="J1 (peak drift ratio)")
    metric_axis.plot(steps, j2, "s-", label="J2 (peak acceleration ratio)")
    metric_axis.axhline(1.0, color="grey", linewidth=0.8, linestyle="--")
    references = [
        ("lqg_J1", "LQG J1", "tab:blue", ":"),
        ("lqg_J2", "LQG J2", "tab:orange", ":"),
        ("lqg_ground_J1", "LQG + ground J1", "tab:blue", "-."),
        ("lqg_ground_model_J1", "LQG + ground model J1", "tab:green", "-."),
    ]
    shown = [1.0, *j1, *j2]
    for key, label, colour, style in references if rows else []:
        metric_axis.axhline(rows[-1][key], color=colour, linewidth=1.0, linestyle=style, label=label)
        shown.append(rows[-1][key])
    finite = [value for value in shown if np.isfinite(value)]
    margin = 0.05 * (max(finite) - min(finite) or 1.0)
    metric_axis.set_ylim(min(finite) - margin, max(finite) + margin)  # every reference line inside
    metric_axis.set(
        xlabel="environment steps", ylabel="controlled / uncontrolled", title="Validation (generated motions)"
    )
    metric_axis.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8)
    figure.tight_layout()
    path = atomic_savefig(figure, run.path / "learning_curve.png", dpi=110)
    plt.close(figure)
    return path
