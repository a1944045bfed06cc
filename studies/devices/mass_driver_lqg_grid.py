"""Study: LQG + ground model of an active-mass-driver experiment over its force and stroke weights.

Usage: python studies/devices/mass_driver_lqg_grid.py [CONFIG] [--records ../shared/records ...]
           [--force 0.3 1 3] [--stroke 1 2 3 5 7 10 20] [--frequencies 0.85 0.9 1 1.1 1.15]
           [--plot tradeoff.png] [--runs RUN ...]

`rlc compare lqg --sweep` moves LQG along its force weight; for a mass driver the quantity that
binds is the stroke. This designs LQG + ground model (on the design model, the driver as tuned) for
every pair of multipliers of the reward's force and stroke weights, and runs each on plants whose
drivers are detuned: frequency times each factor (the spring times its square), as built. Per
suite of records (folders, as `rlc evaluate --records` takes) it prints the nominal driver's mean
J1, J2 and peak stroke (mean over records of each record's largest |stroke|), and J1 per frequency
with its mean and worst; the row with the least mean is marked: the robust choice on that suite.
`--plot` draws the first suite's nominal trade-off, J1 against peak stroke, with the learned
controllers of `--runs` (run folders evaluated on that suite: their evaluation/summary.csv) marked.
docs/devices.md's tables are this script's output for configs/experiments/five_story_amd.yaml.
"""

from __future__ import annotations

import argparse
import itertools
import sys
from pathlib import Path

import numpy as np

from rlcontroller.config import ConfigError, Experiment, PlantConfig, load_experiment
from rlcontroller.control.controllers import LQGController
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.evaluation.evaluation import PASSIVE, evaluate, mean_metric, scaled_weights
from rlcontroller.files import atomic_savefig
from rlcontroller.physics.motions.excitation import Load
from rlcontroller.physics.motions.records import choose_motions
from rlcontroller.physics.plant import Plant

REPOSITORY = Path(__file__).resolve().parents[2]


def grid(experiment: Experiment, force: list[float], stroke: list[float]) -> list[LQGController]:
    """LQG + ground model designed on the design model for each pair of weight multipliers."""
    if not any(term.quantity == "stroke" for term in experiment.reward.terms):
        raise ConfigError(f"{experiment.name}: the reward has no stroke term to sweep")
    design = Plant(experiment).design
    return [
        LQGController(
            design_lqg_ground_model(
                design, reward=scaled_weights(experiment.reward, {"force": f, "stroke": s})
            ),
            design,
            f"LQG + ground model, force x{f:g}, stroke x{s:g}",
        )
        for f, s in itertools.product(force, stroke)
    ]


def detuned(experiment: Experiment, frequency: float) -> Plant:
    """The plant whose mass devices' frequencies are `frequency` times their tuned ones."""
    part = PlantConfig.model_validate({"devices": {"frequency": frequency}})
    return Plant(experiment.model_copy(update={"plant": part}))


def table(
    experiment: Experiment,
    controllers: list[LQGController],
    motions: list[Load],
    frequencies: list[float],
) -> list[dict[str, float | str]]:
    """One row per weight pair (and the passive driver): nominal J1, J2, peak stroke; J1 per frequency."""
    names = [PASSIVE, *(controller.name for controller in controllers)]
    rows: dict[str, dict[str, float | str]] = {
        name: {"controller": name, "J2": 0.0, "peak stroke (m)": 0.0} for name in names
    }
    for frequency in frequencies:
        evaluation = evaluate(detuned(experiment, frequency), motions, controllers, "", include_optimal=False)
        for name, row in rows.items():
            row[f"J1 x{frequency:g}"] = mean_metric(evaluation, name, "J1")
            if frequency == 1.0:
                row["J2"] = mean_metric(evaluation, name, "J2")
                row["peak stroke (m)"] = mean_metric(evaluation, name, "stroke_m")
    for row in rows.values():
        values = [row[f"J1 x{frequency:g}"] for frequency in frequencies]
        row["mean J1"], row["worst J1"] = float(np.mean(values)), float(np.max(values))
    return list(rows.values())


