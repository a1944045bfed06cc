"""The tables of an evaluation (pandas frames and Markdown): the summary, RL against the LQGs, J1 by
PGA band, per record. No plotting here: commands that only print a table stay light."""

from __future__ import annotations

import numpy as np
import pandas as pd

from rlcontroller.evaluation.evaluation import LQG_VARIANTS, Evaluation, percent_better
from rlcontroller.physics.metrics import METRICS
from rlcontroller.physics.motions.excitation import STANDARD_GRAVITY

METRIC_NAMES = {
    "J1": "J1 peak drift",
    "J2": "J2 peak abs. acceleration",
    "J3": "J3 force energy",
    "J4": "J4 peak story shear",
    "ductility": "ductility demand max|drift| / yield drift",
    "residual_drift_m": "residual drift (m)",
    "hysteretic_energy_J": "hysteretic energy (J)",
}


LEGEND = (
    "J1 peak inter-story drift, J2 peak absolute floor acceleration, J3 energy of the actuator force over "
    "that of the uncontrolled base shear, J4 peak story shear: each controlled over uncontrolled on the same "
    "record, the mean over stories (J3: actuators) and records; lower is better."
)
FAIRNESS = (
    "LQG is designed on the quadratic part of the RL reward (same weights and scales), with a Kalman "
    "filter on the same noisy floor accelerations, and runs in the same simulator with the same force limits."
)


def markdown_table(frame: pd.DataFrame, digits: int = 3) -> str:
    """A Markdown table; numbers with `digits` decimals, percentages (columns named '... %') with one."""
    header = "| " + " | ".join([str(frame.index.name or "")] + [str(c) for c in frame.columns]) + " |"
    rule = "|" + "---|" * (len(frame.columns) + 1)
    lines = [header, rule]
    places = [1 if str(column).endswith("%") else digits for column in frame.columns]
    for index, row in frame.iterrows():
        cells = [
            ("–" if np.isnan(v) else f"{v:.{d}f}") if isinstance(v, float | np.floating) else str(v)
            for v, d in zip(row, places, strict=True)
        ]
        label = f"{index:g}" if isinstance(index, float | np.floating) else str(index)
        lines.append("| " + " | ".join([label] + cells) + " |")
    return "\n".join(lines)


def summary_table(evaluation: Evaluation) -> pd.DataFrame:
    """Means over records and stories, with percent reductions from the uncontrolled building."""
    table = evaluation.summary()
    for metric in ("J1", "J2", "J4"):
        table[f"{metric} reduction %"] = 100.0 * (1.0 - table[metric])
    table.index.name = "controller"
    return table


def improvement_table(evaluation: Evaluation, candidate: str = "RL") -> pd.DataFrame | None:
    """Percent by which `candidate`'s mean J's are below each LQG variant's (positive = better)."""
    table = evaluation.summary()
    references = [r for r in LQG_VARIANTS if r in table.index]
    if candidate not in table.index or not references:
        return None
    rows = {
        f"{candidate} better than {reference} (%)": {
            m: percent_better(table.loc[candidate, m], table.loc[reference, m]) for m in METRICS
        }
        for reference in references
    }
    return pd.DataFrame.from_dict(rows, orient="index").rename_axis("comparison")


# weak motions, where sensor noise is as large as the signal, first
PGA_BANDS_G = (0.0, 0.02, 0.1, 0.3, np.inf)


def by_pga(evaluation: Evaluation, metric: str = "J1") -> pd.DataFrame:
    """Controller x PGA band: the mean `metric` (J1 or J2) of the records in the band (mean over stories or
    floors), and per controller the number of records where it is above 1 (worse than no control). Loads
    with no ground acceleration (wind) have no band: one column of every record."""
    values = evaluation.metrics[evaluation.metrics["metric"] == metric]
    per_record = values.groupby(["controller", "record"], sort=False)["value"].mean().unstack("record")
    pga = pd.Series({record: evaluation.pgas[record] / STANDARD_GRAVITY for record in per_record.columns})
    table = pd.DataFrame(index=pd.Index(evaluation.controllers, name="controller"))
    bands = zip(PGA_BANDS_G[:-1], PGA_BANDS_G[1:], strict=True)
    if not pga.any():
        table[f"every record ({pga.size}, no ground shaking)"] = per_record.mean(axis=1)
        bands = iter(())
    for low, high in bands:
        chosen = pga[(pga >= low) & (pga < high)].index
        label = f"PGA ≥ {low:g} g" if np.isinf(high) else f"PGA {low:g}–{high:g} g"
        table[f"{label} ({len(chosen)})"] = per_record[chosen].mean(axis=1) if len(chosen) else np.nan
    table[f"records with {metric} > 1"] = (per_record > 1.0 + 1e-9).sum(axis=1).astype(object)
    return table


def per_record_frame(evaluation: Evaluation) -> pd.DataFrame:
    wide = evaluation.metrics.pivot_table(
        index=["controller", "record", "metric"], columns="index", values="value", sort=False
    )
    wide.columns = [f"{c}" for c in wide.columns]
    return wide.reset_index()
