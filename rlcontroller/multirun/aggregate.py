"""Statistics over seeds: mean, std, interquartile mean and 95 % stratified-bootstrap intervals.

Each run (a seed) contributes one score per controller, metric and record: the metric's mean over
stories (actuators for J3) on that record. Following rliable (Agarwal et al. 2021, "Deep RL at the
edge of the statistical precipice"), the aggregates are taken over all run x record scores: the
mean and the interquartile mean (IQM: the mean of the middle 50 %, robust to an outlying run or
record), each with a 95 % percentile interval from a stratified bootstrap that resamples the runs
independently for every record. The method is rliable's, written here in a few lines of numpy
(rliable itself brings arch and seaborn along); `std` is the sample standard deviation (ddof 1) of
the runs' mean scores.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from rlcontroller.config import ConfigError
from rlcontroller.files import atomic_savefig, atomic_write
from rlcontroller.physics.metrics import METRICS

BOOTSTRAP_REPS = 2000
STATISTICS = ["runs", "mean", "std", "mean_low", "mean_high", "iqm", "iqm_low", "iqm_high"]


def metrics_file(run: Path) -> Path:
    """The evaluation metrics of a run folder (RUN/evaluation/metrics.csv), of an evaluation folder, or
    of a robustness folder (robustness.csv)."""
    for candidate in (run / "evaluation" / "metrics.csv", run / "metrics.csv", run / "robustness.csv"):
        if candidate.is_file():
            return candidate
    inner = sorted(folder.name for folder in run.glob("*/") if any(folder.glob("**/metrics.csv")))
    if inner:
        names = ", ".join(inner[:4]) + (", ..." if len(inner) > 4 else "")
        raise ConfigError(f"{run}: a folder of runs ({names}); give the runs: 'rlc aggregate {run}/*/'")
    if not (run / "config.yaml").is_file():
        raise ConfigError(f"{run}: not a run folder nor an evaluation or robustness folder (no metrics.csv)")
    raise ConfigError(
        f"{run}: no evaluation/metrics.csv; evaluate it first with 'rlc evaluate {run} --out "
        f"{run}/evaluation'"
    )


def scores(runs: list[Path]) -> pd.DataFrame:
    """Long form (run, controller, metric, record, score): each run's mean over stories per record.
    Robustness results add a `group` per scenario and one more, "all scenarios", whose records are
    every scenario's."""
    frames = []
    for run in runs:
        path = metrics_file(run)
        frame = read_metrics(path)
        keys = ["scenario"] if "scenario" in frame.columns else []
        per_record = frame.groupby([*keys, "controller", "metric", "record"], sort=False)["value"].mean()
        per_record = per_record.rename("score").reset_index().assign(run=str(run))
        if keys:
            pooled = per_record.assign(
                group="all scenarios", record=per_record["scenario"] + ": " + per_record["record"]
            )
            per_record = pd.concat(
                [per_record.rename(columns={"scenario": "group"}), pooled.drop(columns="scenario")]
            )
        frames.append(per_record)
    table = pd.concat(frames, ignore_index=True)
    if "group" in table.columns and table["group"].isna().any():
        raise ConfigError("robustness results and evaluations cannot be aggregated together")
    records = table.groupby("run")["record"].apply(frozenset)
    if records.nunique() > 1:
        raise ConfigError("the runs were evaluated on different records; aggregate runs of one motion suite")
    return table


METRICS_COLUMNS = ("controller", "record", "metric", "index", "value")


def read_metrics(path: Path) -> pd.DataFrame:
    """An evaluation's metrics.csv (or robustness.csv), checked: its columns, at least one row, finite
    numbers; a damaged file is a one-line `ConfigError` naming it."""
    try:
        frame = pd.read_csv(path)
    except (ValueError, UnicodeDecodeError, pd.errors.ParserError, pd.errors.EmptyDataError) as error:
        raise ConfigError(f"{path}: not an evaluation metrics file ({type(error).__name__})") from None
    missing = [column for column in METRICS_COLUMNS if column not in frame.columns]
    if missing:
        raise ConfigError(f"{path}: not an evaluation metrics file (no column {', '.join(missing)})")
    if frame.empty:
        raise ConfigError(f"{path}: no rows: the evaluation holds no results")
    values = pd.to_numeric(frame["value"], errors="coerce")
    bad = ~np.isfinite(values.to_numpy(dtype=float))
    if bad.any():
        line = int(np.argmax(bad)) + 2
        raise ConfigError(f"{path}:{line}: value {frame['value'].iloc[line - 2]!r}, expected a finite number")
    if frame[["controller", "record", "metric"]].isna().any().any():
        raise ConfigError(f"{path}: a row without its controller, record or metric")
    return frame.assign(value=values)


def interquartile_mean(values: np.ndarray) -> float:
    """The mean of the middle 50 % of the values (25 % trimmed from each end)."""
    return float(stats.trim_mean(np.ravel(values), 0.25))


def stratified_bootstrap(matrix: np.ndarray, rng: np.random.Generator, reps: int = BOOTSTRAP_REPS) -> dict:
    """95 % percentile intervals of the mean and the IQM of a (runs, records) score matrix, resampling
    the runs independently for every record."""
    runs, records = matrix.shape
    picks = rng.integers(0, runs, size=(reps, runs, records))
    samples = matrix[picks, np.arange(records)]  # (reps, runs, records)
    flat = samples.reshape(reps, -1)
    means = flat.mean(axis=1)
    iqms = stats.trim_mean(flat, 0.25, axis=1)
    return {
        "mean_low": float(np.percentile(means, 2.5)),
        "mean_high": float(np.percentile(means, 97.5)),
        "iqm_low": float(np.percentile(iqms, 2.5)),
        "iqm_high": float(np.percentile(iqms, 97.5)),
    }


