"""Run folders: one training run's files, never overwritten, with checkpoints that resume.

A run folder holds:
    config.yaml            the resolved experiment (with command-line overrides applied)
    run.json               command line, package versions, seed, device used, host, start time
    checkpoints/step_N/    model.zip, replay_buffer.pkl (off-policy), vecnormalize.pkl (if used),
                           or with `backend: sbx` learner.npz/.json, replay_buffer.npz, vecnormalize.npz
                           (no pickle, `learning.jax_learners`);
                           state.json (steps, wall time, best validation); written to a
                           temporary folder and renamed, so the newest complete one is always valid
    learning_curve.csv     steps, wall_time_s, episode_reward, eval_reward, eval_peak_drift_m,
                           eval_J1, eval_J2, eval_worse (validation on held-out generated motions), the
                           references lqg_J1, lqg_J2, lqg_ground_J1, lqg_ground_J2,
                           lqg_ground_model_J1, lqg_ground_model_J2 on the same motions
    best_model.zip         the best validation so far (algorithm.select_by); final_model.zip at the end
                           (stable-baselines3 files, for this run's own use: they unpickle; none with sbx)
    best_policy.yaml/.npz  the same policies as data (`control.policy_file`): what evaluate, check and
    final_policy.yaml/.npz export read, never unpickling
    best_check.yaml        the safety check's verdict on the best policy (`rlc train`, `evaluation.safety`)
    learning_curve.png     written at the end; tensorboard/ with `rlc train --tensorboard`
"""

from __future__ import annotations

import csv
import datetime as dt
import importlib.metadata
import json
import os
import platform
import shutil
import socket
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rlcontroller.config import Experiment, load_experiment
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.control.policy_file import write_policy
from rlcontroller.files import atomic_savefig, atomic_write, check_new_folder
from rlcontroller.learning.jax_learners import is_jax_model, save_jax_learner
from rlcontroller.physics.plant import Plant

CURVE_COLUMNS = (
    "steps",
    "wall_time_s",
    "episode_reward",
    "eval_reward",
    "eval_peak_drift_m",
    "eval_J1",
    "eval_J2",
    "eval_worse",
    "lqg_J1",
    "lqg_J2",
    "lqg_ground_J1",
    "lqg_ground_J2",
    "lqg_ground_model_J1",
    "lqg_ground_model_J2",
    "eval_spectral_radius",  # measured for `select_by: standard` only (nan otherwise)
)
KEPT_CHECKPOINTS = 2


