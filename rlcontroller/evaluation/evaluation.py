"""Run every controller on every record in the same simulator and collect J1-J4.

The uncontrolled building is simulated as whole records with the precomputed step map; LQG and
the RL policy run through the same environment (same sensors, force clipping, and a noise
realisation seeded by the record's content, so a record gives the same numbers in any folder and
order); the clairvoyant optimal controller is the reference no causal controller can pass.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from rlcontroller.background import in_background
from rlcontroller.config import Experiment, RewardConfig, WindGeneratorConfig, display_path
from rlcontroller.control.controllers import (
    ClippedOptimal,
    ConstantCommand,
    Controller,
    LQGController,
    Uncontrolled,
)
from rlcontroller.control.lqg import design_lqg, design_lqg_ground_model, design_lqg_wind_model
from rlcontroller.control.optimal import optimal_responses
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.physics.metrics import (
    DEVICE_METRICS,
    METRICS,
    WIND_METRICS,
    YIELDING_METRICS,
    device_metrics,
    j_metrics,
    peak,
    residual_drift,
    wind_metrics,
    yielding_metrics,
)
from rlcontroller.physics.motions.excitation import Load, content_seed, with_settling_tail
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.response import Response
from rlcontroller.simulation import kept
from rlcontroller.simulation.rollout import batch_rollout, uncontrolled_responses

OPTIMAL = "optimal (clairvoyant)"
# the mass devices with no command: tuned masses as tuned, drivers as tuned masses
PASSIVE = "passive devices"
# passive command levels of a damper sweep, of its range
DAMPER_LEVELS = (0.0, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0)
LQG_VARIANTS = ("LQG", "LQG + ground", "LQG + ground model", "LQG + wind model")  # names in every table
PREVIEW_SECONDS = (0.0, 0.02, 0.04, 0.1, 0.2, 0.5, 1.0, None)


@dataclass
class Evaluation:
    """J-metrics in long form (controller, record, metric, index, value) and the responses."""

    label: str
    experiment: Experiment
    metrics: pd.DataFrame
    responses: dict[tuple[str, str], Response] = field(repr=False)
    seconds: float = 0.0
    sources: dict[str, str] = field(default_factory=dict)  # controller -> what was evaluated (a model file)
    descriptions: dict[str, str] = field(default_factory=dict)  # record -> event, station ... (may be empty)
    pgas: dict[str, float] = field(default_factory=dict)  # record -> peak ground acceleration (m/s^2)
    # controller -> devices, sensors, states
    costs: dict[str, tuple[int, int, int]] = field(default_factory=dict)

    @property
    def controllers(self) -> list[str]:
        return list(dict.fromkeys(self.metrics["controller"]))

    @property
    def records(self) -> list[str]:
        return list(dict.fromkeys(self.metrics["record"]))

    def summary(self) -> pd.DataFrame:
        """Mean over records, then over stories (actuators for J3), per controller; for yielding
        plants also the ductility, residual drift and hysteretic energy (means per story); with mass
        devices their strokes, dissipated energy and the commanded devices' power (means per device)."""
        per_index = self.metrics.groupby(["controller", "metric", "index"], sort=False)["value"].mean()
        table = per_index.groupby(["controller", "metric"], sort=False).mean().unstack("metric")
        columns = (*METRICS, *YIELDING_METRICS, *WIND_METRICS, *DEVICE_METRICS)
        return table.loc[self.controllers, [m for m in columns if m in table.columns]]


def progress_total(plant: Plant, motions: list) -> int:
    """The motions `evaluate` reports to its `on_motions`: an FE plant's uncontrolled runs, then the
    controlled."""
    return len(motions) * (2 if plant.fe_model is not None else 1)


