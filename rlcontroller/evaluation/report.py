"""The report files of an evaluation, an LQG sweep, a preview study and a robustness study: tables
(CSV + Markdown, built by `tables`) and the paper's plots.

Every table and plot carries the motion suite's label, so synthetic results can never pass for
the records. Plots show drift in cm and forces in kN for readability; the CSVs are SI.
"""

from __future__ import annotations

import contextlib
from pathlib import Path

import numpy as np
import pandas as pd

from rlcontroller.evaluation.evaluation import OPTIMAL, Evaluation
from rlcontroller.evaluation.tables import (
    FAIRNESS,
    LEGEND,
    METRIC_NAMES,
    improvement_table,
    j1_by_pga,
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
        atomic_write(out / "metrics.csv", evaluation.metrics.assign(suite=evaluation.label).to_csv(index=False)),
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
    by_pga = j1_by_pga(evaluation)
    written.append(atomic_write(out / "j1_by_pga.csv", by_pga.assign(suite=evaluation.label).to_csv()))
    text += ["Mean J1 by the record's PGA (number of records in the band):", "", markdown_table(by_pga), ""]
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


def strong_part(ground: np.ndarray, time: np.ndarray, low: float = 0.05, high: float = 0.95) -> tuple[float, float]:
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
    story = min(story, len(evaluation.experiment.building.masses))
    bare = evaluation.responses["uncontrolled", record]
    start, end = strong_part(bare.ground, bare.time)
    shown = slice(max(0, np.searchsorted(bare.time, start) - 1), np.searchsorted(bare.time, end) + 1)
    lines = []
    for controller in evaluation.controllers:
        result = evaluation.responses[controller, record]
        lines.append(
            (controller, result.time[shown], 100 * result.drift[shown, story - 1], result.base_shear[shown] / 1e3)
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
    lines = {
        metric: [
            (controller, mean.loc[metric, controller].index.to_numpy(), mean.loc[metric, controller].to_numpy())
            for controller in evaluation.controllers
        ]
        for metric in METRICS
    }
    return {"label": evaluation.label, "lines": lines, "command_labels": evaluation.experiment.command_labels()}


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
        if metric == "J3":
            axis.set_xticklabels([data["command_labels"][i - 1] for i in axis.get_xticks()])
        axis.set(
            xlabel="story of the commanded device" if metric == "J3" else "story",
            title=METRIC_NAMES[metric] + (" (E_u / E_Vb,UC)" if metric == "J3" else " (C / UC)"),
        )
        axis.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    figure.suptitle(f"J1–J4 per story, mean over records — {data['label']}", fontsize=11)
    figure.subplots_adjust(left=0.04, right=0.99, bottom=0.14, top=0.84, wspace=0.2)  # tight_layout's, fixed (above)
    atomic_savefig(figure, path)
    plt.close(figure)
    return path


DRAWINGS = {draw.__name__: draw for draw in (draw_time_histories, draw_metrics_per_story)}


def write_report(evaluation: Evaluation, out: Path, drawing: Drawing | None = None) -> list[Path]:
    """Tables and plots of one evaluation into `out`; the plots by `drawing`'s process while the tables
    are written, when one is given."""
    out.mkdir(parents=True, exist_ok=True)
    jobs = [
        (draw_time_histories, time_history_data(evaluation), out / "time_histories.png"),
        (draw_metrics_per_story, per_story_data(evaluation), out / "metrics_per_story.png"),
    ]
    if drawing is None:
        return write_tables(evaluation, out) + [draw(data, path) for draw, data, path in jobs]
    drawing.submit(jobs)
    return write_tables(evaluation, out) + drawing.results()


class Drawing:
    """A process, forked at once, that imports matplotlib while its parent simulates and then draws the
    evaluation's plots from their data (`write_report`): with two cores the import (0.4 s) and the drawing
    (0.5 s) leave `rlc evaluate`'s path (docs/speed.md). Our own data between our own processes (pickled
    through a pipe); nothing read from a file. Use as a context manager: leaving it ends the process."""

    def __init__(self) -> None:
        import multiprocessing
        import sys

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
            raise RuntimeError(f"the drawing process ended early (exit code {self._process.exitcode})") from None
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
    import traceback

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


def write_sweep(sweep: pd.DataFrame, out: Path, label: str, points: dict[str, tuple[float, float]]) -> list[Path]:
    """LQG's J1-J3 trade-off (one row per force-weight multiplier) with other controllers marked."""
    plt = pyplot()
    out.mkdir(parents=True, exist_ok=True)
    written = [atomic_write(out / "lqg_sweep.csv", sweep.assign(suite=label).to_csv(index=False))]
    lines = [
        f"# LQG trade-off: {label}",
        "",
        "A controller beats LQG only if it lies below this curve (lower J1 at equal J3).",
        "",
    ]
    lines += [markdown_table(sweep.set_index("force_weight_multiplier")), ""]
    for name, (j3, j1) in points.items():
        lqg_j1 = lqg_j1_at(sweep, j3)
        verdict = "below" if j1 < lqg_j1 else "above"
        lines.append(
            f"- {name}: J3 = {j3:.4f}, J1 = {j1:.3f}; LQG at the same J3: J1 = {lqg_j1:.3f} ({verdict} the curve)"
        )
    atomic_write(out / "lqg_sweep.md", "\n".join(lines) + "\n")
    figure, axis = plt.subplots(figsize=(7, 5))
    axis.plot(sweep["J3"], sweep["J1"], "o-", color=COLOURS["LQG"], label="LQG, force weight × multiplier")
    for _, row in sweep.iterrows():
        axis.annotate(
            f"×{row['force_weight_multiplier']:.2g}",
            (row["J3"], row["J1"]),
            fontsize=7,
            xytext=(3, 3),
            textcoords="offset points",
        )
    for name, (j3, j1) in points.items():
        marker = "*" if name == "RL" else "D"
        axis.plot(
            [j3], [j1], marker, markersize=13 if marker == "*" else 8, color=COLOURS.get(name, "tab:green"), label=name
        )
    axis.set(xscale="log", xlabel="J3 = E_u / E_Vb,UC (mean over actuators)", ylabel="J1 = peak drift ratio (mean)")
    axis.set_title(f"LQG trade-off — {label}", fontsize=9)
    axis.grid(alpha=0.3, which="both")
    axis.legend(fontsize=8)
    figure.tight_layout()
    written += [out / "lqg_sweep.md", atomic_savefig(figure, out / "lqg_sweep.png")]
    plt.close(figure)
    return written


def write_damper_sweep(
    sweep: pd.DataFrame, out: Path, label: str, points: dict[str, tuple[float, float, float]]
) -> list[Path]:
    """The semi-active dampers' classical trade-off (`evaluation.damper_sweep`): the passive dampers
    at each command level and clipped-optimal control at each force-weight multiplier, J1 against J3
    and J2, with other controllers (name -> (J1, J2, J3)) marked."""
    plt = pyplot()
    out.mkdir(parents=True, exist_ok=True)
    written = [atomic_write(out / "damper_sweep.csv", sweep.assign(suite=label).to_csv(index=False))]
    best = sweep.loc[sweep["J1"].idxmin()]
    lines = [
        f"# Semi-active dampers' trade-off: {label}",
        "",
        "Passive dampers at each command level (a fraction of the range: voltage / maximum for MR dampers)",
        "and clipped-optimal control at each multiplier of the reward's force weights. A controller beats",
        "the classical ones only below every point here at its own J2 and J3.",
        "",
        markdown_table(sweep.set_index("family")),
        "",
        f"- lowest J1 of the classical points: {best['family']} at {best['parameter']:g}, J1 = {best['J1']:.3f}, "
        f"J2 = {best['J2']:.3f}",
    ]
    for name, (j1, j2, j3) in points.items():
        lines.append(f"- {name}: J1 = {j1:.3f}, J2 = {j2:.3f}, J3 = {j3:.4f}")
    atomic_write(out / "damper_sweep.md", "\n".join(lines) + "\n")
    figure, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for family, marker in (("passive", "s-"), ("clipped-optimal", "o-")):
        chosen = sweep[sweep["family"] == family]
        for axis, x in zip(axes, ("J3", "J2"), strict=True):
            axis.plot(chosen[x], chosen["J1"], marker, label=family)
    for number, (name, (j1, j2, j3)) in enumerate(points.items()):  # each its own marker and colour
        marker, size = ("*", 13) if name == "RL" else ("Dv^PX"[number % 5], 8)
        for axis, x in zip(axes, (j3, j2), strict=True):
            axis.plot([x], [j1], marker, markersize=size, color=COLOURS.get(name, f"C{number + 2}"), label=name)
    axes[0].set(xlabel="J3 (damper force energy / uncontrolled base shear energy)", ylabel="J1 (peak drift ratio)")
    axes[1].set(xlabel="J2 (peak acceleration ratio)", ylabel="J1 (peak drift ratio)")
    for axis in axes:
        axis.grid(alpha=0.3)
        axis.legend(fontsize=8)
    figure.suptitle(f"Semi-active dampers' trade-off — {label}", fontsize=9)
    figure.tight_layout()
    written += [out / "damper_sweep.md", atomic_savefig(figure, out / "damper_sweep.png")]
    plt.close(figure)
    return written


def lqg_j1_at(sweep: pd.DataFrame, j3: float) -> float:
    """LQG's J1 at the given J3, interpolated in log J3 along the sweep (clamped at the ends)."""
    ordered = sweep.sort_values("J3")
    return float(np.interp(np.log(j3), np.log(ordered["J3"]), ordered["J1"]))


def equivalent_preview(preview: pd.DataFrame, j1: float) -> float | None:
    """The preview (s) at which full-state LQR reaches this J1, interpolated; None if it needs none."""
    finite = preview[np.isfinite(preview["preview_s"])].sort_values("preview_s")
    if j1 >= finite["J1"].iloc[0]:
        return None
    return float(np.interp(-j1, -finite["J1"].to_numpy(), finite["preview_s"].to_numpy()))


def write_preview(
    preview: pd.DataFrame, out: Path, label: str, references: dict[str, tuple[float, float]]
) -> list[Path]:
    """J1/J2 of full-state LQR against how far ahead it knows the ground, other controllers as lines."""
    plt = pyplot()
    out.mkdir(parents=True, exist_ok=True)
    written = [atomic_write(out / "preview.csv", preview.assign(suite=label).to_csv(index=False))]
    lines = [
        f"# What knowing the coming ground motion is worth: {label}",
        "",
        "Full-state LQR (same cost) plus the optimal feed-forward on the next `preview_s` seconds of",
        "ground motion; inf = the whole record (the clairvoyant optimum). A causal controller has no preview.",
        "",
        markdown_table(preview.set_index("preview_s")),
        "",
    ]
    for name, (j1, _) in references.items():
        seconds = equivalent_preview(preview, j1)
        reach = "no preview" if seconds is None else f"{seconds:.3f} s of preview"
        lines.append(f"- {name}: J1 = {j1:.3f}, which full-state LQR reaches with {reach}")
    atomic_write(out / "preview.md", "\n".join(lines) + "\n")
    finite = preview[np.isfinite(preview["preview_s"])]
    clairvoyant = preview[~np.isfinite(preview["preview_s"])]
    figure, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for axis, metric in zip(axes, ("J1", "J2"), strict=True):
        axis.plot(finite["preview_s"], finite[metric], "o-", color="black", label="full-state LQR with preview")
        for _, row in clairvoyant.iterrows():
            axis.axhline(row[metric], color="black", linestyle=":", label="whole record known (clairvoyant)")
        for index, (name, values) in enumerate(references.items()):
            axis.axhline(
                values[0 if metric == "J1" else 1], color=COLOURS.get(name, f"C{index}"), linestyle="--", label=name
            )
        axis.set(xlabel="ground motion known ahead (s)", ylabel=METRIC_NAMES[metric] + " (mean)")
        axis.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    figure.suptitle(f"Value of ground-motion preview — {label}", fontsize=9)
    figure.tight_layout()
    written += [out / "preview.md", atomic_savefig(figure, out / "preview.png")]
    plt.close(figure)
    return written


def write_robustness(table: pd.DataFrame, scenarios: list, out: Path, label: str, seconds: float) -> list[Path]:
    """robustness.csv (long form), robustness.md (scenario x controller means, the worst record's
    J1, the mean over scenarios) and robustness.png (J1 against the stiffness factor; J1 and J2 per
    scenario)."""
    plt = pyplot()
    from rlcontroller.evaluation.robustness import mean_over_scenarios, stiffness_curve, summary, worst_record_j1

    out.mkdir(parents=True, exist_ok=True)
    means = summary(table)
    worst = worst_record_j1(table)
    written = [atomic_write(out / "robustness.csv", table.assign(suite=label).to_csv(index=False))]
    controllers = [c for c in dict.fromkeys(table["controller"]) if c != "uncontrolled"]
    wide = means["J1"].unstack("controller")[controllers]
    lines = [
        f"# Robustness: {label}",
        "",
        "Every controller is designed on the design model (the experiment's building, actuators and sensors)",
        "and run on each scenario's plant; J against the uncontrolled plant, mean over records and stories.",
        "LQG (re-designed on the plant) is the oracle: LQG designed on the true plant, actuator lag and delay",
        "included (from the floor accelerometers; LQG + ground model also reads the ground accelerometer).",
        "Worst record: the largest per-record mean J1 (above 1: worse than no control).",
        "",
        "## Mean J1 per scenario",
        "",
        markdown_table(wide.rename_axis("scenario")),
        "",
        "## Worst record's J1 per scenario",
        "",
        markdown_table(worst.unstack("controller")[controllers].rename_axis("scenario")),
        "",
        "## Mean over the scenarios",
        "",
        markdown_table(mean_over_scenarios(means).loc[controllers].rename_axis("controller")),
        "",
        "## J1-J4 (and, for yielding stories, ductility, residual drift, hysteretic energy) per scenario",
        "",
        markdown_table(means.loc[(slice(None), controllers), :].reset_index().set_index("scenario")),
        "",
        f"Evaluated {len(scenarios)} scenarios x {len(controllers)} controllers x "
        f"{table['record'].nunique()} records in {seconds:.0f} s.",
        "",
    ]
    atomic_write(out / "robustness.md", "\n".join(lines))
    curve = stiffness_curve(means, scenarios)
    figure, (curve_axis, bar_axis) = plt.subplots(1, 2, figsize=(14, 5.5), gridspec_kw={"width_ratios": [1, 2]})
    for name in controllers if not curve.empty else []:
        colour = COLOURS.get("RL") if name == "RL" else None
        curve_axis.plot(curve.index, curve[name], "o-", label=name, color=colour)
    curve_axis.axhline(1.0, color="0.5", linestyle=":", linewidth=0.8)
    curve_axis.set(xlabel="stiffness factor (plant / design)", ylabel="J1 (mean)", title="J1 against stiffness")
    curve_axis.grid(alpha=0.3)
    curve_axis.legend(fontsize=8)
    positions = np.arange(len(wide))
    width = 0.8 / len(controllers)
    for index, name in enumerate(controllers):
        colour = COLOURS.get("RL") if name == "RL" else f"C{index}"
        bar_axis.bar(positions + index * width, wide[name], width, label=name, color=colour)
    bar_axis.axhline(1.0, color="0.5", linestyle=":", linewidth=0.8)
    bar_axis.set_xticks(positions + 0.4 - width / 2, wide.index, rotation=35, ha="right", fontsize=8)
    bar_axis.set(ylabel="J1 (mean)", title="J1 per scenario (dotted: no control)")
    bar_axis.grid(alpha=0.3, axis="y")
    bar_axis.legend(fontsize=8)
    figure.suptitle(f"Robustness — {label}", fontsize=10)
    figure.tight_layout()
    written += [out / "robustness.md", atomic_savefig(figure, out / "robustness.png")]
    plt.close(figure)
    return written