def package_versions() -> dict[str, str]:
    names = (
        "rlcontroller",
        "stable-baselines3",
        "sbx-rl",
        "jax",
        "gymnasium",
        "torch",
        "numpy",
        "scipy",
        "control",
    )
    names += ("pydantic",)
    versions = {"python": platform.python_version()}
    for name in names:
        try:
            versions[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return versions


@dataclass
class TrainingState:
    """What a run carries from one checkpoint to the next, and what this invocation learned on the way.

    Saved in each checkpoint's state.json (with the step count): `wall_time_s` (s, trained in all
    invocations), `best` (the best validation row so far, `algorithm.select_by`) and `best_steps`
    (its step). `time_limit_reached` and `stopped_by_validation` say why this invocation stopped."""

    wall_time_s: float = 0.0
    best: dict[str, float] | None = None
    best_steps: int | None = None
    time_limit_reached: bool = False
    stopped_by_validation: bool = False

    def to_json(self, steps: int) -> dict[str, Any]:
        return {
            "wall_time_s": self.wall_time_s,
            "best_steps": self.best_steps,
            "best": self.best,
            "steps": steps,
        }

    @classmethod
    def from_json(cls, saved: Any) -> TrainingState:
        """The state a checkpoint saved (a ValueError when it is not one)."""
        if not isinstance(saved, dict) or not isinstance(saved.get("wall_time_s"), int | float):
            raise ValueError("expected a mapping with wall_time_s")
        best, best_steps = saved.get("best"), saved.get("best_steps")
        if not (best is None or isinstance(best, dict)) or not (
            best_steps is None or isinstance(best_steps, int)
        ):
            raise ValueError("expected best as a mapping and best_steps as a whole number")
        return cls(wall_time_s=float(saved["wall_time_s"]), best=best, best_steps=best_steps)


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
        return load_experiment(self.path / "config.yaml", self_contained=True)

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

    def save_checkpoint(self, model, state: TrainingState) -> Path:
        """Write model, replay buffer, normalisation statistics and state; rename when complete."""
        steps = int(model.num_timesteps)
        final = self.checkpoint_root / f"step_{steps:010d}"
        if final.exists():
            return final
        temporary = self.checkpoint_root / f".incomplete_step_{steps:010d}"
        shutil.rmtree(temporary, ignore_errors=True)
        temporary.mkdir(parents=True)
        try:
            if is_jax_model(model):
                save_jax_learner(model, temporary)
            else:
                model.save(temporary / "model.zip")
                if hasattr(model, "replay_buffer") and model.replay_buffer is not None:
                    model.save_replay_buffer(temporary / "replay_buffer.pkl")
                normalize = model.get_vec_normalize_env()
                if normalize is not None:
                    normalize.save(str(temporary / "vecnormalize.pkl"))
            (temporary / "state.json").write_text(json.dumps(state.to_json(steps)) + "\n")
            os.rename(temporary, final)
        except BaseException:
            shutil.rmtree(temporary, ignore_errors=True)  # the newest complete checkpoint stays the newest
            raise
        for old in self.checkpoints()[:-KEPT_CHECKPOINTS]:
            shutil.rmtree(old, ignore_errors=True)
        return final

    def append_curve(self, row: dict[str, float]) -> None:
        with open(self.curve_path, "a", newline="") as handle:
            csv.writer(handle).writerow([row.get(c, float("nan")) for c in CURVE_COLUMNS])

    def truncate_curve(self, steps: int) -> None:
        """Drop rows logged after the checkpoint being resumed (they will be logged again); columns
        added since the run started are filled with nan."""
        with open(self.curve_path, newline="") as handle:
            rows = list(csv.DictReader(handle))
        kept = [list(CURVE_COLUMNS)] + [
            [row.get(column, "nan") for column in CURVE_COLUMNS]
            for row in rows
            if int(float(row["steps"])) <= steps
        ]
        temporary = self.curve_path.with_name(self.curve_path.name + ".tmp")
        with open(temporary, "w", newline="") as handle:
            csv.writer(handle).writerows(kept)
        os.replace(temporary, self.curve_path)

    def read_curve(self) -> list[dict[str, float]]:
        with open(self.curve_path, newline="") as handle:
            return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(handle)]

    def save_model(self, model, name: str, controller: PolicyController, plant: Plant) -> Path:
        """Save the model `name` (best or final) atomically: NAME_model.zip (and its
        .vecnormalize.pkl if used) for this run (not with sbx: no pickle), and `controller`, its policy, as
        data."""
        if is_jax_model(model):
            return write_policy(controller, plant, self.path, name)
        temporary = self.path / f".{name}_model.tmp.zip"
        model.save(temporary)
        os.replace(temporary, self.path / f"{name}_model.zip")
        normalize = model.get_vec_normalize_env()
        if normalize is not None:
            statistics = self.path / f".{name}_model.vecnormalize.tmp"
            normalize.save(str(statistics))
            os.replace(statistics, self.path / f"{name}_model.vecnormalize.pkl")
        return write_policy(controller, plant, self.path, name)


def default_run_dir(experiment: Experiment) -> Path:
    stamp = dt.datetime.now().strftime("%Y%m%d-%H%M%S")
    return Path("runs") / f"{experiment.name}-seed{experiment.seed}-{stamp}"


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
