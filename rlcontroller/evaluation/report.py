"""The report files of an evaluation, an LQG sweep, a preview study and a robustness study: tables
(CSV + Markdown, built by `tables`) and the paper's plots.

Every table and plot carries the motion suite's label, so synthetic results can never pass for
the records. Plots show drift in cm and forces in kN for readability; the CSVs are SI.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import sys
import traceback
from collections.abc import Callable
from pathlib import Path

import numpy as np

from rlcontroller.evaluation.evaluation import OPTIMAL, Evaluation
from rlcontroller.evaluation.tables import (
    FAIRNESS,
    LEGEND,
    METRIC_NAMES,
    by_pga,
    improvement_table,
    markdown_table,
    per_record_frame,
    summary_table,
)
from rlcontroller.files import atomic_savefig, atomic_write
from rlcontroller.physics.metrics import METRICS

COLOURS = {
    "uncontrolled": "0.6",
    "LQG": "tab:blue",
    "LQG + ground": "tab:purple",
    "LQG + ground model": "tab:green",
    "LQG + wind model": "tab:cyan",
    "RL": "tab:red",
    OPTIMAL: "black",
}
LINE_STYLES = {
    "LQG + ground": (0, (5, 2)),
    "LQG + ground model": (0, (1, 1)),
    "LQG + wind model": (0, (1, 1)),
    OPTIMAL: "--",
}


def write_tables(evaluation: Evaluation, out: Path) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    summary = summary_table(evaluation)
    improvement = improvement_table(evaluation)
    per_record = per_record_frame(evaluation)
    written = [
        atomic_write(
            out / "metrics.csv", evaluation.metrics.assign(suite=evaluation.label).to_csv(index=False)
        ),
        atomic_write(out / "per_record.csv", per_record.assign(suite=evaluation.label).to_csv(index=False)),
        atomic_write(out / "summary.csv", summary.assign(suite=evaluation.label).to_csv()),
    ]
    text = [f"# Summary: {evaluation.label}", ""]
    text += [f"Experiment: {evaluation.experiment.name} (seed {evaluation.experiment.seed})."]
    text += [f"Evaluated {name}: {source}." for name, source in evaluation.sources.items()]
    text += ["", f"{LEGEND} {FAIRNESS}", ""]
    text += [markdown_table(summary), ""]
    if improvement is not None:
        text += [markdown_table(improvement, digits=1), ""]
    for metric in ("J1", "J2"):
        banded = by_pga(evaluation, metric)
        written.append(
            atomic_write(out / f"{metric.lower()}_by_pga.csv", banded.assign(suite=evaluation.label).to_csv())
        )
        text += [
            f"Mean {metric} by the record's PGA (number of records in the band):",
            "",
            markdown_table(banded),
            "",
        ]
    text += [f"Evaluated in {evaluation.seconds:.1f} s.", ""]
    atomic_write(out / "summary.md", "\n".join(text))
    stories = ", ".join(evaluation.experiment.command_labels())
    detail = [f"# J1-J4 per record and story: {evaluation.label}", ""]
    detail += [f"Columns: story (J3: commanded device, on stories {stories}).", ""]
    detail += [f"- {name}: {text}" for name, text in evaluation.descriptions.items() if text] + [""]
    for metric in [m for m in METRIC_NAMES if m in set(evaluation.metrics["metric"])]:
        for controller in evaluation.controllers:
            if controller == "uncontrolled":
                continue
            chosen = per_record[(per_record["metric"] == metric) & (per_record["controller"] == controller)]
            frame = chosen.drop(columns=["controller", "metric"]).set_index("record").dropna(axis=1)
            frame.loc["mean"] = frame.mean()
            detail += [f"## {METRIC_NAMES[metric]}, {controller}", "", markdown_table(frame), ""]
    atomic_write(out / "per_record.md", "\n".join(detail))
    return written + [out / "summary.md", out / "per_record.md"]


def time_history_record(evaluation: Evaluation) -> str:
    """The Northridge record the paper plots (Sylmar Olive View), else the first one."""
    for name in evaluation.records:
        if "NORTHR_SYL" in name:
            return name
    for name in evaluation.records:
        if "NORTHR" in name:
            return name
    return evaluation.records[0]


def strong_part(
    ground: np.ndarray, time: np.ndarray, low: float = 0.05, high: float = 0.95
) -> tuple[float, float]:
    """The strong shaking: the significant duration D5-95 of the ground motion (where its Arias
    intensity, the integral of a_g^2, goes from 5 % to 95 %), padded by 1 s before and 4 s after,
    at least 10 s long (s)."""
    energy = np.cumsum(ground**2)
    if energy[-1] <= 0.0:
        return float(time[0]), float(time[-1])
    start = time[np.searchsorted(energy, low * energy[-1])] - 1.0
    end = time[min(np.searchsorted(energy, high * energy[-1]), time.size - 1)] + 4.0
    end = max(end, start + 10.0)
    return float(max(time[0], start)), float(min(time[-1], end))


def time_history_data(evaluation: Evaluation, story: int = 4) -> dict:
    """What `draw_time_histories` draws: drift of one story and base shear on one record, every
    controller, over the strong part of the response (plain arrays and text)."""
    record = time_history_record(evaluation)
    story = min(story, evaluation.experiment.building.n_floors)
    bare = evaluation.responses["uncontrolled", record]
    start, end = strong_part(bare.ground, bare.time)
    shown = slice(max(0, np.searchsorted(bare.time, start) - 1), np.searchsorted(bare.time, end) + 1)
    lines = []
    for controller in evaluation.controllers:
        result = evaluation.responses[controller, record]
        lines.append(
            (
                controller,
                result.time[shown],
                100 * result.drift[shown, story - 1],
                result.base_shear[shown] / 1e3,
            )
        )
    description = evaluation.descriptions.get(record, "")
    source = "SYNTHETIC motion" if "SYNTHETIC" in evaluation.label else "as recorded"
    if "scaled to PGA" in evaluation.label:
        source = evaluation.label[evaluation.label.index("scaled to PGA") :]
    title = f"{record}" + (f" ({description})" if description else "") + f", {source}; strong part shown"
    return {"title": title, "story": story, "span": (start, end), "lines": lines}


def draw_time_histories(data: dict, path: Path) -> Path:
    """`time_history_data` as a two-panel PNG at `path`: drift (cm) above, base shear (kN) below."""
    plt = pyplot()
    figure, (drift_axis, shear_axis) = plt.subplots(2, 1, figsize=(11, 6.5), sharex=True)
    for controller, time, drift, shear in data["lines"]:
        style = {
            "color": COLOURS.get(controller),
            "linestyle": LINE_STYLES.get(controller, "-"),
            "linewidth": 1.6 if controller == "RL" else 1.0,
        }
        drift_axis.plot(time, drift, label=controller, **style)
        shear_axis.plot(time, shear, label=controller, **style)
    drift_axis.set(ylabel=f"story-{data['story']} drift (cm)", title=data["title"], xlim=data["span"])
    shear_axis.set(xlabel="time (s)", ylabel="base shear (kN)")
    drift_axis.legend(loc="upper right", ncol=3, fontsize=9)
    for axis in (drift_axis, shear_axis):
        axis.grid(alpha=0.3)
    # tight_layout's margins for these sizes, fixed: it measures every label again (0.06 s a figure)
    figure.subplots_adjust(left=0.08, right=0.985, bottom=0.09, top=0.94, hspace=0.08)
    atomic_savefig(figure, path)
    plt.close(figure)
    return path


def per_story_data(evaluation: Evaluation) -> dict:
    """What `draw_metrics_per_story` draws: J1-J4 per story (J3 per commanded device), the mean over
    records, per controller."""
    mean = evaluation.metrics.groupby(["metric", "controller", "index"], sort=True)["value"].mean()
    present = set(mean.index.droplevel("index"))  # no J3 for passive devices: nothing commanded
    lines = {
        metric: [
            (
                controller,
                mean.loc[metric, controller].index.to_numpy(),
                mean.loc[metric, controller].to_numpy(),
            )
            for controller in evaluation.controllers
            if (metric, controller) in present
        ]
        for metric in METRICS
    }
    return {
        "label": evaluation.label,
        "lines": lines,
        "command_labels": evaluation.experiment.command_labels(),
    }


def draw_metrics_per_story(data: dict, path: Path) -> Path:
    """`per_story_data` as four panels, one line per controller, as a PNG at `path`."""
    plt = pyplot()
    figure, axes = plt.subplots(1, 4, figsize=(16, 4.2))
    for axis, metric in zip(axes, METRICS, strict=True):
        for controller, index, values in data["lines"][metric]:
            axis.plot(
                index,
                values,
                marker="o",
                markersize=3,
                color=COLOURS.get(controller, "tab:orange"),
                linestyle=LINE_STYLES.get(controller, "-"),
                linewidth=1.8 if controller == "RL" else 1.0,
                label=controller,
            )
            axis.set_xticks(index)
        if metric == "J3" and data["command_labels"]:
            axis.set_xticklabels([data["command_labels"][i - 1] for i in axis.get_xticks()])
        axis.set(
            xlabel="story of the commanded device" if metric == "J3" else "story",
            title=METRIC_NAMES[metric] + (" (E_u / E_Vb,UC)" if metric == "J3" else " (C / UC)"),
        )
        axis.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    figure.suptitle(f"J1–J4 per story, mean over records — {data['label']}", fontsize=11)
    # tight_layout's, fixed (above)
    figure.subplots_adjust(left=0.04, right=0.99, bottom=0.14, top=0.84, wspace=0.2)
    atomic_savefig(figure, path)
    plt.close(figure)
    return path


DRAWINGS = {draw.__name__: draw for draw in (draw_time_histories, draw_metrics_per_story)}


def write_report(
    evaluation: Evaluation,
    out: Path,
    drawing: Drawing | None = None,
    *,
    meanwhile: Callable[[], None] | None = None,
) -> list[Path]:
    """Tables and plots of one evaluation into `out`; the plots by `drawing`'s process while the tables
    are written and `meanwhile` runs (the caller's own work, off the path while the plots take longer),
    when one is given."""
    out.mkdir(parents=True, exist_ok=True)
    jobs = [
        (draw_time_histories, time_history_data(evaluation), out / "time_histories.png"),
        (draw_metrics_per_story, per_story_data(evaluation), out / "metrics_per_story.png"),
    ]
    if drawing is not None:
        drawing.submit(jobs)
    if meanwhile is not None:
        meanwhile()
    tables = write_tables(evaluation, out)
    if drawing is None:
        return tables + [draw(data, path) for draw, data, path in jobs]
    return tables + drawing.results()


class Drawing:
    """A process, forked at once, that imports matplotlib while its parent simulates and then draws the
    evaluation's plots from their data (`write_report`): with two cores the import (0.4 s) and the drawing
    (0.5 s) leave `rlc evaluate`'s path (docs/speed.md). Our own data between our own processes (pickled
    through a pipe); nothing read from a file. Use as a context manager: leaving it ends the process."""

    def __init__(self) -> None:

        sys.stdout.flush()  # the child must not write its copy of unflushed output again
        sys.stderr.flush()
        context = multiprocessing.get_context("fork")
        self._connection, child_end = context.Pipe()
        self._process = context.Process(target=_draw_jobs, args=(child_end,), daemon=True)
        self._process.start()
        child_end.close()

    def submit(self, jobs: list[tuple]) -> None:
        self._connection.send([(draw.__name__, data, path) for draw, data, path in jobs])

    def results(self) -> list[Path]:
        try:
            status, value = self._connection.recv()
        except EOFError:
            raise RuntimeError(
                f"the drawing process ended early (exit code {self._process.exitcode})"
            ) from None
        if status == "error":
            raise RuntimeError(f"drawing the plots failed:\n{value}")
        return value

    def __enter__(self) -> Drawing:
        return self

    def __exit__(self, *exception) -> None:
        with contextlib.suppress(OSError):  # no more jobs (the child holds a copy of this end: no EOF for it)
            self._connection.send(None)
        self._connection.close()
        self._process.join(timeout=5.0)
        if self._process.is_alive():
            self._process.terminate()
            self._process.join()


def _draw_jobs(connection) -> None:

    pyplot()  # the import, while the parent simulates
    while True:
        try:
            jobs = connection.recv()
        except EOFError:
            return
        if jobs is None:
            return
        try:
            connection.send(("ok", [DRAWINGS[name](data, path) for name, data, path in jobs]))
        except Exception:
            connection.send(("error", traceback.format_exc()))


def pyplot():
    """matplotlib's pyplot on the Agg backend, imported on first use: only what draws pays its 0.4 s."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt
