"""Run every controller on every record in the same simulator and collect J1-J4.

The uncontrolled building is simulated as whole records with the precomputed step map; LQG and
the RL policy run through the same environment (same sensors, noise realisation per record, force
clipping); the clairvoyant optimal controller is the reference no causal controller can pass.
"""

from __future__ import annotations

import csv
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from rlcontroller.config import Experiment, KanaiTajimiConfig
from rlcontroller.controllers import Controller, rollout
from rlcontroller.dynamics import Response, simulate
from rlcontroller.env import BuildingEnv
from rlcontroller.excitation import GroundMotion, MotionError, for_control_step, generate_suite, read_at2, scale_to_pga
from rlcontroller.lqg import optimal_response
from rlcontroller.metrics import METRICS, j_metrics

PROJECT_MANIFEST = Path(__file__).resolve().parents[1] / "records" / "manifest.csv"
RECORDS_VARIABLE = "RLC_RECORDS"
OPTIMAL = "optimal (clairvoyant)"
LQG_VARIANTS = ("LQG", "LQG + ground", "LQG + ground model")  # names in every table
PREVIEW_SECONDS = (0.0, 0.02, 0.04, 0.1, 0.2, 0.5, 1.0, None)
SYNTHETIC_LABEL = "SYNTHETIC suite (7 seeded Kanai-Tajimi motions), not the paper's records"
RECORDS_LABEL = "PEER NGA-West2 records (7)"
SYNTHETIC_SEED = 2024


def read_manifest(folder: Path | None = None) -> list[dict[str, str]]:
    """Rows of the project's record manifest (or of `folder`/manifest.csv when that is the only one)."""
    path = PROJECT_MANIFEST if PROJECT_MANIFEST.is_file() else (folder or Path(".")) / "manifest.csv"
    if not path.is_file():
        raise MotionError(f"{path}: record manifest not found")
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def load_records(folder: Path, scale_pga_g: float | None = None) -> list[GroundMotion]:
    """The seven records from `folder`, as recorded or scaled to a PGA (in g)."""
    folder = Path(folder)
    rows = read_manifest(folder)
    missing = [row for row in rows if not (folder / row["file"]).is_file()]
    if missing:
        names = ", ".join(row["file"] for row in missing)
        rsns = ", ".join(row["rsn"] for row in missing)
        raise MotionError(
            f"{folder}: {len(missing)} of {len(rows)} records missing: {names}; download them from "
            f"https://ngawest2.berkeley.edu (RSN {rsns}) into that folder, see records/README.md"
        )
    motions = [read_at2(folder / row["file"]) for row in rows]
    if scale_pga_g is not None:
        motions = [scale_to_pga(m, scale_pga_g * 9.80665) for m in motions]
    return motions


def synthetic_suite(count: int = 7, seed: int = SYNTHETIC_SEED) -> list[GroundMotion]:
    """The embedded default: seeded Kanai-Tajimi motions, strong enough to matter (PGA 2-6 m/s^2)."""
    config = KanaiTajimiConfig(duration=(25.0, 40.0), pga=(2.0, 6.0), strong_duration=(6.0, 15.0))
    motions = generate_suite(config, count, seed)
    return [GroundMotion(f"synthetic_KT_{i + 1}", m.dt, m.acceleration, synthetic=True) for i, m in enumerate(motions)]


def choose_motions(records: Path | None, scale_pga_g: float | None = None) -> tuple[list[GroundMotion], str]:
    """The records in `records` (or $RLC_RECORDS); without either, the labelled synthetic suite."""
    folder = records or (Path(os.environ[RECORDS_VARIABLE]) if os.environ.get(RECORDS_VARIABLE) else None)
    if folder is None:
        motions = synthetic_suite()
        if scale_pga_g is not None:
            motions = [scale_to_pga(m, scale_pga_g * 9.80665) for m in motions]
        return motions, SYNTHETIC_LABEL
    label = RECORDS_LABEL + (f", scaled to PGA {scale_pga_g:g} g" if scale_pga_g is not None else ", as recorded")
    return load_records(folder, scale_pga_g), label


def uncontrolled_response(env: BuildingEnv, motion: GroundMotion) -> Response:
    """Whole-record simulation of the bare building with the env's step map."""
    samples, substeps = for_control_step(motion, env.control_dt)
    return simulate(env.building, env.step_map(substeps), samples)


