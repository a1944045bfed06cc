"""The report files of the studies beside an evaluation: LQG's trade-off curve (`rlc compare lqg --sweep`),
the dampers' trade-off, the preview study (`--preview`) and the robustness study (`rlc robustness`):
CSV and Markdown tables and a plot each, every one carrying the suite's label."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from rlcontroller.evaluation.report import COLOURS, pyplot
from rlcontroller.evaluation.tables import METRIC_NAMES, markdown_table
from rlcontroller.files import atomic_savefig, atomic_write


def write_sweep(
    sweep: pd.DataFrame, out: Path, label: str, points: dict[str, tuple[float, float]]
) -> list[Path]:
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
            f"- {name}: J3 = {j3:.4f}, J1 = {j1:.3f}; LQG at the same J3: J1 = {lqg_j1:.3f} ({verdict} the "
            "curve)"
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
            [j3],
            [j1],
            marker,
            markersize=13 if marker == "*" else 8,
            color=COLOURS.get(name, "tab:green"),
            label=name,
        )
    axis.set(
        xscale="log", xlabel="J3 = E_u / E_Vb,UC (mean over actuators)", ylabel="J1 = peak drift ratio (mean)"
    )
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
        f"- lowest J1 of the classical points: {best['family']} at {best['parameter']:g}, J1 = "
        f"{best['J1']:.3f}, "
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
            axis.plot(
                [x], [j1], marker, markersize=size, color=COLOURS.get(name, f"C{number + 2}"), label=name
            )
    axes[0].set(
        xlabel="J3 (damper force energy / uncontrolled base shear energy)", ylabel="J1 (peak drift ratio)"
    )
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
        "ground motion; inf = the whole record (the clairvoyant optimum). A causal controller has no "
        "preview.",
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
        axis.plot(
            finite["preview_s"], finite[metric], "o-", color="black", label="full-state LQR with preview"
        )
        for _, row in clairvoyant.iterrows():
            axis.axhline(row[metric], color="black", linestyle=":", label="whole record known (clairvoyant)")
        for index, (name, values) in enumerate(references.items()):
            axis.axhline(
                values[0 if metric == "J1" else 1],
                color=COLOURS.get(name, f"C{index}"),
                linestyle="--",
                label=name,
            )
        axis.set(xlabel="ground motion known ahead (s)", ylabel=METRIC_NAMES[metric] + " (mean)")
        axis.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    figure.suptitle(f"Value of ground-motion preview — {label}", fontsize=9)
    figure.tight_layout()
    written += [out / "preview.md", atomic_savefig(figure, out / "preview.png")]
    plt.close(figure)
    return written


def write_robustness(
    table: pd.DataFrame, scenarios: list, out: Path, label: str, *, seconds: float
) -> list[Path]:
    """robustness.csv (long form), robustness.md (scenario x controller means, the worst record's
    J1, the mean over scenarios) and robustness.png (J1 against the stiffness factor; J1 and J2 per
    scenario)."""
    plt = pyplot()
    from rlcontroller.evaluation.robustness import (
        mean_over_scenarios,
        stiffness_curve,
        summary,
        worst_record_j1,
    )

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
        "LQG (re-designed on the plant) is the oracle: LQG designed on the true plant, actuator lag and "
        "delay",
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
    figure, (curve_axis, bar_axis) = plt.subplots(
        1, 2, figsize=(14, 5.5), gridspec_kw={"width_ratios": [1, 2]}
    )
    for name in controllers if not curve.empty else []:
        colour = COLOURS.get("RL") if name == "RL" else None
        curve_axis.plot(curve.index, curve[name], "o-", label=name, color=colour)
    curve_axis.axhline(1.0, color="0.5", linestyle=":", linewidth=0.8)
    curve_axis.set(
        xlabel="stiffness factor (plant / design)", ylabel="J1 (mean)", title="J1 against stiffness"
    )
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
