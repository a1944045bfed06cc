"""The 76-story wind benchmark under generated wind: uncontrolled, passive TMD, LQG + wind model
along its trade-off, and a learned controller; comfort tables and per-floor RMS accelerations.

Usage: python studies/wind/wind_benchmark.py OUT [--run RUN_FOLDER] [--records configs/loads/wind_76.yaml]

The experiment is configs/experiments/seventy_six_story_atmd.yaml (active tuned mass damper on floor 75);
the records are the wind suite (generated; the experiment's own design wind is a separate generator).
LQG + wind model is designed with the experiment's effort weights (force and stroke) times each of
EFFORT_MULTIPLIERS, so that a learned controller is compared at its own stroke and power, not at one
weight. Writes OUT/wind_comfort.md (per mean speed), OUT/wind_tradeoff.png and OUT/wind_rms_per_floor.png.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from rlcontroller.assets import CONFIGS  # noqa: E402
from rlcontroller.config import load_experiment, load_wind_suite  # noqa: E402
from rlcontroller.control.controllers import LQGController  # noqa: E402
from rlcontroller.control.lqg import design_lqg_wind_model  # noqa: E402
from rlcontroller.control.policy_file import read_policy  # noqa: E402
from rlcontroller.evaluation.evaluation import PASSIVE, evaluate  # noqa: E402
from rlcontroller.evaluation.tables import markdown_table  # noqa: E402
from rlcontroller.files import atomic_savefig, atomic_write  # noqa: E402
from rlcontroller.physics.motions.excitation import STANDARD_GRAVITY  # noqa: E402
from rlcontroller.physics.motions.wind import wind_suite  # noqa: E402
from rlcontroller.physics.plant import Plant  # noqa: E402

EFFORT_MULTIPLIERS = (0.1, 0.3, 1.0, 3.0, 10.0, 30.0)
CHOSEN = "LQG + wind model"  # the experiment's own weights (multiplier 1)
COLUMNS = (
    "rms_acceleration",
    "rms_acceleration_top",
    "peak_acceleration_top_mg",
    "rms_top_displacement",
    "stroke_rms_m",
    "stroke_m",
    "power_rms_W",
)


def lqg_at(plant: Plant, multiplier: float) -> LQGController:
    """LQG + wind model with the reward's force and stroke weights times `multiplier`."""
    reward = plant.experiment.reward
    terms = [
        term.model_copy(update={"weight": term.weight * multiplier})
        if term.quantity in ("force", "stroke")
        else term
        for term in reward.terms
    ]
    name = CHOSEN if multiplier == 1.0 else f"{CHOSEN} x{multiplier:g}"
    design = design_lqg_wind_model(plant.design, reward.model_copy(update={"terms": terms}))
    return LQGController(design, plant.design, name)


def per_speed_table(evaluation, speeds: list[float]) -> pd.DataFrame:
    """Mean over each speed's records (and floors, devices) of every comfort and device column."""
    frame = evaluation.metrics.copy()
    frame["speed"] = frame["record"].str.extract(r"wind_([0-9.]+)ms")[0].astype(float)
    frame = frame[frame["metric"].isin(COLUMNS)]
    per_index = frame.groupby(["speed", "controller", "metric", "index"], sort=False)["value"].mean()
    table = per_index.groupby(["speed", "controller", "metric"], sort=False).mean().unstack("metric")
    return table[[c for c in COLUMNS if c in table.columns]].loc[speeds]


def rms_per_floor(evaluation, controller: str, records: list[str]) -> np.ndarray:
    """RMS absolute acceleration per floor (milli-g), the mean over `records`."""
    values = [np.std(evaluation.responses[controller, r].absolute_acceleration[1:], axis=0) for r in records]
    return np.mean(values, axis=0) / STANDARD_GRAVITY * 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--run", type=Path, help="a run folder of the experiment (its best policy)")
    parser.add_argument("--records", type=Path, default=CONFIGS / "loads" / "wind_76.yaml")
    arguments = parser.parse_args()
    experiment = load_experiment(CONFIGS / "experiments" / "seventy_six_story_atmd.yaml")
    plant = Plant(experiment)
    suite = load_wind_suite(arguments.records)
    motions = wind_suite(suite, plant.building)
    controllers = [lqg_at(plant, multiplier) for multiplier in EFFORT_MULTIPLIERS]
    if arguments.run is not None:
        controllers.append(read_policy(arguments.run, "best", plant, "learned"))
    evaluation = evaluate(plant, motions, controllers, "wind", include_optimal=False)
    table = per_speed_table(evaluation, suite.speeds)
    arguments.out.mkdir(parents=True, exist_ok=True)
    flat = table.set_axis([f"{speed:g} m/s, {name}" for speed, name in table.index]).rename_axis(
        "wind, controller"
    )
    text = markdown_table(flat)
    atomic_write(arguments.out / "wind_comfort.md", text + "\n")
    print(text)

    figure, axis = plt.subplots(figsize=(6, 4))
    summary = evaluation.summary()
    sweep = summary.loc[[c.name for c in controllers if c.name.startswith(CHOSEN)]].sort_values(
        "stroke_rms_m"
    )
    axis.plot(
        sweep["stroke_rms_m"],
        sweep["rms_acceleration"],
        "o-",
        label="LQG + wind model (effort weights swept)",
    )
    axis.plot(
        summary.loc[PASSIVE, "stroke_rms_m"],
        summary.loc[PASSIVE, "rms_acceleration"],
        "s",
        label="passive TMD",
    )
    if "learned" in summary.index:
        axis.plot(
            summary.loc["learned", "stroke_rms_m"],
            summary.loc["learned", "rms_acceleration"],
            "*",
            ms=12,
            label="learned",
        )
    axis.set(
        xlabel="RMS stroke of the damper (m)", ylabel="RMS floor acceleration, controlled / uncontrolled"
    )
    axis.legend(fontsize=8)
    atomic_savefig(figure, arguments.out / "wind_tradeoff.png")

    figure, axes = plt.subplots(1, len(suite.speeds), figsize=(5 * len(suite.speeds), 6), sharey=True)
    floors = np.arange(1, plant.bare.building.n_floors + 1)
    for axis, speed in zip(np.atleast_1d(axes), suite.speeds, strict=True):
        records = [r for r in evaluation.records if r.startswith(f"wind_{speed:g}ms")]
        for name in ("uncontrolled", PASSIVE, CHOSEN, *(["learned"] if "learned" in summary.index else [])):
            axis.plot(rms_per_floor(evaluation, name, records)[: floors.size], floors, label=name)
        axis.set(xlabel="RMS acceleration (milli-g)", title=f"{speed:g} m/s at 10 m")
    np.atleast_1d(axes)[0].set(ylabel="floor")
    np.atleast_1d(axes)[0].legend(fontsize=8)
    atomic_savefig(figure, arguments.out / "wind_rms_per_floor.png")


if __name__ == "__main__":
    main()