@dataclass
class Evaluation:
    """J-metrics in long form (controller, record, metric, index, value) and the responses."""

    label: str
    experiment: Experiment
    metrics: pd.DataFrame
    responses: dict[tuple[str, str], Response] = field(repr=False)
    seconds: float = 0.0

    @property
    def controllers(self) -> list[str]:
        return list(dict.fromkeys(self.metrics["controller"]))

    @property
    def records(self) -> list[str]:
        return list(dict.fromkeys(self.metrics["record"]))

    def summary(self) -> pd.DataFrame:
        """Mean over records, then over stories (actuators for J3), per controller."""
        per_index = self.metrics.groupby(["controller", "metric", "index"], sort=False)["value"].mean()
        table = per_index.groupby(["controller", "metric"], sort=False).mean().unstack("metric")
        return table.loc[self.controllers, ["J1", "J2", "J3", "J4"]]


def evaluate(
    experiment: Experiment,
    motions: list[GroundMotion],
    controllers: list[Controller],
    label: str,
    include_optimal: bool = True,
) -> Evaluation:
    """Run the uncontrolled building, every controller and (optionally) the optimal reference."""
    start = time.perf_counter()
    env = BuildingEnv(experiment)
    rows: list[dict] = []
    responses: dict[tuple[str, str], Response] = {}
    for number, motion in enumerate(motions):
        bare = uncontrolled_response(env, motion)
        responses["uncontrolled", motion.name] = bare
        results = [("uncontrolled", bare)]
        for controller in controllers:
            results.append((controller.name, rollout(env, motion, controller, seed=number)[0]))
        if include_optimal:
            results.append((OPTIMAL, optimal_response(experiment, motion)))
        for name, result in results:
            responses[name, motion.name] = result
            for metric, values in j_metrics(result, bare).items():
                rows.extend(
                    {"controller": name, "record": motion.name, "metric": metric, "index": i + 1, "value": float(v)}
                    for i, v in enumerate(values)
                )
    return Evaluation(label, experiment, pd.DataFrame(rows), responses, time.perf_counter() - start)


def percent_better(candidate: float, reference: float) -> float:
    """How much smaller `candidate` is than `reference`, in percent (positive = better)."""
    return float(100.0 * (1.0 - candidate / reference)) if reference else float("nan")


def mean_metric(evaluation: Evaluation, controller: str, metric: str) -> float:
    frame = evaluation.metrics
    chosen = frame[(frame["controller"] == controller) & (frame["metric"] == metric)]
    return float(np.mean(chosen.groupby("index")["value"].mean()))


def lqg_sweep(
    experiment: Experiment,
    motions: list[GroundMotion],
    label: str,
    multipliers: np.ndarray,
    known_ground: bool = False,
) -> pd.DataFrame:
    """LQG's trade-off: mean J1..J4 for the reward's force weights times each multiplier."""
    from rlcontroller.lqg import LQGController, design_lqg

    env = BuildingEnv(experiment)
    if not any(term.quantity == "force" for term in experiment.reward.terms):
        raise ValueError("the reward has no force term to sweep")
    rows = []
    for multiplier in multipliers:
        terms = [
            term.model_copy(update={"weight": term.weight * multiplier}) if term.quantity == "force" else term
            for term in experiment.reward.terms
        ]
        reward = experiment.reward.model_copy(update={"terms": terms})
        controller = LQGController(design_lqg(experiment, known_ground=known_ground, reward=reward), env)
        result = evaluate(experiment, motions, [controller], label, include_optimal=False)
        summary = result.summary().loc["LQG"]
        rows.append(
            {"force_weight_multiplier": float(multiplier), **{m: float(summary[m]) for m in ("J1", "J2", "J3", "J4")}}
        )
    return pd.DataFrame(rows)


def preview_study(
    experiment: Experiment,
    motions: list[GroundMotion],
    seconds: tuple[float | None, ...] = PREVIEW_SECONDS,
) -> pd.DataFrame:
    """How much knowing the coming ground motion is worth: mean J1..J4 of full-state LQR with the
    optimal feed-forward on the next `s` seconds of ground motion (None: the whole record).

    Preview 0 is full-state LQR without ground knowledge; a causal controller has no preview, so
    the rows bound what better sensing (full state) and prediction of the ground can buy.
    """
    env = BuildingEnv(experiment)
    dt = experiment.simulation.control_dt
    bare = [uncontrolled_response(env, motion) for motion in motions]
    rows = []
    for horizon in seconds:
        steps = None if horizon is None else round(horizon / dt)
        values = {metric: [] for metric in METRICS}
        for motion, uncontrolled in zip(motions, bare, strict=True):
            metrics = j_metrics(optimal_response(experiment, motion, preview=steps), uncontrolled)
            for metric in METRICS:
                values[metric].append(metrics[metric])
        rows.append(
            {
                "preview_s": float("inf") if steps is None else steps * dt,
                **{metric: float(np.mean(np.mean(values[metric], axis=0))) for metric in METRICS},
            }
        )
    return pd.DataFrame(rows)
