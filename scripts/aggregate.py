"""Mean +- std over seeds of the evaluation summaries of several runs (Markdown on stdout).

Usage: python scripts/aggregate.py RUN_DIR [RUN_DIR ...]   (each with evaluation/summary.csv)
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

from rlcontroller.evaluation.evaluation import LQG_VARIANTS
from rlcontroller.learning.run_folder import RunFolder

METRICS = ["J1", "J2", "J3", "J4"]


def main(runs: list[Path]) -> None:
    summaries = [pd.read_csv(run / "evaluation" / "summary.csv", index_col="controller") for run in runs]
    suite = summaries[0]["suite"].iloc[0]
    stacked = pd.concat([s[METRICS] for s in summaries], keys=range(len(summaries)), names=["seed"])
    mean = stacked.groupby("controller", sort=False).mean()
    std = stacked.groupby("controller", sort=False).std(ddof=0)
    print(f"# {len(runs)} seeds on the {suite}: mean ± std over seeds of the means over records and stories\n")
    print("| controller | " + " | ".join(METRICS) + " | J1 reduction % | J2 reduction % |")
    print("|---|" + "---|" * (len(METRICS) + 2))
    for controller in mean.index:
        cells = [f"{mean.loc[controller, m]:.3f} ± {std.loc[controller, m]:.3f}" for m in METRICS]
        reductions = [f"{100 * (1 - mean.loc[controller, m]):.1f}" for m in ("J1", "J2")]
        print(f"| {controller} | " + " | ".join(cells + reductions) + " |")
    print()
    for reference in LQG_VARIANTS:
        better = [100 * (1 - s.loc["RL", METRICS] / s.loc[reference, METRICS]) for s in summaries]
        frame = pd.DataFrame(better)
        cells = [f"{frame[m].mean():.1f} ± {frame[m].std(ddof=0):.1f}" for m in METRICS]
        print(
            f"- RL better than {reference} (%): " + ", ".join(f"{m} {c}" for m, c in zip(METRICS, cells, strict=True))
        )
    print()
    for run in runs:
        curve = RunFolder(run).read_curve()
        last = curve[-1] if curve else {"steps": float("nan"), "wall_time_s": float("nan")}
        print(f"- {run.name}: {last['steps']:.0f} training steps, {last['wall_time_s'] / 60:.1f} min wall time")


if __name__ == "__main__":
    main([Path(argument) for argument in sys.argv[1:]])
