"""Robustness: every controller on every scenario's plant and every record, through `evaluate`.

Controllers, all run on the scenario's plant (the real building) with the same sensors, noise and
records: the uncontrolled building; LQG designed on the design model, as deployed in practice; LQG +
ground model designed on the design model (it also reads the ground accelerometer and models the
ground motion, as the learned controllers may); LQG re-designed on the true plant (its stiffness,
mass, damping, damage, sensor faults, and the actuator lag and delay as states of its model; for
yielding stories, their initial stiffness) — the oracle, the room a perfect linear model would give;
for semi-active dampers instead passive-off, passive-on and clipped-optimal control designed on the
design model, and clipped-optimal re-designed on the plant as the oracle; when the run was trained
with `plant_randomization`, LQG designed on the centre of its structural and sensor ranges with the
nominal actuator dynamics, the robust classical design an engineer would deploy without knowing the
plant; and the RL policy of a run, if given. J1-J4 are taken against the uncontrolled *plant*.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import pandas as pd

from rlcontroller.config import Experiment, Scenario
from rlcontroller.control.controllers import ClippedOptimal, ConstantCommand, Controller, LQGController
from rlcontroller.control.lqg import design_lqg, design_lqg_ground_model, design_lqg_wind_model
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.evaluation.evaluation import evaluate
from rlcontroller.physics.metrics import METRICS, YIELDING_METRICS
from rlcontroller.physics.motions.excitation import Load
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.variations import centre_of_ranges

NOMINAL_LQG = "LQG (nominal design)"
NOMINAL_GROUND_MODEL = "LQG + ground model (nominal design)"
NOMINAL_WIND_MODEL = "LQG + wind model (nominal design)"  # for an experiment trained under wind
ORACLE_LQG = "LQG (re-designed on the plant)"
NOMINAL_CLIPPED = "clipped-optimal (nominal design)"
ORACLE_CLIPPED = "clipped-optimal (re-designed on the plant)"
CENTRE_LQG = "LQG (centre of the ranges)"


def robustness(
    experiment: Experiment,
    scenarios: list[Scenario],
    motions: list[Load],
    label: str,
    *,
    policy: PolicyController | None = None,
    on_scenario: Callable[[str], None] | None = None,
) -> tuple[pd.DataFrame, float]:
    """J1-J4 in long form (scenario, controller, record, metric, index, value) and the seconds taken;
    `on_scenario(name)` is called as each scenario is done (a progress bar)."""
    start = time.perf_counter()
    model = Plant(experiment.model_copy(update={"plant": None, "plant_randomization": None}))
    dampers = model.semi_active is not None
    designed: list[Controller] = (
        [  # designed once, without knowing the plant
            LQGController(design_lqg(model), model, NOMINAL_LQG),
            LQGController(design_lqg_wind_model(model), model, NOMINAL_WIND_MODEL)
            if model.wind is not None
            else LQGController(design_lqg_ground_model(model), model, NOMINAL_GROUND_MODEL),
        ]
        if not dampers
        else [
            ConstantCommand(-1.0, model.building.n_actuators, "passive-off"),
            ConstantCommand(1.0, model.building.n_actuators, "passive-on"),
            ClippedOptimal(model, NOMINAL_CLIPPED),
        ]
    )
    robust: list[Controller] = []
    if experiment.plant_randomization is not None and not dampers:
        part = centre_of_ranges(experiment.plant_randomization, experiment.plant)
        centre = Plant(experiment.model_copy(update={"plant": part, "plant_randomization": None})).elastic
        robust.append(LQGController(design_lqg(centre), centre, CENTRE_LQG))
    learned: list[Controller] = [policy] if policy is not None else []
    frames = []
    for scenario in scenarios:
        plant = Plant(experiment.model_copy(update={"plant": scenario.plant}))
        if dampers:
            oracle: Controller = ClippedOptimal(plant, ORACLE_CLIPPED)
        else:
            oracle = LQGController(design_lqg(plant.elastic), plant.elastic, ORACLE_LQG)
        controllers = [*designed, oracle, *robust, *learned]
        result = evaluate(plant, motions, controllers, label, include_optimal=False)
        frames.append(result.metrics.assign(scenario=scenario.name))
        if on_scenario is not None:
            on_scenario(scenario.name)
    table = pd.concat(frames, ignore_index=True)
    columns = ["scenario", "controller", "record", "metric", "index", "value"]
    return table[columns], time.perf_counter() - start


def summary(table: pd.DataFrame) -> pd.DataFrame:
    """Scenario x controller: the mean over records, then over stories (J3: actuators)."""
    per_index = table.groupby(["scenario", "controller", "metric", "index"], sort=False)["value"].mean()
    means = per_index.groupby(["scenario", "controller", "metric"], sort=False).mean().unstack("metric")
    return means[[m for m in (*METRICS, *YIELDING_METRICS) if m in means.columns]]


def worst_record_j1(table: pd.DataFrame) -> pd.Series:
    """Scenario x controller: the largest per-record mean J1 (above 1: worse than no control)."""
    j1 = (
        table[table["metric"] == "J1"]
        .groupby(["scenario", "controller", "record"], sort=False)["value"]
        .mean()
    )
    return j1.groupby(["scenario", "controller"], sort=False).max()


def stiffness_factor(scenario: Scenario) -> float | None:
    """The scalar stiffness factor of a scenario that changes only that (1 for nominal), else None."""
    if scenario.plant is None:
        return 1.0
    changed = scenario.plant.model_dump(exclude_defaults=True)
    if set(changed) == {"stiffness"} and not isinstance(scenario.plant.stiffness, list):
        return float(scenario.plant.stiffness)
    return None


def stiffness_curve(summary_table: pd.DataFrame, scenarios: list[Scenario]) -> pd.DataFrame:
    """J1 against the stiffness factor (rows sorted by factor), one column per controller."""
    rows = {}
    for scenario in scenarios:
        factor = stiffness_factor(scenario)
        if factor is not None:
            rows[factor] = summary_table.loc[scenario.name, "J1"]
    return pd.DataFrame(rows).T.sort_index().rename_axis("stiffness factor") if rows else pd.DataFrame()


def mean_over_scenarios(summary_table: pd.DataFrame) -> pd.DataFrame:
    """Controller: the mean of each metric over the scenarios."""
    return summary_table.groupby(level="controller", sort=False).mean()