def evaluate(
    plant: Plant,
    motions: list[Load],
    controllers: list[Controller],
    label: str,
    *,
    include_optimal: bool = True,
    on_motions: Callable[[int], None] | None = None,
    settle: bool = True,
) -> Evaluation:
    """Run the uncontrolled building, every controller and (optionally) the optimal reference;
    `on_motions(count)` is called as each batch of `count` motions is done (a progress bar of
    `progress_total(plant, motions)`: an FE plant's uncontrolled runs count too). A yielding or
    FE plant reports each story's ductility demand (peak drift over `Plant.yield_drift`) and, if `settle`,
    its residual drift after SETTLING_TAIL_S of rest appended to every motion."""
    start = time.perf_counter()
    yielding = plant.yielding
    include_optimal = include_optimal and plant.integrator is None and not plant.has_actuator_dynamics
    # ground only
    include_optimal = include_optimal and all(motion.floor_forces is None for motion in motions)
    settle = settle and (yielding is not None or plant.fe_model is not None)
    yield_drift = plant.yield_drift if settle else None
    simulated = [with_settling_tail(motion) for motion in motions] if settle else motions
    seeds = [content_seed(motion) for motion in motions]
    bare = kept.uncontrolled(plant.bare, simulated, on_motions)  # an FE model's kept between commands
    devices = plant.building.devices
    damping = np.array([device.damping for device in devices])
    stroke_limits = np.array([np.nan if d.stroke_limit is None else d.stroke_limit for d in devices])
    passive = uncontrolled_responses(plant, simulated) if devices else []
    # the optimum on the other core while the controllers run here (`background`): the same numbers
    optimum = in_background(optimal_responses, plant, simulated) if include_optimal else None
    controlled = batch_rollout(plant, simulated, controllers, seeds=seeds, on_motions=on_motions)
    optimal = optimum.result() if optimum is not None else []
    rows: list[dict] = []
    responses: dict[tuple[str, str], Response] = {}
    for number, motion in enumerate(motions):
        results = [("uncontrolled", bare[number])] + ([(PASSIVE, passive[number])] if devices else [])
        results += [
            (controller.name, run[number][0]) for controller, run in zip(controllers, controlled, strict=True)
        ]
        if include_optimal:
            results.append((OPTIMAL, optimal[number]))
        for name, result in results:
            responses[name, motion.name] = result
            metrics = j_metrics(result, bare[number])
            if settle and yielding is not None:
                metrics |= yielding_metrics(result, yield_drift, yielding.collapse_drift)
            elif settle:  # an FE plant: no hysteretic force to integrate
                metrics |= {"ductility": peak(result.drift) / yield_drift} | residual_drift(result)
            if motion.floor_forces is not None:
                metrics |= wind_metrics(result, bare[number])
            if (devices or plant.building.dampers) and name != "uncontrolled":
                metrics |= device_metrics(result, damping=damping, stroke_limits=stroke_limits)
            for metric, values in metrics.items():
                rows.extend(
                    {
                        "controller": name,
                        "record": motion.name,
                        "metric": metric,
                        "index": i + 1,
                        "value": float(v),
                    }
                    for i, v in enumerate(values)
                )
    descriptions = {motion.name: motion.description for motion in motions}
    pgas = {motion.name: motion.pga for motion in motions}
    seconds = time.perf_counter() - start
    costs = {"uncontrolled": (0, 0, 0)}
    costs |= {c.name: controller_costs(c, plant.layout, plant.building.n_actuators) for c in controllers}
    return Evaluation(
        label,
        plant.experiment,
        pd.DataFrame(rows),
        responses,
        seconds,
        descriptions=descriptions,
        pgas=pgas,
        costs=costs,
    )


def compare(
    plant: Plant,
    motions: list[Load],
    label: str,
    *,
    policy: PolicyController | None = None,
    on_motions: Callable[[int], None] | None = None,
    extra: tuple[Controller, ...] = (),
) -> Evaluation:
    """Uncontrolled, the classical controllers (`classical_controllers`) and any `extra` ones (MPC), the
    saved `policy` (if given) and the optimal reference, on every motion."""
    controllers = [*classical_controllers(plant), *extra]
    sources = {}
    if policy is not None:
        controllers.append(policy)
        sources[policy.name] = f"{display_path(Path(policy.source))} ({policy.steps:,} training steps)"
    evaluation = evaluate(plant, motions, controllers, label, on_motions=on_motions)
    evaluation.sources.update(sources)
    return evaluation


def classical_controllers(plant: Plant) -> list[Controller]:
    """The field's answers for the experiment's devices, designed on the design model and run on the
    plant: the three LQGs (accelerations only; + measured ground; + ground model) for actuators and
    active mass drivers, or for an experiment that trains under wind LQG and LQG + wind model;
    passive-off, passive-on and clipped-optimal control for semi-active dampers."""
    design = plant.design
    if design.semi_active is not None:
        count = design.building.n_actuators
        return [
            ConstantCommand(-1.0, count, "passive-off"),
            ConstantCommand(1.0, count, "passive-on"),
            ClippedOptimal(design),
        ]
    if isinstance(plant.experiment.excitation.generator, WindGeneratorConfig):
        designs = {"LQG": design_lqg(design), "LQG + wind model": design_lqg_wind_model(design)}
    else:
        designs = {
            "LQG": design_lqg(design),
            "LQG + ground": design_lqg(design, known_ground=True),
            "LQG + ground model": design_lqg_ground_model(design),
        }
    return [LQGController(lqg, design, name) for name, lqg in designs.items()]


def controller_costs(controller: Controller, layout, n_commands: int) -> tuple[int, int, int]:
    """(J15 devices, J16 sensors, J17 states carried between steps) of a controller of `n_commands` commanded
    devices reading observations laid out as `layout` (`physics.observation.ObservationLayout`): an LQG its
    filter's states (and the last ground reading), clipped-optimal its LQG's; a commanded constant reads
    nothing; a policy or law on the observation carries what the observation keeps beyond this step's readings
    (their history, an estimate, the last actions)."""
    if isinstance(controller, Uncontrolled):
        return 0, 0, 0
    if isinstance(controller, ConstantCommand):
        return n_commands, 0, 0
    if isinstance(controller, LQGController):
        return n_commands, layout.block, int(controller.transition.shape[0])
    if isinstance(controller, ClippedOptimal):
        return n_commands, layout.block, int(controller.design.filter.size) + 1
    return n_commands, layout.block, int(layout.size - layout.block)