def aggregate(
    table: pd.DataFrame, seed: int = 0, reps: int = BOOTSTRAP_REPS, advance: Callable[[], None] | None = None
) -> pd.DataFrame:
    """Per group (if a `group` column), controller and metric: runs, mean, std over runs, IQM, and
    their 95 % stratified-bootstrap intervals. `advance()` is called after each of them (a progress bar)."""
    keys = (["group"] if "group" in table.columns else []) + ["controller", "metric"]
    rng = np.random.default_rng(seed)
    rows = []
    for key, chosen in table.groupby(keys, sort=False):
        matrix = chosen.pivot(index="run", columns="record", values="score").to_numpy()
        run_means = matrix.mean(axis=1)
        row = dict(zip(keys, key if isinstance(key, tuple) else (key,), strict=True))
        row |= {
            "runs": matrix.shape[0],
            "mean": float(matrix.mean()),
            "std": float(run_means.std(ddof=1)) if matrix.shape[0] > 1 else float("nan"),
            "iqm": interquartile_mean(matrix),
        }
        rows.append(row | stratified_bootstrap(matrix, rng, reps))
        if advance is not None:
            advance()
    frame = pd.DataFrame(rows)
    order = [m for m in METRICS if m in set(frame["metric"])] + sorted(set(frame["metric"]) - set(METRICS))
    frame["metric"] = pd.Categorical(frame["metric"], order, ordered=True)
    for column in keys[:-1]:  # groups and controllers in the order the runs list them
        frame[column] = pd.Categorical(frame[column], list(dict.fromkeys(table[column])), ordered=True)
    return frame.sort_values(keys, kind="stable").reset_index(drop=True)[[*keys, *STATISTICS]]


def markdown(frame: pd.DataFrame, title: str) -> str:
    """Two tables, one row per (group and) controller, one column per metric: the IQM with its 95 %
    interval, then the mean ± std over runs with the mean's 95 % interval."""
    labels = _label_columns(frame)
    rows = frame.groupby(labels, sort=False, observed=True)
    metrics = list(dict.fromkeys(frame["metric"]))
    parts = [f"# {title}", ""]
    for heading, cell in (
        (
            "Interquartile mean [95 % stratified-bootstrap CI]",
            lambda r: f"{r.iqm:.3f} [{r.iqm_low:.3f}, {r.iqm_high:.3f}]",
        ),
        ("Mean ± std over runs [95 % CI of the mean]", _mean_cell),
    ):
        parts += [f"## {heading}", "", "| " + " | ".join([*labels, "runs", *metrics]) + " |"]
        parts.append("|" + "---|" * (len(labels) + 1 + len(metrics)))
        for key, chosen in rows:
            by_metric = {row.metric: row for row in chosen.itertuples()}
            key = key if isinstance(key, tuple) else (key,)
            cells = [str(k) for k in key] + [str(chosen["runs"].iloc[0])]
            cells += [cell(by_metric[m]) if m in by_metric else "–" for m in metrics]
            parts.append("| " + " | ".join(cells) + " |")
        parts.append("")
    return "\n".join(parts)


def _mean_cell(row) -> str:
    std = "–" if np.isnan(row.std) else f"{row.std:.3f}"
    return f"{row.mean:.3f} ± {std} [{row.mean_low:.3f}, {row.mean_high:.3f}]"


def _label_columns(frame: pd.DataFrame) -> list[str]:
    return [c for c in ("group", "controller") if c in frame.columns]


def plot(frame: pd.DataFrame, path: Path, title: str) -> Path:
    """IQM with its 95 % interval per controller (and group), one panel per metric."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    metrics = list(frame["metric"].cat.categories.intersection(frame["metric"].unique()))
    labels = (
        frame[[c for c in ("group", "controller") if c in frame.columns]].astype(str).agg(" · ".join, axis=1)
    )
    names = list(dict.fromkeys(labels))
    figure, axes = plt.subplots(
        1, len(metrics), figsize=(3.2 * len(metrics) + 2.5, 0.35 * len(names) + 1.6), sharey=True
    )
    axes = np.atleast_1d(axes)
    for axis, metric in zip(axes, metrics, strict=True):
        chosen = frame[frame["metric"] == metric]
        positions = [names.index(label) for label in labels[chosen.index]]
        low = chosen["iqm"] - chosen["iqm_low"]
        high = chosen["iqm_high"] - chosen["iqm"]
        axis.errorbar(chosen["iqm"], positions, xerr=[low, high], fmt="o", capsize=3, label="IQM, 95 % CI")
        axis.plot(chosen["mean"], positions, "x", color="0.4", label="mean")
        axis.set_title(metric)
        axis.grid(axis="x", alpha=0.3)
    axes[0].set_yticks(range(len(names)), names)
    axes[0].invert_yaxis()
    axes[-1].legend(loc="lower right", fontsize="small")
    figure.suptitle(title, fontsize="medium")
    figure.tight_layout()
    atomic_savefig(figure, path)
    plt.close(figure)
    return path


def write_aggregate(frame: pd.DataFrame, out: Path, title: str) -> list[Path]:
    """aggregate.csv, aggregate.md and aggregate.png in `out`."""
    out.mkdir(parents=True, exist_ok=True)
    csv = atomic_write(out / "aggregate.csv", frame.to_csv(index=False))
    md = atomic_write(out / "aggregate.md", markdown(frame, title))
    return [csv, md, plot(frame, out / "aggregate.png", title)]