def markdown(rows: list[dict[str, float | str]]) -> str:
    best = min(rows[1:], key=lambda row: row["mean J1"])["controller"]
    columns = list(rows[0])
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for row in rows:
        mark = " (least mean J1)" if row["controller"] == best else ""
        cells = [f"{row[c]:.3f}" if isinstance(row[c], float) else f"{row[c]}{mark}" for c in columns]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def plot(rows: list[dict[str, float | str]], runs: list[Path], out: Path) -> None:
    """J1 against peak stroke (nominal driver): one line per force multiplier, the passive driver and
    each run's learned controller (its evaluation/summary.csv row "RL") marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import pandas as pd

    figure, axis = plt.subplots(figsize=(7, 5))
    lines: dict[str, list[dict[str, float | str]]] = {}
    for row in rows[1:]:
        lines.setdefault(str(row["controller"]).split(", stroke")[0], []).append(row)
    for label, chosen in lines.items():
        axis.plot(
            [r["peak stroke (m)"] for r in chosen],
            [r["J1 x1"] for r in chosen],
            "o-",
            label=f"{label}, stroke x ...",
        )
    axis.plot(
        [rows[0]["peak stroke (m)"]], [rows[0]["J1 x1"]], "s", color="grey", label="passive (driver off)"
    )
    experiments: dict[str, list[Path]] = {}
    for run in runs:
        experiments.setdefault(run.parent.name, []).append(run)
    for number, (name, chosen) in enumerate(experiments.items()):  # colours after the LQG lines'
        points = [
            pd.read_csv(run / "evaluation" / "summary.csv").set_index("controller").loc["RL"]
            for run in chosen
        ]
        stroke, j1 = [point["stroke_m"] for point in points], [point["J1"] for point in points]
        axis.plot(
            stroke,
            j1,
            "*",
            markersize=12,
            color=f"C{len(lines) + number}",
            label=f"learned: {name} ({len(points)} seeds)",
        )
    axis.set(xlabel="peak stroke (m), mean over motions", ylabel="J1 = peak drift ratio (mean)")
    axis.set_title("Active mass driver: LQG + ground model over its force and stroke weights", fontsize=9)
    axis.grid(alpha=0.3)
    axis.legend(fontsize=7)
    figure.tight_layout()
    atomic_savefig(figure, out)
    plt.close(figure)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default = REPOSITORY / "configs/experiments/five_story_amd.yaml"
    parser.add_argument("config", type=Path, nargs="?", default=default)
    parser.add_argument("--records", type=Path, nargs="+", default=[REPOSITORY.parent / "shared" / "records"])
    parser.add_argument("--force", type=float, nargs="+", default=[0.3, 1.0, 3.0])
    parser.add_argument("--stroke", type=float, nargs="+", default=[1.0, 2.0, 3.0, 5.0, 7.0, 10.0, 20.0])
    parser.add_argument("--frequencies", type=float, nargs="+", default=[0.85, 0.9, 1.0, 1.1, 1.15])
    parser.add_argument("--plot", type=Path, help="PNG of the first suite's trade-off")
    parser.add_argument("--runs", type=Path, nargs="*", default=[], help="run folders to mark on the plot")
    arguments = parser.parse_args()
    if 1.0 not in arguments.frequencies:
        sys.exit("error: --frequencies: include 1 (the driver as tuned), which gives J2 and the stroke")
    try:
        experiment = load_experiment(arguments.config)
        controllers = grid(experiment, arguments.force, arguments.stroke)
        suites = {str(folder): choose_motions(folder)[0] for folder in arguments.records}
    except ConfigError as error:
        sys.exit(f"error: {error}")
    missing = [run for run in arguments.runs if not (run / "evaluation" / "summary.csv").is_file()]
    if missing:
        sys.exit(
            f"error: --runs: {missing[0]} has no evaluation/summary.csv (evaluate it on the first suite)"
        )
    for number, (name, motions) in enumerate(suites.items()):
        rows = table(experiment, controllers, motions, arguments.frequencies)
        print(f"## {name}\n\n{markdown(rows)}\n", flush=True)
        if number == 0 and arguments.plot is not None:
            plot(rows, arguments.runs, arguments.plot)


if __name__ == "__main__":
    main()