def percent_better(candidate: float, reference: float) -> float:
    """How much smaller `candidate` is than `reference`, in percent (positive = better)."""
    return float(100.0 * (1.0 - candidate / reference)) if reference else float("nan")


def mean_metric(evaluation: Evaluation, controller: str, metric: str) -> float:
    frame = evaluation.metrics
    chosen = frame[(frame["controller"] == controller) & (frame["metric"] == metric)]
    return float(np.mean(chosen.groupby("index")["value"].mean()))


def lqg_sweep(
    plant: Plant,
    motions: list[Load],
    label: str,
    multipliers: np.ndarray,
    *,
    known_ground: bool = False,
    on_point: Callable[[], None] | None = None,
) -> pd.DataFrame:
    """LQG's trade-off: mean J1..J4 for the reward's force weights times each multiplier (LQG
    designed on the design model, run on the plant); `on_point()` after each (a progress bar)."""
    experiment, design = plant.experiment, plant.design
    if not any(term.quantity == "force" for term in experiment.reward.terms):
        raise ValueError("the reward has no force term to sweep")
    rows = []
    for multiplier in multipliers:
        reward = scaled_weights(experiment.reward, {"force": multiplier})
        controller = LQGController(design_lqg(design, known_ground=known_ground, reward=reward), design)
        result = evaluate(plant, motions, [controller], label, include_optimal=False)
        summary = result.summary().loc["LQG"]
        rows.append({"force_weight_multiplier": float(multiplier), **{m: float(summary[m]) for m in METRICS}})
        if on_point is not None:
            on_point()
    return pd.DataFrame(rows)


def scaled_weights(reward: RewardConfig, multipliers: dict[str, float]) -> RewardConfig:
    """The reward with each term's weight times its quantity's multiplier (`{"force": 0.1}`; other
    quantities unchanged): a point of a trade-off."""
    terms = [
        term.model_copy(update={"weight": term.weight * multipliers.get(term.quantity, 1.0)})
        for term in reward.terms
    ]
    return reward.model_copy(update={"terms": terms})


def damper_sweep(
    plant: Plant,
    motions: list[Load],
    label: str,
    levels: np.ndarray,
    *,
    multipliers: np.ndarray,
    on_motions: Callable[[int], None] | None = None,
) -> pd.DataFrame:
    """The classical trade-off of semi-active dampers: every damper held at each command `level`
    (a fraction of its range: for an MR damper the voltage over its maximum) and clipped-optimal
    control with the reward's force weights times each multiplier (designed on the design model,
    run on the plant), all in one batched evaluation; mean J1..J4 per point. `on_motions(count)` as
    in `evaluate`."""
    if not any(term.quantity == "force" for term in plant.experiment.reward.terms):
        raise ValueError("the reward has no force term to sweep")
    count = plant.building.n_actuators
    controllers: list[tuple[str, float, Controller]] = [
        ("passive", float(level), ConstantCommand(2.0 * float(level) - 1.0, count, f"passive at {level:g}"))
        for level in levels
    ]
    reward = plant.experiment.reward
    controllers += [
        (
            "clipped-optimal",
            float(m),
            ClippedOptimal(plant.design, f"clipped-optimal x{m:g}", scaled_weights(reward, {"force": m})),
        )
        for m in multipliers
    ]
    chosen = [controller for _, _, controller in controllers]
    evaluation = evaluate(plant, motions, chosen, label, include_optimal=False, on_motions=on_motions)
    summary = evaluation.summary()
    rows = [
        {
            "family": family,
            "parameter": parameter,
            **{m: float(summary.loc[controller.name, m]) for m in METRICS},
        }
        for family, parameter, controller in controllers
    ]
    return pd.DataFrame(rows)


def preview_study(
    plant: Plant,
    motions: list[Load],
    seconds: tuple[float | None, ...] = PREVIEW_SECONDS,
    on_horizon: Callable[[], None] | None = None,
) -> pd.DataFrame:
    """How much knowing the coming ground motion is worth: mean J1..J4 of full-state LQR with the
    optimal feed-forward on the next `s` seconds of ground motion (None: the whole record).

    Preview 0 is full-state LQR without ground knowledge; a causal controller has no preview, so
    the rows bound what better sensing (full state) and prediction of the ground can buy.
    """
    dt = plant.control_dt
    bare = uncontrolled_responses(plant.bare, motions)
    rows = []
    for horizon in seconds:
        steps = None if horizon is None else round(horizon / dt)
        values = {metric: [] for metric in METRICS}
        for optimal, uncontrolled in zip(optimal_responses(plant, motions, preview=steps), bare, strict=True):
            metrics = j_metrics(optimal, uncontrolled)
            for metric in METRICS:
                values[metric].append(metrics[metric])
        rows.append(
            {
                "preview_s": float("inf") if steps is None else steps * dt,
                **{metric: float(np.mean(np.mean(values[metric], axis=0))) for metric in METRICS},
            }
        )
        if on_horizon is not None:
            on_horizon()
    return pd.DataFrame(rows)
